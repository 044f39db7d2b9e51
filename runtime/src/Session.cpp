// One session of a Runtime: start, the control loop, stop, report.

#include "hapto/runtime/Session.h"

#include "hapto/devices/TraceRecorder.h"
#include "hapto/runtime/BodyTrace.h"

#include <thread>
#include <utility>

namespace hapto {

std::string_view sessionEndName(SessionEnd end) {
    switch (end) {
    case SessionEnd::Duration:
        return "duration";
    case SessionEnd::Requested:
        return "requested";
    case SessionEnd::Finished:
        return "finished";
    case SessionEnd::NoneRunning:
        return "none running";
    }
    return "?";
}

bool runsOnStepClock(DeviceKind kind) {
    return kind == DeviceKind::Sim || kind == DeviceKind::Replay || kind == DeviceKind::Scripted;
}

Session::Session(Runtime& runtime, SessionOptions options)
    : mRuntime(runtime), mOptions(std::move(options)) {}

Session::~Session() {
    if (mStarted && !mStopped) {
        try {
            stop();
        } catch (...) {
            // A recorder that cannot close: the devices are at zero force already.
        }
    }
}

std::size_t Session::start() {
    mStarted = true;
    if (mOptions.bodyRecorder && !mRuntime.hasDynamics()) {
        mOptions.bodyRecorder->abandon(); // no body to record
        mOptions.bodyRecorder = nullptr;
    }
    mRuntime.setBodyRecorder(mOptions.bodyRecorder);
    const std::size_t opened =
        mOptions.steppedClock ? mRuntime.startStepped(*mOptions.steppedClock) : mRuntime.start();
    if (mOptions.steppedClock) {
        mSteppedT0Ns = mOptions.steppedClock->nowNs();
    }
    mWallT0 = std::chrono::steady_clock::now();
    mNextStep = mWallT0;
    if (opened == 0) {
        for (TraceRecorder* recorder : mOptions.recorders) {
            recorder->abandon(); // nothing recorded: an older trace of that name stays
        }
        mAbandoned = true;
    }
    return opened;
}

double Session::timeS() const {
    if (mOptions.steppedClock) {
        return static_cast<double>(mOptions.steppedClock->nowNs() - mSteppedT0Ns) / 1e9;
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - mWallT0).count();
}

bool Session::stopRequested() const {
    return mOptions.stopRequested && mOptions.stopRequested();
}

// Waits for the next control period (wall clock), or runs the servo ticks due in it (step
// mode); returns the session time then.
double Session::advance() {
    if (ManualClock* clock = mOptions.steppedClock) {
        mRuntime.runUntil(clock->nowNs() + mOptions.controlPeriodNs);
    } else {
        mNextStep += std::chrono::nanoseconds(mOptions.controlPeriodNs);
        std::this_thread::sleep_until(mNextStep);
    }
    return timeS();
}

SessionEnd Session::run(const ControlStep& step) {
    for (;;) {
        if (stopRequested()) {
            return SessionEnd::Requested;
        }
        if (!mRuntime.anyRunning()) {
            return SessionEnd::NoneRunning;
        }
        const double t = advance();
        if (mOptions.durationS > 0 && t >= mOptions.durationS) {
            return SessionEnd::Duration;
        }
        mRuntime.maintain();
        const bool goOn = !step || step(t);
        for (TraceRecorder* recorder : mOptions.recorders) {
            recorder->drain();
        }
        if (mOptions.bodyRecorder) {
            mOptions.bodyRecorder->drain();
        }
        if (!goOn) {
            return SessionEnd::Finished;
        }
    }
}

const RunReport& Session::stop() {
    if (mStopped) {
        return mReport;
    }
    mStopped = true;
    mRuntime.stop(); // zero force on every device before anything else
    if (!mAbandoned) {
        for (TraceRecorder* recorder : mOptions.recorders) {
            recorder->close();
        }
    }
    if (mOptions.bodyRecorder) {
        mOptions.bodyRecorder->close(); // the dynamics ran from start() to stop()
    }
    mReport = mRuntime.report();
    return mReport;
}

} // namespace hapto
