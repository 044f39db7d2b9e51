// StopSignals: the four stop signals are blocked in every thread and taken with sigtimedwait
// on one thread of their own. A signal sent to the process while some thread (a TBB worker
// made before) still has them unblocked runs the fallback handler, which only counts it; the
// watcher picks the count up on its next pass. During start-up the watcher ends the process
// itself; the phase is one atomic the watcher and endStartUp() race for with a compare-exchange,
// so either the process exits before anything is opened, or the signal is an orderly stop.

#include "StopSignals.h"

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <pthread.h>
#include <unistd.h>

namespace hapto::cli {
namespace {

constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};

std::atomic<int> gHandled{0};      // signals taken by the fallback handler
std::atomic<int> gHandledFirst{0}; // the first of them

extern "C" void countStopSignal(int sig) {
    int none = 0;
    gHandledFirst.compare_exchange_strong(none, sig);
    gHandled.fetch_add(1);
}

sigset_t stopSet() {
    sigset_t set;
    sigemptyset(&set);
    for (int s : kStopSignals) {
        sigaddset(&set, s);
    }
    return set;
}

} // namespace

StopSignals::StopSignals() {
    gHandled.store(0);
    gHandledFirst.store(0);
    struct sigaction sa {};
    sa.sa_handler = countStopSignal;
    sigemptyset(&sa.sa_mask);
    for (int s : kStopSignals) {
        sigaction(s, &sa, nullptr);
    }
    const sigset_t set = stopSet();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    mThread = std::thread([this] { watch(); });
}

StopSignals::~StopSignals() {
    mQuit.store(true);
    mThread.join();
    const sigset_t set = stopSet();
    pthread_sigmask(SIG_UNBLOCK, &set, nullptr);
    for (int s : kStopSignals) {
        std::signal(s, SIG_DFL);
    }
}

void StopSignals::onSecondSignal(std::function<void()> action) {
    mSecond = std::move(action);
    mSecondSet.store(true);
}

void StopSignals::endStartUp() {
    int phase = kStartUp;
    if (!mPhase.compare_exchange_strong(phase, kSession) && phase == kExiting) {
        for (;;) { // the signal thread is ending the process
            std::this_thread::sleep_for(std::chrono::seconds(1));
        }
    }
}

void StopSignals::watch() {
    const sigset_t set = stopSet();
    const timespec pass{0, 20'000'000}; // 20 ms: how soon a quit or a handled signal is seen
    int seenHandled = 0;
    std::chrono::steady_clock::time_point forceAt{};
    while (!mQuit.load()) {
        int sig = sigtimedwait(&set, nullptr, &pass);
        const int handled = gHandled.load();
        if (sig <= 0 && handled > seenHandled) {
            sig = gHandledFirst.load();
            seenHandled = handled;
        }
        const bool overdue = mCount.load() > 0 && std::chrono::steady_clock::now() >= forceAt;
        if (sig <= 0 && !overdue) {
            continue;
        }
        int none = 0;
        mFirst.compare_exchange_strong(none, sig > 0 ? sig : SIGTERM);
        int phase = kStartUp;
        if (mPhase.compare_exchange_strong(phase, kExiting)) {
            std::_Exit(128 + mFirst.load()); // start-up: nothing opened, nothing to finish
        }
        if (overdue || mCount.fetch_add(1) >= 1) {
            // The second, or the first not done in time: make the devices safe without the
            // control thread, and leave.
            if (mSecondSet.load()) {
                mSecond();
            }
            std::_Exit(128 + (overdue ? mFirst.load() : sig));
        }
        forceAt = std::chrono::steady_clock::now() + std::chrono::seconds(kOrderlyStopLimitS);
    }
}

} // namespace hapto::cli
