#pragma once
/// A bounded lock-free single-producer / single-consumer ring of plain values.

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <type_traits>

namespace hapto {

/// A fixed-capacity SPSC queue: one thread pushes (a servo thread), one other thread pops (a
/// control thread). Push and pop never block, lock or allocate; a full ring refuses the push.
/// Invariant: 0 <= head - tail <= capacity, where head counts pushes and tail counts pops;
/// each index is written by one side only and read by the other with acquire/release. Each
/// side caches the other's index on its own cache line, so a push touches shared memory only
/// when the ring looks full.
template <class T> class SpscRing {
    // Plain values whose copy never throws, allocates or locks.
    static_assert(std::is_trivially_copyable_v<T> && std::is_default_constructible_v<T>,
                  "SpscRing holds plain values");

public:
    /// A ring of at least `capacity` (>= 1) slots, rounded up to a power of two. [control]
    explicit SpscRing(std::size_t capacity)
        : mCapacity(std::bit_ceil(capacity < 1 ? std::size_t{1} : capacity)), mMask(mCapacity - 1),
          mSlots(std::make_unique<T[]>(mCapacity)) {}

    SpscRing(const SpscRing&) = delete;
    SpscRing& operator=(const SpscRing&) = delete;

    /// Appends `value` unless the ring is full; never blocks. Producer only. [servo]
    bool tryPush(const T& value) noexcept {
        const std::uint64_t head = mHead.load(std::memory_order_relaxed);
        if (head - mTailCache >= mCapacity) {
            mTailCache = mTail.load(std::memory_order_acquire);
            if (head - mTailCache >= mCapacity) {
                return false;
            }
        }
        mSlots[head & mMask] = value;
        mHead.store(head + 1, std::memory_order_release);
        return true;
    }

    /// Moves up to out.size() values, oldest first, into `out`; returns how many. Consumer
    /// only; never blocks. [any thread]
    std::size_t popInto(std::span<T> out) noexcept {
        const std::uint64_t tail = mTail.load(std::memory_order_relaxed);
        if (mHeadCache - tail < out.size()) {
            mHeadCache = mHead.load(std::memory_order_acquire);
        }
        const std::size_t n =
            static_cast<std::size_t>(std::min<std::uint64_t>(mHeadCache - tail, out.size()));
        for (std::size_t i = 0; i < n; ++i) {
            out[i] = mSlots[(tail + i) & mMask];
        }
        mTail.store(tail + n, std::memory_order_release);
        return n;
    }

    /// Pops one value into `out`; false when empty. Consumer only. [any thread]
    bool tryPop(T& out) noexcept { return popInto(std::span<T>(&out, 1)) == 1; }

    /// Number of slots. [any thread]
    std::size_t capacity() const noexcept { return mCapacity; }
    /// Values waiting, as seen now (exact only when neither side is active). [any thread]
    std::size_t sizeApprox() const noexcept {
        return static_cast<std::size_t>(mHead.load(std::memory_order_acquire) -
                                        mTail.load(std::memory_order_acquire));
    }

private:
    const std::size_t mCapacity;
    const std::size_t mMask;
    std::unique_ptr<T[]> mSlots;
    alignas(64) std::atomic<std::uint64_t> mHead{0}; // written by the producer
    std::uint64_t mTailCache = 0;                    // producer's view of mTail
    alignas(64) std::atomic<std::uint64_t> mTail{0}; // written by the consumer
    std::uint64_t mHeadCache = 0;                    // consumer's view of mHead
};

} // namespace hapto
