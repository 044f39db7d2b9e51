#pragma once
/// How a session ends on a signal: during start-up (loading the scene, building the index), at
/// once; after it, SIGINT, SIGTERM, SIGHUP and SIGQUIT ask for an orderly stop (zero force,
/// report), and a second one, or an orderly stop still not done after kOrderlyStopLimitS,
/// forces the zero-force exit.

#include <atomic>
#include <functional>
#include <thread>

namespace hapto::cli {

/// Catches the four stop signals for as long as it lives, on a thread of its own, so a stop
/// is seen even while the control thread is blocked (a terminal paused with Ctrl-S, a slow
/// disk). Construct it first, before any other thread starts: every thread created after it
/// inherits the blocked signal mask.
///
/// It starts in the start-up phase: nothing is open or written yet, so a signal ends the
/// process at once with 128 + the signal (a 10^6-object scene's load or index build is not
/// waited for). endStartUp() ends that phase; call it before the first device, recording,
/// output or server is opened. [control]
class StopSignals {
public:
    /// How long an orderly stop may take before it is forced like a second signal (s): a
    /// stop blocked on a paused terminal, a stuck disk or a device still ends the process.
    static constexpr int kOrderlyStopLimitS = 10;

    StopSignals();
    ~StopSignals();
    StopSignals(const StopSignals&) = delete;
    StopSignals& operator=(const StopSignals&) = delete;

    /// What a second signal does, on the signal thread, before the process exits with
    /// 128 + the signal: it must make the devices safe (Runtime::emergencyStop) and not wait
    /// on the control thread. Without one, the second signal exits at once. [control]
    void onSecondSignal(std::function<void()> action);
    /// Ends the start-up phase: from now on a signal asks for the orderly stop. If a signal is
    /// already ending the process, never returns. [control]
    void endStartUp();
    /// True once a stop signal came. [any thread]
    bool requested() const noexcept { return mCount.load() > 0; }
    /// The first signal's number, 0 before one came. [any thread]
    int signalNumber() const noexcept { return mFirst.load(); }

private:
    void watch();

    enum Phase : int { kStartUp, kSession, kExiting };

    std::atomic<int> mCount{0}, mFirst{0};
    std::atomic<int> mPhase{kStartUp};
    std::atomic<bool> mQuit{false};
    std::function<void()> mSecond; // set before the session starts, read by the signal thread
    std::atomic<bool> mSecondSet{false};
    std::thread mThread;
};

} // namespace hapto::cli
