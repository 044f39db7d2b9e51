#pragma once
/// Clocks, absolute-deadline sleeps and real-time scheduling for servo threads (Linux).

#include <cstdint>
#include <string>
#include <string_view>

namespace hapto::rt {

/// CLOCK_MONOTONIC now, in nanoseconds. [servo]
std::uint64_t nowNs() noexcept;

/// Sleeps until the absolute CLOCK_MONOTONIC time `deadlineNs` with clock_nanosleep and
/// TIMER_ABSTIME; when spinNs > 0, sleeps until deadline - spinNs and spins the rest. [servo]
void sleepUntilNs(std::uint64_t deadlineNs, std::uint64_t spinNs) noexcept;

/// Sets the calling thread's timer slack to 1 ns, so absolute-deadline sleeps wake on time
/// (Linux's default slack for normal threads is 50 us). [control]
void tightenTimerSlack() noexcept;

/// Names the calling thread (at most 15 characters are kept), as `top -H`, `gdb` and
/// /proc/PID/task/TID/comm show it: the runtime's threads are hapto-servo, hapto-group,
/// hapto-dynamics, hapto-watchdog and hapto-reopen. [control]
void nameCurrentThread(const char* name) noexcept;

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

/// A request to the kernel's CPU latency QoS that no idle CPU take longer than `us`
/// microseconds to start running again, held while this object lives. Linux's interface
/// (Documentation/power/pm_qos_interface.rst, "From user space"): a process that holds
/// /dev/cpu_dma_latency open has a request registered; writing an s32 sets its value; closing
/// the file removes it. With 0, the cpuidle governor picks only states that wake at once (on
/// a virtual machine's haltpoll driver: POLL, never the halt that exits to the host), as cyclictest
/// does by default. The price: idle CPUs spin instead of sleeping, on every core, while it is held.
/// Move-only. [control]
class WakeLatencyHold {
public:
    /// The kernel's CPU latency request file (PM QoS).
    static constexpr std::string_view kDefaultPath = "/dev/cpu_dma_latency";

    WakeLatencyHold() = default;
    /// Opens `path` and writes `us` (>= 0) as a native s32. On failure nothing is held and
    /// note() says what and why ("/dev/cpu_dma_latency: Permission denied ..."). Never throws
    /// on an I/O error.
    explicit WakeLatencyHold(std::int32_t us, std::string_view path = kDefaultPath);
    ~WakeLatencyHold();
    /// Takes over `other`'s request; `other` then holds none.
    WakeLatencyHold(WakeLatencyHold&& other) noexcept;
    /// Releases this request, then takes over `other`'s.
    WakeLatencyHold& operator=(WakeLatencyHold&& other) noexcept;
    WakeLatencyHold(const WakeLatencyHold&) = delete;
    WakeLatencyHold& operator=(const WakeLatencyHold&) = delete;

    /// The kernel holds the request now. [control]
    bool held() const noexcept { return mFd >= 0; }
    /// The request asked for (us; -1 when none was), held or not. [control]
    std::int32_t us() const noexcept { return mUs; }
    /// Why nothing is held, for people; empty when held (or never asked).
    const std::string& note() const noexcept { return mNote; }

private:
    int mFd = -1;
    std::int32_t mUs = -1;
    std::string mNote;
};

/// True on a servo thread between loop entry and exit: what allocation-counting tests use to
/// tell servo-path allocations from set-up ones. [any thread]
bool inServoLoop() noexcept;
/// Marks the calling thread's servo loop entry (true) and exit (false). [servo]
void setInServoLoop(bool inside) noexcept;

} // namespace hapto::rt
