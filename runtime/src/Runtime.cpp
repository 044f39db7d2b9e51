// The servo threads. Design note: each device owns one Channel, a cache-line-aligned block
// holding everything its thread touches per tick (cursors, proxy renderer, force safety,
// metrics, its snapshot claim). Threads share only the read-only World snapshots. Everything
// is sized before the loop starts; inside the loop a tick is: sleep to an absolute deadline,
// read, claim the snapshot, locate both cursors, render, filter, write, record. Faults become
// zero force and a recorded FaultKind, never an exception.
//
// Supervision runs on the runtime's own supervisor thread (SCHED_FIFO one above the servo
// threads when real-time): every few milliseconds it checks each servo thread's heartbeat
// (the watchdog) and hands a device whose thread ended on a fault to a worker thread, which
// closes it, reopens it every reopenAfterNs and starts its next servo thread. No step of
// that waits on the control thread, a terminal, a disk or another device's open().

#include "hapto/runtime/Runtime.h"

#include "hapto/devices/TraceRecorder.h"
#include "hapto/index/Cursor.h"
#include "hapto/runtime/Realtime.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <pthread.h>
#include <sched.h>
#include <stdexcept>
#include <unistd.h>

namespace hapto {

const char* faultName(FaultKind kind) noexcept {
    switch (kind) {
    case FaultKind::None:
        return "none";
    case FaultKind::OpenFailed:
        return "open-failed";
    case FaultKind::ReadFailed:
        return "read-failed";
    case FaultKind::WriteFailed:
        return "write-failed";
    case FaultKind::NonFinite:
        return "non-finite";
    case FaultKind::Watchdog:
        return "watchdog";
    }
    return "unknown";
}

namespace {

using Triple = std::array<double, 3>;
Triple triple(const Vec3& v) {
    return {v.x, v.y, v.z};
}
Vec3 vec(const Triple& t) {
    return {t[0], t[1], t[2]};
}

// ContactReport as plain words for the mailbox (GLM vectors are not trivially copyable).
struct ContactWire {
    std::uint64_t tick;
    Triple devicePoint, proxy, force;
    std::array<ObjectId, 3> objects;
    std::array<Triple, 3> normals;
    std::uint32_t contactCount;
};

} // namespace

struct alignas(64) Runtime::Channel {
    RuntimeDevice rd;
    DeviceMetrics metrics;
    Cursor deviceCursor; // the device point's leaf
    Cursor proxyCursor;  // the proxy's leaf: they differ while pressing into a surface
    GodObjectRenderer renderer;
    ForceSafety safety;
    SnapshotReader* reader = nullptr;
    Mailbox<ContactWire> contacts; // servo -> control, every tick
    Mailbox<Triple> externalForce; // control -> servo, world frame (N)
    std::uint64_t periodNs = 1'000'000;
    int cpu = -1;
    std::atomic<bool> stop{false};
    std::thread thread;
    bool opened = false; // open() succeeded at start(); control thread only
    std::string openError;
    rt::RealtimeGrant grant;

    // Fault recovery. The supervisor hands a faulted device to a worker thread (recovering),
    // which closes it (down), reopens it and starts its next servo thread; with reopening
    // off it stays closed (gaveUp). `closed` makes sure one thread, and one only, closes it.
    std::atomic<bool> recovering{false}, down{false}, gaveUp{false}, closed{false};
    std::thread worker;
    mutable std::mutex cold;       // guards the record below: workers write it, report() reads
    std::uint64_t downSinceNs = 0; // when the fault happened
    std::uint64_t faults = 0, reopens = 0, downNs = 0;
    std::string lastFault;       // what the last fault was, for the report
    std::string lastReopenError; // so a device that stays away is logged once, not per try
    std::vector<std::string> events;
    std::uint64_t eventsDropped = 0;

    Channel(RuntimeDevice d, const RuntimeOptions& o, double maxForceN)
        : rd(std::move(d)), renderer(o.renderer), safety(safetyFor(maxForceN)) {}

