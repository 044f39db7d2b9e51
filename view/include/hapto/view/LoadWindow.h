#pragma once
/// A device's load over the last second, from its lifetime histogram: the difference of two
/// copies of the bucket counts taken about a second apart.

#include "hapto/runtime/LoadHistogram.h"

#include <array>
#include <cstdint>
#include <vector>

namespace hapto {

/// The load quantiles of one window, as fractions of the servo period.
struct WindowLoad {
    std::uint64_t ticks = 0; ///< Ticks recorded in the window.
    double p50 = 0.0;        ///< Median load (bucket upper bound, like the report).
    double p999 = 0.0;       ///< 99.9th percentile load.
    double spanS = 0.0;      ///< How long the window is (s); shorter than asked at the start.
};

/// Keeps copies of a histogram's counts, one per sample(), and answers for the span between
/// the newest and the oldest one still within `windowNs`. Runs on the view's own thread
/// (about 30 copies of 11 KiB each for a one-second window at 30 Hz); the servo thread goes
/// on recording meanwhile, never waiting. [view thread]
class LoadWindow {
public:
    /// `periodNs`: the device's servo period; `windowNs`: the span wanted; `capacity`: how
    /// many copies to keep (>= 2; the samples per window plus one). [control]
    LoadWindow(double periodNs, std::uint64_t windowNs, std::size_t capacity);

    /// Takes a copy of `histogram` at time `nowNs` and returns the window ending now.
    /// [view thread]
    WindowLoad sample(const LoadHistogram& histogram, std::uint64_t nowNs);

private:
    struct Copy {
        std::uint64_t timeNs = 0;
        std::array<std::uint64_t, LoadHistogram::kBuckets> counts{};
    };
    double mPeriodNs;
    std::uint64_t mWindowNs;
    std::vector<Copy> mCopies; // a ring
    std::size_t mNext = 0, mHeld = 0;
    std::array<std::uint64_t, LoadHistogram::kBuckets> mDiff{};
};

} // namespace hapto
