#pragma once
/// A clock that moves only when told to: the time source of the runtime's step mode and of a
/// stepped World, so tests and tools drive them tick by tick with the same results every run.

#include <atomic>
#include <cstdint>

namespace hapto {

/// Monotonic-looking nanoseconds set by its owner. The step mode reads it where the threaded
/// runtime reads CLOCK_MONOTONIC: for wake-ups, deadlines, lateness, tick and I/O times,
/// heartbeats, the watchdog and reopen delays. A test device can advance it inside its
/// read() or write() to make that call take time. Reads and writes are relaxed atomics, so
/// a clock may be shared with another thread, but a stepped runtime uses it from one.
class ManualClock {
public:
    /// A clock reading `startNs`. [any thread]
    explicit ManualClock(std::uint64_t startNs = 1'000'000'000) noexcept : mNs(startNs) {}

    /// The time (ns). [any thread]
    std::uint64_t nowNs() const noexcept { return mNs.load(std::memory_order_relaxed); }
    /// Sets the time (ns); the step mode may set it back (see Runtime::stepAll). [any thread]
    void set(std::uint64_t ns) noexcept { mNs.store(ns, std::memory_order_relaxed); }
    /// Moves the time on by `ns`. [any thread]
    void advance(std::uint64_t ns) noexcept { mNs.fetch_add(ns, std::memory_order_relaxed); }

private:
    std::atomic<std::uint64_t> mNs;
};

} // namespace hapto
