#pragma once
/// What a servo thread measures about itself, written by that thread only and read live by
/// the control thread.

#include "hapto/runtime/LoadHistogram.h"

#include <atomic>
#include <cstdint>

namespace hapto {

/// Why a servo thread stopped driving its device.
enum class FaultKind : std::uint8_t {
    None,        ///< Running, or stopped cleanly.
    OpenFailed,  ///< open() failed; the thread never started.
    ReadFailed,  ///< read() returned an error status (see faultStatus).
    WriteFailed, ///< write() returned an error status.
    NonFinite,   ///< The device reported a non-finite position or velocity.
    Watchdog,    ///< No tick completed within the stall timeout.
};

/// A short name for a fault ("read-failed", ...). [any thread]
const char* faultName(FaultKind kind) noexcept;

/// Per-device counters and histograms: single writer (the servo thread), lock-free readers.
struct alignas(64) DeviceMetrics {
    LoadHistogram tickNs;     ///< Wake-up to force written (ns): the haptic load numerator.
    LoadHistogram latenessNs; ///< Wake-up minus deadline (ns).
    LoadHistogram ioNs;       ///< Time inside device read() plus write() (ns).

    std::atomic<std::uint64_t> ticks{0}; ///< Ticks completed.
    std::atomic<std::uint64_t> missedDeadlines{
        0};                                    ///< Ticks whose force came after the next deadline.
    std::atomic<std::uint64_t> lateWakeups{0}; ///< Wake-ups later than the late threshold.
    std::atomic<std::uint64_t> zeroedForMisses{
        0};                                       ///< Ticks commanded zero after K misses in a row.
    std::atomic<std::uint64_t> locateStepsSum{0}; ///< Cursor steps, both cursors, summed.
    std::atomic<std::uint64_t> candidatesSum{
        0};                                     ///< Candidate slots handed to the renderer, summed.
    std::atomic<std::uint64_t> outsideTicks{0}; ///< Ticks with the pointer outside the bounds.
    std::atomic<std::uint64_t> contactTicks{0}; ///< Ticks in contact with some object.
    std::atomic<std::uint64_t> snapshotsSeen{0};   ///< Distinct world versions picked up.
    std::atomic<std::uint64_t> hookNonFinite{0};   ///< Ticks whose hook force was not finite.
    std::atomic<std::uint64_t> heartbeatNs{0};     ///< Monotonic time of the last completed tick.
    std::atomic<FaultKind> fault{FaultKind::None}; ///< Set once when the thread faults.
    std::atomic<std::uint8_t> faultStatus{0};      ///< The DeviceStatus behind a read/write fault.
    std::atomic<std::uint64_t> faultNs{0};         ///< Monotonic time of the fault (ns).
    std::atomic<bool> running{false};              ///< The servo loop is live.
    std::atomic<int> threadId{0};      ///< Linux thread id of the servo thread (for chrt, taskset).
    std::atomic<bool> realtime{false}; ///< The servo thread was granted SCHED_FIFO.
    std::atomic<double> forceN[3]{};   ///< Last force sent, world frame (N), for the live view.
    std::atomic<double> positionM[3]{}; ///< Last device point, world frame (m), for the live view.
    /// The device point's cursor leaf and the snapshot it is a leaf of, in one word so a reader
    /// never pairs a leaf with the wrong index: (version & 0xFFFFFFFF) << 32 | leaf (kNoLeaf
    /// outside the bounds). For the live view. ~0 before the first tick.
    std::atomic<std::uint64_t> leafAtVersion{~std::uint64_t{0}};

    /// Adds to a counter; the servo thread is the only writer. [servo]
    static void bump(std::atomic<std::uint64_t>& c, std::uint64_t by = 1) noexcept {
        c.store(c.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
    }
};

} // namespace hapto
