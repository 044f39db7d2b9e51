#pragma once
/// A lock-free single-writer mailbox holding the newest value of a small trivially copyable T:
/// how a servo thread exchanges samples and forces with a device's I/O thread, and publishes
/// its contacts to the control thread.
///
/// Design note (a seqlock): the writer bumps the sequence to odd, stores the payload, bumps it
/// to even; a reader reads the sequence, the payload, the sequence again, and keeps the payload
/// only when both reads are the same even number. Every payload word is a std::atomic, so there
/// is no data race in the C++ sense, and no fences (which TSan cannot model): each word is
/// stored with release after the odd sequence store and loaded with acquire, so a reader that
/// sees any word of a newer write also sees the sequence move. On x86-64 these are plain moves.
/// The writer never waits; a reader retries a bounded number of times and then reports "no
/// value", which callers treat as a stale sample. No allocation, lock or syscall either side.

#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace hapto {

/// The newest T, published by one thread and read by any. [servo]-safe on both sides.
template <class T> class Mailbox {
    static_assert(std::is_trivially_copyable_v<T>);
    static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;

public:
    /// Stores a new value (one writer at a time). [servo]
    void publish(const T& value) noexcept {
        std::uint64_t words[kWords]{};
        std::memcpy(words, &value, sizeof(T));
        const std::uint64_t s = mSeq.load(std::memory_order_relaxed);
        mSeq.store(s + 1, std::memory_order_relaxed);
        for (std::size_t i = 0; i < kWords; ++i) {
            mWords[i].store(words[i], std::memory_order_release);
        }
        mSeq.store(s + 2, std::memory_order_release);
    }

    /// Copies the newest value and how many values were published up to it; false when
    /// nothing was published yet or every retry raced a write (`out` untouched). [servo]
    bool read(T& out, std::uint64_t& writes) const noexcept {
        for (int attempt = 0; attempt < 64; ++attempt) {
            const std::uint64_t s0 = mSeq.load(std::memory_order_acquire);
            if (s0 == 0) {
                return false;
            }
            if (s0 & 1u) {
                continue;
            }
            std::uint64_t words[kWords];
            for (std::size_t i = 0; i < kWords; ++i) {
                words[i] = mWords[i].load(std::memory_order_acquire);
            }
            if (mSeq.load(std::memory_order_relaxed) == s0) {
                std::memcpy(&out, words, sizeof(T));
                writes = s0 / 2;
                return true;
            }
        }
        return false;
    }
    /// Copies the newest value; false as above. [servo]
    bool read(T& out) const noexcept {
        std::uint64_t writes = 0;
        return read(out, writes);
    }

    /// Forgets every value. Only while nobody reads or writes. [control]
    void reset() noexcept {
        for (auto& w : mWords) {
            w.store(0, std::memory_order_relaxed);
        }
        mSeq.store(0, std::memory_order_release);
    }

private:
    alignas(64) std::atomic<std::uint64_t> mSeq{0};
    std::atomic<std::uint64_t> mWords[kWords]{};
};

} // namespace hapto
