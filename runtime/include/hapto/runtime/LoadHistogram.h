#pragma once
/// A lock-free log-linear histogram of nanosecond values: one writer (a servo thread), any
/// number of readers (the control thread's live view and final report).

#include <array>
#include <atomic>
#include <cstdint>

namespace hapto {

/// Quantiles and moments of a histogram, in the recorded unit (ns).
struct HistogramSummary {
    std::uint64_t count = 0; ///< Values recorded.
    double mean = 0.0;       ///< Exact mean.
    double p50 = 0.0;        ///< Median (bucket upper bound, <= 3.2 % above the true value).
    double p99 = 0.0;        ///< 99th percentile (same precision).
    double p999 = 0.0;       ///< 99.9th percentile (same precision).
    double max = 0.0;        ///< Exact maximum.
};

/// Values 0..2^47 ns in buckets 1/32 of a power of two wide (3.2 % relative precision).
/// record() is wait-free for its single writer: relaxed loads and stores, no read-modify-write.
/// Readers see each counter atomically; a summary taken while recording is a consistent
/// snapshot to within the ticks recorded during the read.
class LoadHistogram {
public:
    static constexpr int kSubBits = 5;                      ///< 32 sub-buckets per octave.
    static constexpr int kSub = 1 << kSubBits;              ///< Sub-buckets per octave.
    static constexpr int kOctaves = 48 - kSubBits;          ///< Octaves above the linear range.
    static constexpr int kBuckets = kSub + kOctaves * kSub; ///< Total buckets (1408).

    /// Adds one value (ns). [servo]
    void record(std::uint64_t value) noexcept {
        auto bump = [](std::atomic<std::uint64_t>& a, std::uint64_t by) {
            a.store(a.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
        };
        bump(mBuckets[bucketOf(value)], 1);
        bump(mSum, value);
        if (value > mMax.load(std::memory_order_relaxed)) {
            mMax.store(value, std::memory_order_relaxed);
        }
        mCount.store(mCount.load(std::memory_order_relaxed) + 1, std::memory_order_release);
    }
    /// Counts, mean and quantiles. [any thread]
    HistogramSummary summary() const noexcept;
    /// Values recorded so far. [any thread]
    std::uint64_t count() const noexcept { return mCount.load(std::memory_order_acquire); }
    /// Copies every bucket's count into `out` (for windowed quantiles: the difference of two
    /// copies is the histogram of the values recorded between them). [any thread]
    void counts(std::array<std::uint64_t, kBuckets>& out) const noexcept {
        for (int i = 0; i < kBuckets; ++i) {
            out[static_cast<std::size_t>(i)] =
                mBuckets[static_cast<std::size_t>(i)].load(std::memory_order_relaxed);
        }
    }

    /// The bucket a value falls in. [any thread]
    static int bucketOf(std::uint64_t v) noexcept {
        if (v < kSub) {
            return static_cast<int>(v);
        }
        const int e = 63 - __builtin_clzll(v); // >= kSubBits
        if (e >= 48) {
            return kBuckets - 1;
        }
        const int sub = static_cast<int>((v >> (e - kSubBits)) & (kSub - 1));
        return kSub + (e - kSubBits) * kSub + sub;
    }
    /// The largest value that falls in bucket i. [any thread]
    static std::uint64_t bucketUpper(int i) noexcept {
        if (i < kSub) {
            return static_cast<std::uint64_t>(i);
        }
        const int e = (i - kSub) / kSub + kSubBits;
        const std::uint64_t sub = static_cast<std::uint64_t>((i - kSub) % kSub);
        return (((kSub + sub + 1) << (e - kSubBits))) - 1;
    }

private:
    std::array<std::atomic<std::uint64_t>, kBuckets> mBuckets{};
    std::atomic<std::uint64_t> mCount{0};
    std::atomic<std::uint64_t> mSum{0};
    std::atomic<std::uint64_t> mMax{0};
    static_assert(std::atomic<std::uint64_t>::is_always_lock_free);
};

} // namespace hapto
