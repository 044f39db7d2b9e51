#pragma once
/// Clocks, absolute-deadline sleeps and real-time scheduling for servo threads (Linux).

#include <cstdint>
#include <string>

namespace hapto::rt {

/// CLOCK_MONOTONIC now, in nanoseconds. [servo]
std::uint64_t nowNs() noexcept;

/// Sleeps until the absolute CLOCK_MONOTONIC time `deadlineNs` with clock_nanosleep and
/// TIMER_ABSTIME; when spinNs > 0, sleeps until deadline - spinNs and spins the rest. [servo]
void sleepUntilNs(std::uint64_t deadlineNs, std::uint64_t spinNs) noexcept;

/// Sets the calling thread's timer slack to 1 ns, so absolute-deadline sleeps wake on time
/// (Linux's default slack for normal threads is 50 us). [control]
void tightenTimerSlack() noexcept;

/// What the current thread got when it asked for real-time scheduling.
struct RealtimeGrant {
    bool fifo = false;   ///< SCHED_FIFO granted.
    bool pinned = false; ///< CPU affinity set.
    std::string note;    ///< Why not, for people (empty when both were granted).
};

/// Tightens the timer slack, asks for SCHED_FIFO at `priority` and pins the calling thread to
/// `cpu` (-1: no pinning).
/// Never fails: returns what was granted. Call at thread start, before the loop. [control]
RealtimeGrant makeCurrentThreadRealtime(int priority, int cpu);

/// True on a servo thread between loop entry and exit: what allocation-counting tests use to
/// tell servo-path allocations from set-up ones. [any thread]
bool inServoLoop() noexcept;
/// Marks the calling thread's servo loop entry (true) and exit (false). [servo]
void setInServoLoop(bool inside) noexcept;

} // namespace hapto::rt
