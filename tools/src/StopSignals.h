#pragma once
/// How a session ends on a signal: SIGINT, SIGTERM, SIGHUP and SIGQUIT ask for an orderly stop
/// (zero force, report); a second one forces the zero-force exit at once.

#include <atomic>
#include <functional>
#include <thread>

namespace hapto::cli {

/// Catches the four stop signals for as long as it lives, on a thread of its own, so a stop
/// is seen even while the control thread is blocked (a terminal paused with Ctrl-S, a slow
/// disk). Construct it first, before any other thread starts: every thread created after it
/// inherits the blocked signal mask. [control]
class StopSignals {
public:
    StopSignals();
    ~StopSignals();
    StopSignals(const StopSignals&) = delete;
    StopSignals& operator=(const StopSignals&) = delete;

    /// What a second signal does, on the signal thread, before the process exits with
    /// 128 + the signal: it must make the devices safe (Runtime::emergencyStop) and not wait
    /// on the control thread. Without one, the second signal exits at once. [control]
    void onSecondSignal(std::function<void()> action);
    /// True once a stop signal came. [any thread]
    bool requested() const noexcept { return mCount.load() > 0; }
    /// The first signal's number, 0 before one came. [any thread]
    int signalNumber() const noexcept { return mFirst.load(); }

private:
    void watch();

    std::atomic<int> mCount{0}, mFirst{0};
    std::atomic<bool> mQuit{false};
    std::function<void()> mSecond; // set before the session starts, read by the signal thread
    std::atomic<bool> mSecondSet{false};
    std::thread mThread;
};

} // namespace hapto::cli
