// Supervision: the watchdog, closing a faulted device, reopening it. Design note: it runs on
// the runtime's own supervisor thread (SCHED_FIFO one above the servo threads when real-time):
// every few milliseconds a pass checks each servo's heartbeat (the watchdog) and hands a
// device whose servo ended on a fault to a worker thread, which closes it, reopens it every
// reopenAfterNs and starts its next servo thread. No step of that waits on the control
// thread, a terminal, a disk or another device's open(). In step mode the same pass
// (superviseChannel) runs on the caller's thread at the caller's times, and the close and the
// opens run inline: closed in the pass that finds the fault, opened in the first pass at or
// after each reopen time. The same pass watches the dynamics thread (superviseDynamics): a
// published body state older than its bound freezes the bodies where they are, at zero
// velocity, without waiting on that thread (DynamicsChannel.h's design note).

#include "Channel.h"
#include "DynamicsChannel.h"

#include <algorithm>
#include <cstdio>
#include <pthread.h>
#include <sched.h>

namespace hapto {

bool Runtime::waitUnlessStopping(std::uint64_t ns) {
    std::unique_lock lock(mWakeMutex);
    return !mWake.wait_for(lock, std::chrono::nanoseconds(ns),
                           [this] { return mStopping.load(std::memory_order_acquire); });
}

void Runtime::superviseMain() {
    // Above the servo threads, so a stalled or starved core never keeps the watchdog from
    // running (it sleeps between passes and its pass is a few atomic loads).
    rt::nameCurrentThread("hapto-watchdog");
    if (mOptions.realtime) {
        (void)rt::makeCurrentThreadRealtime(std::min(99, mOptions.fifoPriority + 1), -1);
    }
    const std::uint64_t passNs =
        std::clamp<std::uint64_t>(mOptions.stallTimeoutNs / 5, 1'000'000, 10'000'000);
    while (waitUnlessStopping(passNs)) {
        const std::uint64_t t = rt::nowNs();
        for (auto& chp : mChannels) {
            superviseChannel(*chp, t);
        }
        superviseDynamics(t);
    }
}

void Runtime::supervise(std::uint64_t nowNs) {
    requireStepped("supervise");
    for (auto& chp : mChannels) {
        mClock->set(nowNs);
        superviseChannel(*chp, nowNs);
    }
    mClock->set(nowNs); // an open or close that took time held up no other device
    superviseDynamics(nowNs);
}

void Runtime::superviseDynamics(std::uint64_t nowNs) noexcept {
    if (!mDynamics) {
        return;
    }
    DynamicsChannel& dc = *mDynamics;
    DynamicsMetrics& m = dc.metrics;
    const auto stale = [&] {
        const std::uint64_t state = m.stateNs.load(std::memory_order_relaxed);
        return nowNs > state && nowNs - state > dc.stallBoundNs;
    };
    if (!m.running.load(std::memory_order_acquire) ||
        m.fault.load(std::memory_order_relaxed) != FaultKind::None || !stale()) {
        return;
    }
    int expected = DynamicsMetrics::kFree;
    if (!m.publisher.compare_exchange_strong(expected, DynamicsMetrics::kFrozen,
                                             std::memory_order_acquire)) {
        return; // it is publishing right now, so not stalled: look again next pass
    }
    if (!stale()) { // it published between the first look and the token
        m.publisher.store(DynamicsMetrics::kFree, std::memory_order_release);
        return;
    }
    // The token is ours for good: the table's one writer from now on is this pass, once.
    std::uint64_t step = 0;
    for (std::size_t i = 0; i < dc.poses.size(); ++i) {
        BodyPose p = dc.poses.read(i);
        p.velocity = Vec3(0.0);
        p.angularVelocity = Vec3(0.0); // a servo extrapolates nothing: the body stays put
        dc.poses.publish(i, p);
        step = p.step;
    }
    m.frozenAtStep.store(step, std::memory_order_relaxed);
    m.faultNs.store(nowNs, std::memory_order_relaxed);
    m.fault.store(FaultKind::Watchdog, std::memory_order_release);
}

void Runtime::superviseChannel(Channel& ch, std::uint64_t nowNs) {
    ChannelRecord& c = ch.record;
    if (!c.opened || c.gaveUp.load(std::memory_order_acquire) ||
        mStopping.load(std::memory_order_acquire)) {
        return;
    }
    if (c.recovering.load(std::memory_order_acquire)) {
        if (mClock) {
            reopenStepped(ch, nowNs);
        }
        return; // threaded: the worker has it
    }
    DeviceMetrics& m = ch.metrics;
    if (m.running.load(std::memory_order_acquire)) {
        const std::uint64_t beat = m.heartbeatNs.load(std::memory_order_relaxed);
        FaultKind none = FaultKind::None;
        if (nowNs > beat && nowNs - beat > mOptions.stallTimeoutNs &&
            m.fault.compare_exchange_strong(none, FaultKind::Watchdog)) {
            // The servo is stuck (in the device, or the host stopped it): when it returns it
            // writes zero and ends, and the fault is recovered like any.
            m.faultNs.store(beat);
            ch.servo.stop.store(true, std::memory_order_release);
        }
        return;
    }
    if (m.fault.load(std::memory_order_acquire) == FaultKind::None) {
        return; // between a reopen and its servo's start
    }
    if (mClock) {
        closeFaulted(ch);
        if (mOptions.reopenAfterNs == 0) {
            c.gaveUp.store(true, std::memory_order_release);
            return;
        }
        c.nextReopenNs = nowNs + mOptions.reopenAfterNs;
        c.recovering.store(true, std::memory_order_release);
        return;
    }
    if (c.worker.joinable()) {
        c.worker.join(); // the previous recovery, finished
    }
    c.recovering.store(true, std::memory_order_release);
    c.worker = std::thread([this, &ch] { recoverMain(ch); });
}

namespace {

// Servo and supervisor threads are SCHED_FIFO; a recovery worker (close, open, homing) is not.
void becomeNormalThread() {
    sched_param param{};
    (void)pthread_setschedparam(pthread_self(), SCHED_OTHER, &param);
}

} // namespace

void Runtime::closeFaulted(Channel& ch) {
    ChannelRecord& c = ch.record;
    if (!c.closed.exchange(true)) {
        c.rd.device->close();
    }
    const std::uint64_t t = now();
    std::lock_guard lock(c.mutex);
    const std::uint64_t at = ch.metrics.faultNs.load();
    c.downSinceNs = at != 0 && at <= t ? at : t; // down since the fault itself
    ++c.faults;
    c.lastFault = faultText(ch);
    const std::string detail = c.rd.device->errorMessage();
    addEvent(ch, t, c.lastFault + (detail.empty() ? "" : " (" + detail + ")") + "; force zeroed");
    c.down.store(true, std::memory_order_release);
}

std::string Runtime::faultText(const Channel& ch) const {
    const FaultKind f = ch.metrics.fault.load(std::memory_order_acquire);
    const std::string status =
        f == FaultKind::Watchdog
            ? "no tick for " + std::to_string(mOptions.stallTimeoutNs / 1'000'000) + " ms"
            : std::string(statusName(static_cast<DeviceStatus>(ch.metrics.faultStatus.load())));
    return std::string(faultName(f)) + ": " + status;
}

bool Runtime::openAgain(Channel& ch, std::uint64_t& backNs) {
    ChannelRecord& c = ch.record;
    const DeviceStatus st = c.rd.device->open();
    backNs = now(); // open() may take long (set-up, homing)
    if (st == DeviceStatus::Ok) {
        c.closed.store(false);
        return true;
    }
    const std::string why = std::string(statusName(st)) + ": " + c.rd.device->errorMessage();
    std::lock_guard lock(c.mutex);
    if (why != c.lastReopenError) {
        addEvent(ch, backNs,
                 "reopen failed, " + why + "; trying every " +
                     std::to_string(mOptions.reopenAfterNs / 1'000'000) + " ms");
        c.lastReopenError = why;
    }
    return false;
}

void Runtime::markReopened(Channel& ch, std::uint64_t backNs) {
    ChannelRecord& c = ch.record;
    std::lock_guard lock(c.mutex);
    c.lastReopenError.clear();
    ++c.reopens;
    c.downNs += backNs - c.downSinceNs;
    addEvent(ch, backNs, "reopened; driving again from zero force");
    ch.metrics.fault.store(FaultKind::None);
    ch.metrics.faultStatus.store(0);
    ch.metrics.faultNs.store(0);
    c.down.store(false, std::memory_order_release);
}

void Runtime::recoverMain(Channel& ch) {
    rt::nameCurrentThread("hapto-reopen");
    becomeNormalThread();
    ChannelRecord& c = ch.record;
    if (c.thread.joinable()) {
        c.thread.join(); // it left its loop after commanding zero force
    }
    closeFaulted(ch);
    if (mOptions.reopenAfterNs == 0) {
        c.gaveUp.store(true, std::memory_order_release);
        c.recovering.store(false, std::memory_order_release);
        return;
    }
    while (waitUnlessStopping(mOptions.reopenAfterNs)) {
        std::uint64_t back = 0;
        if (!openAgain(ch, back)) {
            continue;
        }
        std::lock_guard wake(mWakeMutex); // stop() cannot begin between this check and start
        if (mStopping.load(std::memory_order_acquire)) {
            break; // opened while stopping: close below
        }
        markReopened(ch, back);
        restartServo(ch); // its own thread, or its group's
        c.recovering.store(false, std::memory_order_release);
        return;
    }
    if (!c.closed.exchange(true)) {
        c.rd.device->close(); // stopping: a device opened meanwhile is closed again
    }
    c.recovering.store(false, std::memory_order_release);
}

void Runtime::reopenStepped(Channel& ch, std::uint64_t nowNs) {
    ChannelRecord& c = ch.record;
    if (nowNs < c.nextReopenNs) {
        return;
    }
    std::uint64_t back = 0;
    if (!openAgain(ch, back)) {
        c.nextReopenNs = back + mOptions.reopenAfterNs;
        return;
    }
    markReopened(ch, back);
    startServo(ch, back);
    c.recovering.store(false, std::memory_order_release);
}

void Runtime::addEvent(Channel& ch, std::uint64_t nowNs, const std::string& what) {
    ChannelRecord& c = ch.record;
    if (c.events.size() >= kMaxEvents) {
        ++c.eventsDropped;
        return;
    }
    char at[32];
    std::snprintf(at, sizeof at, "%.3f s: ", static_cast<double>(nowNs - mStartNs) * 1e-9);
    c.events.push_back(at + what);
}

} // namespace hapto