    static SafetyConfig safetyFor(double maxForceN) {
        SafetyConfig c;
        if (maxForceN > 0) {
            c.maxForceN = maxForceN;
        }
        return c;
    }
};

namespace {

bool finite(const Vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void storeVec(std::atomic<double> (&dst)[3], const Vec3& v) {
    for (int i = 0; i < 3; ++i) {
        dst[i].store(v[i], std::memory_order_relaxed);
    }
}

} // namespace

Runtime::Runtime(World& world, std::vector<RuntimeDevice> devices, RuntimeOptions options)
    : mWorld(world), mOptions(options) {
    if (devices.size() > World::kMaxReaders) {
        // Refused before anything opens or starts, not at the 65th servo thread.
        throw std::invalid_argument("runtime: " + std::to_string(devices.size()) +
                                    " devices; at most " + std::to_string(World::kMaxReaders) +
                                    " can share one world");
    }
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    for (std::size_t i = 0; i < devices.size(); ++i) {
        if (!devices[i].device) {
            throw std::invalid_argument("runtime: device " + std::to_string(i) + " is null");
        }
        if (!(devices[i].config.rateHz > 0) || !std::isfinite(devices[i].config.rateHz)) {
            throw std::invalid_argument("runtime: device '" + devices[i].config.name +
                                        "' has no servo rate");
        }
        const double maxForce = devices[i].config.maxForceN;
        auto ch = std::make_unique<Channel>(std::move(devices[i]), mOptions, maxForce);
        ch->periodNs = static_cast<std::uint64_t>(std::llround(1e9 / ch->rd.config.rateHz));
        ch->cpu = mOptions.realtime ? static_cast<int>(i % cores) : -1;
        mChannels.push_back(std::move(ch));
    }
}

Runtime::~Runtime() {
    stop();
}

std::size_t Runtime::start() {
    mStartNs = rt::nowNs();
    // Every device is opened before any servo thread starts (the PHANToM's HD scheduler must
    // not run while another device is being initialised; a Falcon homes with zero force).
    for (auto& chp : mChannels) {
        Channel& ch = *chp;
        const DeviceStatus st = ch.rd.device->open();
        if (st != DeviceStatus::Ok) {
            ch.openError = std::string(statusName(st)) + ": " + ch.rd.device->errorMessage();
            ch.metrics.fault.store(FaultKind::OpenFailed);
            ch.metrics.faultStatus.store(static_cast<std::uint8_t>(st));
            ch.closed.store(true);
            continue;
        }
        ch.opened = true;
        ch.closed.store(false);
        ch.reader = mWorld.registerReader(); // the constructor bounded the count
    }
    std::size_t started = 0;
    for (auto& chp : mChannels) {
        if (chp->opened) {
            startThread(*chp);
            ++started;
        }
    }
    mStopping.store(false);
    mSupervisor = std::thread([this] { superviseMain(); });
    return started;
}

void Runtime::startThread(Channel& ch) {
    ch.stop.store(false, std::memory_order_release);
    ch.safety.reset(); // force grows from zero at the safety filter's rate
    ch.metrics.heartbeatNs.store(rt::nowNs());
    ch.metrics.running.store(true);
    ch.thread = std::thread([this, &ch] { servoMain(ch); });
}

void Runtime::servoMain(Channel& ch) {
    // Set-up: may allocate (the real-time grant's note), nothing below the loop entry does.
    if (mOptions.realtime) {
        ch.grant = rt::makeCurrentThreadRealtime(mOptions.fifoPriority, ch.cpu);
    } else {
        rt::tightenTimerSlack();
        ch.grant.note = "real-time scheduling not requested";
    }
    Device& dev = *ch.rd.device;
    DeviceMetrics& m = ch.metrics;
    m.threadId.store(static_cast<int>(gettid()), std::memory_order_relaxed);
    m.realtime.store(ch.grant.fifo, std::memory_order_relaxed);
    const WorkspaceTransform& xf = ch.rd.config.transform;
    const std::uint64_t period = ch.periodNs;
    const double dt = static_cast<double>(period) * 1e-9;
    const std::uint64_t lateNs =
        static_cast<std::uint64_t>(mOptions.lateWakeupFraction * static_cast<double>(period));
    // A wake-up this late means the thread could not run (starved by a CPU hog, or the host)
    // for K periods while the device held its last force: that tick commands zero.
    const std::uint64_t starvedNs =
        static_cast<std::uint64_t>(std::max(1, mOptions.missLimit)) * period;
    const std::uint64_t startNs = mStartNs;
    const int missLimit = std::max(1, mOptions.missLimit);

    const WorldSnapshot* snap = &mWorld.acquire(*ch.reader);
    std::uint64_t version = snap->version;
    ch.deviceCursor.reset(*snap->index);
    ch.proxyCursor.reset(*snap->index);
    DeviceState state;
    Vec3 lastPosition(0.0);
    bool first = true;
    int consecutiveMisses = 0;
    std::uint64_t tick = 0;
    const auto fault = [&](FaultKind k, DeviceStatus st) {
        m.faultStatus.store(static_cast<std::uint8_t>(st), std::memory_order_relaxed);
        m.faultNs.store(rt::nowNs(), std::memory_order_relaxed);
        m.fault.store(k, std::memory_order_release);
        (void)dev.write(Vec3(0.0));
    };

    rt::setInServoLoop(true);
    std::uint64_t deadline = rt::nowNs() + period;
    while (!ch.stop.load(std::memory_order_acquire)) {
        rt::sleepUntilNs(deadline, mOptions.spinNs);
        const std::uint64_t wake = rt::nowNs();
        const std::uint64_t lateness = wake > deadline ? wake - deadline : 0;

        DeviceStatus st = dev.read(state);
        const std::uint64_t readDone = rt::nowNs();
        if (st != DeviceStatus::Ok) {
            fault(FaultKind::ReadFailed, st);
            break;
        }
        if (ch.stop.load(std::memory_order_acquire)) {
            break; // stopped (or the watchdog fired) while inside read(): zero, below
        }
        if (!finite(state.position) || (state.hasVelocity && !finite(state.velocity))) {
            fault(FaultKind::NonFinite, DeviceStatus::BadData);
            break;
        }

        const WorldSnapshot& s = mWorld.acquire(*ch.reader);
        if (s.version != version) {
            version = s.version;
            ch.deviceCursor.reset(*s.index);
            ch.proxyCursor.reset(*s.index);
            DeviceMetrics::bump(m.snapshotsSeen);
        }

        const Vec3 p = xf.positionToWorld(state.position);
        if (first) {
            ch.renderer.reset(p);
            lastPosition = p;
            first = false;
        }
        const Vec3 v =
            state.hasVelocity ? xf.velocityToWorld(state.velocity) : (p - lastPosition) / dt;
        lastPosition = p;

        const LocateResult atDevice = ch.deviceCursor.locate(p);
        const LocateResult atProxy = ch.proxyCursor.locate(ch.renderer.proxy());
        CandidateSet candidates;
        candidates.add(atDevice.candidates);
        if (atProxy.leaf != atDevice.leaf || atProxy.outside != atDevice.outside) {
            candidates.add(atProxy.candidates);
        }
        candidates.add(s.movingSlots());
        const RenderOutput out = ch.renderer.update(*s.scene, candidates, p, v, dt);
        Triple external{0.0, 0.0, 0.0};
        (void)ch.externalForce.read(external);

        if (ch.stop.load(std::memory_order_acquire)) {
            break; // stopped while rendering: the exit below writes zero, not this force
        }
        Vec3 force = ch.safety.filter(out.force + vec(external));
        if (consecutiveMisses >= missLimit || lateness >= starvedNs) {
            force = Vec3(0.0);
            ch.safety.reset();
            DeviceMetrics::bump(m.zeroedForMisses);
        }
        const Vec3 deviceForce = xf.forceToDevice(force);
        const std::uint64_t writeStart = rt::nowNs();
        st = dev.write(deviceForce);
        const std::uint64_t done = rt::nowNs();
        if (st != DeviceStatus::Ok) {
            fault(FaultKind::WriteFailed, st);
            break;
        }

        // Record.
        const std::uint64_t tickNs = done - wake;
        const std::uint64_t ioNs = (readDone - wake) + (done - writeStart);
        m.tickNs.record(tickNs);
        m.latenessNs.record(lateness);
        m.ioNs.record(ioNs);
        if (lateness > lateNs) {
            DeviceMetrics::bump(m.lateWakeups);
        }
        DeviceMetrics::bump(m.locateStepsSum, atDevice.steps + atProxy.steps);
        DeviceMetrics::bump(m.candidatesSum, out.objectsTested);
        if (atDevice.outside) {
            DeviceMetrics::bump(m.outsideTicks);
        }
        if (out.contactCount > 0) {
            DeviceMetrics::bump(m.contactTicks);
        }
        storeVec(m.forceN, force);
        storeVec(m.positionM, p);
        ContactWire report{tick,
                           triple(p),
                           triple(out.proxy),
                           triple(force),
                           {kNoObject, kNoObject, kNoObject},
                           {},
                           out.contactCount};
        for (std::uint32_t c = 0; c < out.contactCount && c < report.objects.size(); ++c) {
            report.objects[c] = out.contacts[c].id;
            report.normals[c] = triple(out.contacts[c].normal);
        }
        ch.contacts.publish(report);
        if (ch.rd.recorder) {
            TraceSample sample{};
            sample.tick = tick;
            sample.timeNs = wake - startNs;
            sample.positionM = state.position;
            sample.forceN = deviceForce;
            sample.computeNs =
                static_cast<std::uint32_t>(std::min<std::uint64_t>(tickNs, UINT32_MAX));
            sample.ioNs = static_cast<std::uint32_t>(std::min<std::uint64_t>(ioNs, UINT32_MAX));
            sample.status = st;
            sample.buttons = state.buttons;
            (void)ch.rd.recorder->push(sample);
        }
        ++tick;
        DeviceMetrics::bump(m.ticks);
        m.heartbeatNs.store(done, std::memory_order_relaxed);

        // The next deadline. A tick whose force came after the next deadline missed it;
        // skip the slots it overran instead of bursting to catch up.
        deadline += period;
        if (done > deadline) {
            DeviceMetrics::bump(m.missedDeadlines);
            consecutiveMisses = std::min(consecutiveMisses + 1, missLimit); // saturates
            deadline += ((done - deadline) / period + 1) * period;
        } else {
            consecutiveMisses = 0;
        }
    }
    (void)dev.write(Vec3(0.0));
    storeVec(m.forceN, Vec3(0.0));
    // Tell the control thread this hand touches nothing now (a grasp must not hold on to it).
    ch.contacts.publish(ContactWire{tick,
                                    triple(lastPosition),
                                    triple(lastPosition),
                                    {0.0, 0.0, 0.0},
                                    {kNoObject, kNoObject, kNoObject},
                                    {},
                                    0});
    rt::setInServoLoop(false);
    m.running.store(false, std::memory_order_release);
}

void Runtime::maintain() {
    mWorld.maintain();
}

bool Runtime::waitUnlessStopping(std::uint64_t ns) {
    std::unique_lock lock(mWakeMutex);
    return !mWake.wait_for(lock, std::chrono::nanoseconds(ns),
                           [this] { return mStopping.load(std::memory_order_acquire); });
}

void Runtime::superviseMain() {
    // Above the servo threads, so a stalled or starved core never keeps the watchdog from
    // running (it sleeps between passes and its pass is a few atomic loads).
    if (mOptions.realtime) {
        (void)rt::makeCurrentThreadRealtime(std::min(99, mOptions.fifoPriority + 1), -1);
    }
    const std::uint64_t passNs =
        std::clamp<std::uint64_t>(mOptions.stallTimeoutNs / 5, 1'000'000, 10'000'000);
    while (waitUnlessStopping(passNs)) {
        const std::uint64_t now = rt::nowNs();
        for (auto& chp : mChannels) {
            Channel& ch = *chp;
            if (!ch.opened || ch.recovering.load(std::memory_order_acquire) ||
                ch.gaveUp.load(std::memory_order_acquire)) {
                continue;
            }
            DeviceMetrics& m = ch.metrics;
            if (m.running.load(std::memory_order_acquire)) {
                const std::uint64_t beat = m.heartbeatNs.load(std::memory_order_relaxed);
                FaultKind none = FaultKind::None;
                if (now > beat && now - beat > mOptions.stallTimeoutNs &&
                    m.fault.compare_exchange_strong(none, FaultKind::Watchdog)) {
                    // The thread is stuck (in the device, or the host stopped it): when it
                    // returns it writes zero and ends, and the fault is recovered like any.
                    m.faultNs.store(beat);
                    ch.stop.store(true, std::memory_order_release);
                }
                continue;
            }
            if (m.fault.load(std::memory_order_acquire) == FaultKind::None) {
                continue; // between a reopen and its thread's start
            }
            if (ch.worker.joinable()) {
                ch.worker.join(); // the previous recovery, finished
            }
            ch.recovering.store(true, std::memory_order_release);
            ch.worker = std::thread([this, &ch] { recoverMain(ch); });
        }
    }
}

namespace {

// Servo and supervisor threads are SCHED_FIFO; a recovery worker (close, open, homing) is not.
void becomeNormalThread() {
    sched_param param{};
    (void)pthread_setschedparam(pthread_self(), SCHED_OTHER, &param);
}

} // namespace

void Runtime::recoverMain(Channel& ch) {
    becomeNormalThread();
    if (ch.thread.joinable()) {
        ch.thread.join(); // it left its loop after commanding zero force
    }
    const FaultKind f = ch.metrics.fault.load(std::memory_order_acquire);
    if (!ch.closed.exchange(true)) {
        ch.rd.device->close();
    }
    const std::uint64_t now = rt::nowNs();
    {
        std::lock_guard lock(ch.cold);
        const std::uint64_t at = ch.metrics.faultNs.load();
        ch.downSinceNs = at != 0 && at <= now ? at : now; // down since the fault itself
        ++ch.faults;
        const std::string status =
            f == FaultKind::Watchdog
                ? "no tick for " + std::to_string(mOptions.stallTimeoutNs / 1'000'000) + " ms"
                : std::string(statusName(static_cast<DeviceStatus>(ch.metrics.faultStatus.load())));
        ch.lastFault = std::string(faultName(f)) + ": " + status;
        const std::string detail = ch.rd.device->errorMessage();
        addEvent(ch, now,
                 ch.lastFault + (detail.empty() ? "" : " (" + detail + ")") + "; force zeroed");
        ch.down.store(true, std::memory_order_release);
    }
    if (mOptions.reopenAfterNs == 0) {
        ch.gaveUp.store(true, std::memory_order_release);
        ch.recovering.store(false, std::memory_order_release);
        return;
    }
    while (waitUnlessStopping(mOptions.reopenAfterNs)) {
        const DeviceStatus st = ch.rd.device->open();
        const std::uint64_t back = rt::nowNs(); // open() may take long (set-up, homing)
        if (st != DeviceStatus::Ok) {
            const std::string why =
                std::string(statusName(st)) + ": " + ch.rd.device->errorMessage();
            std::lock_guard lock(ch.cold);
            if (why != ch.lastReopenError) {
                addEvent(ch, back,
                         "reopen failed, " + why + "; trying every " +
                             std::to_string(mOptions.reopenAfterNs / 1'000'000) + " ms");
                ch.lastReopenError = why;
            }
            continue;
        }
        ch.closed.store(false);
        std::lock_guard wake(mWakeMutex); // stop() cannot begin between this check and start
        if (mStopping.load(std::memory_order_acquire)) {
            break; // opened while stopping: close below
        }
        {
            std::lock_guard lock(ch.cold);
            ch.lastReopenError.clear();
            ++ch.reopens;
            ch.downNs += back - ch.downSinceNs;
            addEvent(ch, back, "reopened; driving again from zero force");
        }
        {
            std::lock_guard lock(ch.cold);
            ch.metrics.fault.store(FaultKind::None);
            ch.metrics.faultStatus.store(0);
            ch.metrics.faultNs.store(0);
            ch.down.store(false, std::memory_order_release);
        }
        startThread(ch);
        ch.recovering.store(false, std::memory_order_release);
        return;
    }
    if (!ch.closed.exchange(true)) {
        ch.rd.device->close(); // stopping: a device opened meanwhile is closed again
    }
    ch.recovering.store(false, std::memory_order_release);
}

void Runtime::addEvent(Channel& ch, std::uint64_t nowNs, const std::string& what) {
    if (ch.events.size() >= kMaxEvents) {
        ++ch.eventsDropped;
        return;
    }
    char at[32];
    std::snprintf(at, sizeof at, "%.3f s: ", static_cast<double>(nowNs - mStartNs) * 1e-9);
    ch.events.push_back(at + what);
}

void Runtime::stop() {
    {
        std::lock_guard wake(mWakeMutex);
        mStopping.store(true, std::memory_order_release);
    }
    mWake.notify_all();
    for (auto& ch : mChannels) {
        ch->stop.store(true, std::memory_order_release);
    }
    if (mSupervisor.joinable()) {
        mSupervisor.join();
    }
    for (auto& chp : mChannels) {
        if (chp->worker.joinable()) {
            chp->worker.join(); // returns at once, or when a reopen in progress returns
        }
    }
    for (auto& chp : mChannels) {
        Channel& ch = *chp;
        ch.stop.store(true, std::memory_order_release); // a thread a worker just started
        if (ch.thread.joinable()) {
            ch.thread.join();
        }
        if (ch.opened) {
            if (!ch.closed.exchange(true)) {
                ch.rd.device->close();
            }
            mWorld.unregisterReader(ch.reader);
            ch.reader = nullptr;
            ch.opened = false;
            if (!ch.grant.note.empty() && mRealtimeNote.find(ch.grant.note) == std::string::npos) {
                mRealtimeNote += (mRealtimeNote.empty() ? "" : "; ") + ch.grant.note;
            }
        }
    }
    std::uint64_t none = 0;
    if (mStartNs != 0) {
        mStopNs.compare_exchange_strong(none, rt::nowNs());
    }
}

void Runtime::emergencyStop(std::uint64_t waitNs) noexcept {
    mStopping.store(true, std::memory_order_release);
    for (auto& ch : mChannels) {
        ch->stop.store(true, std::memory_order_release);
    }
    // Each servo thread commands zero as it leaves its loop (at its next check).
    const std::uint64_t until = rt::nowNs() + waitNs;
    const auto anyInLoop = [this] {
        return std::any_of(mChannels.begin(), mChannels.end(), [](auto& ch) {
            return ch->metrics.running.load(std::memory_order_acquire);
        });
    };
    while (anyInLoop() && rt::nowNs() < until) {
        rt::sleepUntilNs(rt::nowNs() + 1'000'000, 0);
    }
    for (auto& chp : mChannels) {
        Channel& ch = *chp;
        if (!ch.metrics.running.load(std::memory_order_acquire) &&
            !ch.recovering.load(std::memory_order_acquire) && !ch.closed.exchange(true)) {
            ch.rd.device->close(); // zero force, and the device's own I/O ends
        }
    }
}

bool Runtime::anyRunning() const {
    if (mStopping.load(std::memory_order_acquire)) {
        return false;
    }
    return std::any_of(mChannels.begin(), mChannels.end(), [](auto& ch) {
        return ch->opened && !ch->gaveUp.load(std::memory_order_acquire);
    });
}

const DeviceMetrics& Runtime::metrics(std::size_t i) const {
    return mChannels.at(i)->metrics;
}
std::size_t Runtime::deviceCount() const {
    return mChannels.size();
}
Device& Runtime::device(std::size_t i) {
    return *mChannels.at(i)->rd.device;
}

RunReport Runtime::report() const {
    RunReport r;
    r.cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    r.stable = !mChannels.empty();
    for (const auto& chp : mChannels) {
        const Channel& ch = *chp;
        const DeviceMetrics& m = ch.metrics;
        DeviceReport d;
        d.name = ch.rd.config.name;
        d.kind = ch.rd.config.kind;
        d.rateHz = ch.rd.config.rateHz;
        d.ticks = m.ticks.load();
        HistogramSummary t = m.tickNs.summary();
        const double period = static_cast<double>(ch.periodNs);
        d.loadFraction = {t.count,        t.mean / period, t.p50 / period,
                          t.p99 / period, t.p999 / period, t.max / period};
        d.latenessNs = m.latenessNs.summary();
        d.ioNs = m.ioNs.summary();
        d.lateWakeups = m.lateWakeups.load();
        d.missedDeadlines = m.missedDeadlines.load();
        d.zeroedForMisses = m.zeroedForMisses.load();
        const double ticks = static_cast<double>(std::max<std::uint64_t>(1, d.ticks));
        d.locateStepsMean = static_cast<double>(m.locateStepsSum.load()) / ticks;
        d.candidatesMean = static_cast<double>(m.candidatesSum.load()) / ticks;
        d.outsideTicks = m.outsideTicks.load();
        d.contactTicks = m.contactTicks.load();
        d.snapshotsSeen = m.snapshotsSeen.load();
        d.safety = ch.safety.counters();
        d.realtime = m.realtime.load(std::memory_order_relaxed);
        std::lock_guard lock(ch.cold);
        const FaultKind f = m.fault.load();
        const bool down = ch.down.load(std::memory_order_acquire);
        if (f == FaultKind::OpenFailed) {
            d.fault = std::string("open-failed: ") + ch.openError;
        } else if (down) {
            d.fault = ch.lastFault;
        } else if (f != FaultKind::None) { // faulted, not yet taken by the supervisor
            d.fault = std::string(faultName(f)) + ": " +
                      std::string(statusName(static_cast<DeviceStatus>(m.faultStatus.load())));
        }
        d.faults = ch.faults + (f != FaultKind::None && f != FaultKind::OpenFailed && !down);
        d.reopens = ch.reopens;
        const std::uint64_t downNow = down ? rt::nowNs() - ch.downSinceNs : 0;
        d.downS = static_cast<double>(ch.downNs + downNow) * 1e-9;
        d.events = ch.events;
        if (ch.eventsDropped > 0) {
            d.events.push_back("... and " + std::to_string(ch.eventsDropped) + " more events");
        }
        d.stable = d.fault.empty() && d.faults == 0 && d.ticks > 0 && d.loadFraction.p999 < 1.0 &&
                   static_cast<double>(d.missedDeadlines) <= 0.001 * static_cast<double>(d.ticks);
        r.loadSum += d.loadFraction.mean;
        r.stable = r.stable && d.stable;
        r.devices.push_back(std::move(d));
    }
    r.loadPerCore = r.loadSum / r.cores;
    const std::uint64_t stoppedAt = mStopNs.load();
    const std::uint64_t end = stoppedAt ? stoppedAt : rt::nowNs();
    r.durationS = mStartNs ? static_cast<double>(end - mStartNs) * 1e-9 : 0.0;
    r.realtimeNote = mRealtimeNote;
    return r;
}

std::string Runtime::liveLine(std::size_t i) const {
    const Channel& ch = *mChannels.at(i);
    const DeviceMetrics& m = ch.metrics;
    const HistogramSummary t = m.tickNs.summary();
    const double period = static_cast<double>(ch.periodNs);
    const Vec3 f(m.forceN[0].load(), m.forceN[1].load(), m.forceN[2].load());
    char line[256];
    std::snprintf(line, sizeof line,
                  "%-10s %9llu ticks  load p50 %5.1f%%  p99.9 %5.1f%%  max %6.1f%%  missed %llu  "
                  "|F| %5.2f N%s",
                  ch.rd.config.name.c_str(), static_cast<unsigned long long>(m.ticks.load()),
                  100.0 * t.p50 / period, 100.0 * t.p999 / period, 100.0 * t.max / period,
                  static_cast<unsigned long long>(m.missedDeadlines.load()), glm::length(f),
                  m.fault.load() != FaultKind::None ? "  FAULTED" : "");
    return line;
}

bool Runtime::contact(std::size_t i, ContactReport& report) const {
    ContactWire w;
    if (!mChannels.at(i)->contacts.read(w)) {
        return false;
    }
    report.tick = w.tick;
    report.devicePoint = vec(w.devicePoint);
    report.proxy = vec(w.proxy);
    report.force = vec(w.force);
    report.objects = w.objects;
    for (std::size_t c = 0; c < 3; ++c) {
        report.normals[c] = vec(w.normals[c]);
    }
    report.contactCount = w.contactCount;
    return true;
}

void Runtime::setExternalForce(std::size_t i, const Vec3& forceN) {
    mChannels.at(i)->externalForce.publish(triple(forceN));
}

std::string reportToJson(const RunReport& r) {
    using nlohmann::json;
    const auto load = [](const HistogramSummary& s) {
        return json{
            {"mean", s.mean}, {"p50", s.p50}, {"p99", s.p99}, {"p999", s.p999}, {"max", s.max}};
    };
    json devices = json::array();
    for (const DeviceReport& d : r.devices) {
        devices.push_back(json{
            {"name", d.name},
            {"kind", d.kind},
            {"rate_hz", d.rateHz},
            {"ticks", d.ticks},
            {"load", load(d.loadFraction)},
            {"late_wakeups", d.lateWakeups},
            {"missed_deadlines", d.missedDeadlines},
            {"zeroed_for_misses", d.zeroedForMisses},
            {"lateness_ns", load(d.latenessNs)},
            {"io",
             {{"mean_ns", d.ioNs.mean},
              {"p99_ns", d.ioNs.p99},
              {"max_ns", d.ioNs.max},
              {"fraction_of_tick", d.loadFraction.mean > 0
                                       ? d.ioNs.mean / (d.loadFraction.mean * 1e9 / d.rateHz)
                                       : 0.0}}},
            {"locate_steps_mean", d.locateStepsMean},
            {"candidates_mean", d.candidatesMean},
            {"outside_ticks", d.outsideTicks},
            {"contact_ticks", d.contactTicks},
            {"snapshots_seen", d.snapshotsSeen},
            {"safety",
             {{"clamped", d.safety.clamped},
              {"rate_limited", d.safety.rateLimited},
              {"non_finite", d.safety.nonFinite},
              {"overflowed", d.safety.overflowed}}},
            {"faults", d.faults},
            {"fault", d.fault},
            {"reopens", d.reopens},
            {"down_s", d.downS},
            {"events", d.events},
            {"realtime", d.realtime},
            {"stable", d.stable},
        });
    }
    json total{{"load_sum", r.loadSum},
               {"load_per_core", r.loadPerCore},
               {"cores", r.cores},
               {"stable", r.stable},
               {"duration_s", r.durationS}};
    json out{{"devices", devices}, {"total", total}};
    if (!r.realtimeNote.empty()) {
        out["realtime_note"] = r.realtimeNote;
    }
    return out.dump(2) + "\n";
}

} // namespace hapto
