// The servo: one tick of one device, and the loop that runs it. Design note: a tick is read,
// claim the snapshot, pick up changed force effects, the haptic tick (HapticTick: locate both
// cursors, candidates, render, effects and the hook, safety), the fault rules, write, record.
// Faults become zero force and a recorded FaultKind, never an exception. The tick is written once,
// as servoTick(): a servo thread sleeps to each absolute deadline and calls it (servoMain); the
// step mode calls it from the caller's thread at the times the caller gives (step). Nothing below
// servoTick's entry allocates, locks, throws or makes a syscall beyond the device's own I/O and the
// clock.
//
// The fault rules, per tick:
//   - read() or write() fails: fault, zero, the servo ends (supervision closes and reopens);
//   - a non-finite position or velocity: fault, zero, the servo ends;
//   - the read returns more than the stall timeout after the last tick: the watchdog's fault
//     (the supervisor may have seen it first, while the read hung), zero, the servo ends;
//   - K missed deadlines in a row, or a wake-up K periods late (the thread could not run
//     while the device held its last force): that tick commands zero, and force grows from
//     zero at the safety filter's rate once ticks are on time again.

#include "hapto/runtime/ServoLoop.h"

#include "Channel.h"

#include "hapto/core/CpuPause.h"
#include "hapto/core/Finite.h"
#include "hapto/devices/TraceRecorder.h"

#include <algorithm>
#include <cmath>
#include <unistd.h>

namespace hapto {
namespace {

/// Prefetches the scene objects that `items` name (at most kMaxWarmUpPrefetches; triangle
/// items are skipped: finding their mesh is a search, not a load) and returns their sum. [servo]
std::uint64_t touchObjects(const Scene& scene, std::span<const std::uint32_t> items) noexcept {
    const std::span<const SceneObject> objects = scene.objects();
    std::uint64_t sum = 0;
    const std::size_t n = std::min(items.size(), kMaxWarmUpPrefetches);
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t item = items[i];
        if (!isTriangleItem(item) && item < objects.size()) {
            __builtin_prefetch(&objects[item]);
        }
        sum += item;
    }
    return sum;
}

} // namespace

std::uint64_t warmUpTick(const WorldSnapshot& snapshot, const GodObjectRenderer& renderer,
                         std::span<const std::byte> tickState, const Vec3& lastPointM,
                         const Vec3& lastStepM, double dtS) noexcept {
    // The tick's own state first: the cursors, the renderer, the safety filter, the effects.
    for (std::size_t offset = 0; offset < tickState.size(); offset += 64) {
        __builtin_prefetch(tickState.data() + offset);
    }
    const Scene& scene = *snapshot.scene;
    const SpatialIndex& index = *snapshot.index;
    // The index's path to the device point's leaf and the proxy's (a locate from the root
    // reads every node on the way; no cursor moves), and the objects they list.
    CandidateSet candidates;
    // Where the hand will be if it keeps its last step: the tick's own situation (a corner it
    // is about to reach), which the last point's would not show.
    const Vec3 nextPointM = finite(lastStepM) ? lastPointM + lastStepM : lastPointM;
    const LocateResult atDevice = index.locate(nextPointM);
    std::uint64_t sum = atDevice.leaf + touchObjects(scene, atDevice.candidates);
    candidates.add(atDevice.candidates);
    const LocateResult atProxy = index.locate(renderer.proxy());
    if (atProxy.leaf != atDevice.leaf) {
        sum += atProxy.leaf + touchObjects(scene, atProxy.candidates);
        candidates.add(atProxy.candidates);
    }
    sum += touchObjects(scene, snapshot.movingSlots());
    candidates.add(snapshot.movingSlots());
    // A dry render on a copy: the solver's code and the near objects' data, warm.
    GodObjectRenderer dry = renderer; // a plain copy: no allocation
    const RenderOutput out = dry.update(scene, candidates, nextPointM, Vec3(0.0), dtS);
    return sum + out.objectsTested + out.contactCount;
}

void spinUntilNs(std::uint64_t deadlineNs) noexcept {
    while (rt::nowNs() < deadlineNs) {
        cpuPause();
    }
}

void Runtime::startServo(Channel& ch, std::uint64_t nowNs) noexcept {
    ServoState& s = ch.servo;
    s.stop.store(false, std::memory_order_release);
    s.haptic.reset(); // the proxy starts on the first point; force grows from zero
    s.first = true;
    s.consecutiveMisses = 0;
    s.deadlineNs = nowNs + s.periodNs;
    ch.metrics.heartbeatNs.store(nowNs);
    ch.metrics.running.store(true);
}

bool Runtime::servoTick(Channel& ch, const std::uint64_t wake) noexcept {
    ServoState& s = ch.servo;
    DeviceMetrics& m = ch.metrics;
    const auto fault = [&](FaultKind k, DeviceStatus st, std::uint64_t atNs) {
        m.faultStatus.store(static_cast<std::uint8_t>(st), std::memory_order_relaxed);
        m.faultNs.store(atNs, std::memory_order_relaxed);
        m.fault.store(k, std::memory_order_release);
        (void)s.device->write(Vec3(0.0));
    };
    const std::uint64_t lateness = wake > s.deadlineNs ? wake - s.deadlineNs : 0;

    DeviceStatus st = s.device->read(s.sample);
    const std::uint64_t readDone = now();
    if (st != DeviceStatus::Ok) {
        fault(FaultKind::ReadFailed, st, readDone);
        return false;
    }
    if (s.stop.load(std::memory_order_acquire)) {
        return false; // stopped (or the watchdog fired) while inside read(): zero, on leaving
    }
    const std::uint64_t beat = m.heartbeatNs.load(std::memory_order_relaxed);
    if (readDone > beat && readDone - beat > s.stallNs) {
        // No tick for longer than the watchdog allows: the same fault the supervisor gives
        // a hung servo (whichever sees it first), so a tick never ends such a gap with force.
        FaultKind none = FaultKind::None;
        if (m.fault.compare_exchange_strong(none, FaultKind::Watchdog)) {
            m.faultNs.store(beat, std::memory_order_relaxed);
        }
        return false;
    }
    const Quat& q = s.sample.orientation;
    if (!finite(s.sample.position) || (s.sample.hasVelocity && !finite(s.sample.velocity)) ||
        (s.sample.hasOrientation && !(finite(Vec3(q.x, q.y, q.z)) && std::isfinite(q.w))) ||
        (s.sample.hasAngularVelocity && !finite(s.sample.angularVelocity))) {
        fault(FaultKind::NonFinite, DeviceStatus::BadData, readDone);
        return false;
    }

    const WorldSnapshot& snap = mWorld.acquire(*s.reader);
    // The contact point: the tool tip, position + R * tip (R the stylus orientation, or the
    // device's axes on a device without one), which is the gimbal centre for a zero tip. Its
    // velocity adds the stylus's turn, w x (R * tip), where the device measures w.
    const Vec3 tip = s.sample.hasOrientation ? s.sample.orientation * s.toolTip : s.toolTip;
    const Vec3 p = s.transform.positionToWorld(s.sample.position + tip);
    if (s.first) {
        s.lastPosition = p;
        s.first = false;
    }
    s.lastStep = p - s.lastPosition;
    const Vec3 tipTurn =
        s.sample.hasAngularVelocity ? glm::cross(s.sample.angularVelocity, tip) : Vec3(0.0);
    const Vec3 v = s.sample.hasVelocity ? s.transform.velocityToWorld(s.sample.velocity + tipTurn)
                                        : (p - s.lastPosition) / s.dtS;
    s.lastPosition = p;
    Vec3 external{0.0};
    (void)ch.externalForce.read(external);
    // Effects the control thread changed since the last tick: copied in now. A read that races
    // a newer publish fails and is tried again next tick; the servo never waits for it.
    if (ch.effectsPublished.load(std::memory_order_acquire) != s.effectsApplied) {
        EffectSet fresh;
        std::uint64_t writes = 0;
        if (ch.effects.read(fresh, writes)) {
            s.haptic.setEffects(fresh);
            s.effectsApplied = writes;
        }
    }
    const TickOutput out = s.haptic.tick(snap, p, v, s.dtS, external, s.sample);
    if (out.newSnapshot) {
        DeviceMetrics::bump(m.snapshotsSeen);
    }
    if (out.hookNonFinite) {
        DeviceMetrics::bump(m.hookNonFinite);
    }
    if (s.stop.load(std::memory_order_acquire)) {
        return false; // stopped while rendering: leaving writes zero, not this force
    }

    Vec3 force = out.forceN;
    if (s.consecutiveMisses >= s.missLimit || lateness >= s.starvedNs) {
        force = Vec3(0.0);
        s.haptic.zeroForce();
        DeviceMetrics::bump(m.zeroedForMisses);
    }
    const Vec3 deviceForce = s.transform.forceToDevice(force);
    const std::uint64_t writeStart = now();
    st = s.device->write(deviceForce);
    const std::uint64_t done = now();
    if (st != DeviceStatus::Ok) {
        fault(FaultKind::WriteFailed, st, done);
        return false;
    }

    // Record. A force written after the next deadline missed it (the rule at the end).
    const bool missed = done > s.deadlineNs + s.periodNs;
    const std::uint64_t tickNs = done - wake;
    const std::uint64_t ioNs = (readDone - wake) + (done - writeStart);
    m.tickNs.record(tickNs);
    m.latenessNs.record(lateness);
    m.ioNs.record(ioNs);
    if (lateness > s.lateNs) {
        DeviceMetrics::bump(m.lateWakeups);
    }
    DeviceMetrics::bump(m.locateStepsSum, out.locateSteps);
    DeviceMetrics::bump(m.candidatesSum, out.render.objectsTested);
    if (out.outside) {
        DeviceMetrics::bump(m.outsideTicks);
    }
    if (out.render.contactCount > 0) {
        DeviceMetrics::bump(m.contactTicks);
    }
    storeVec(m.forceN, force);
    storeVec(m.positionM, p);
    m.leafAtVersion.store((snap.version & 0xFFFFFFFFu) << 32 | out.deviceLeaf,
                          std::memory_order_relaxed);
    ContactReport report;
    report.tick = s.tick;
    report.devicePoint = p;
    report.proxy = out.render.proxy;
    report.force = force;
    report.contactCount = out.render.contactCount;
    for (std::uint32_t c = 0; c < out.render.contactCount && c < report.objects.size(); ++c) {
        report.objects[c] = out.render.contacts[c].id;
        report.normals[c] = out.render.contacts[c].normal;
    }
    ch.contacts.publish(report);
    if (s.recorder) {
        TraceSample sample{};
        sample.tick = s.tick;
        sample.timeNs = wake - mStartNs;
        sample.positionM = s.sample.position;
        sample.forceN = deviceForce;
        sample.computeNs = static_cast<std::uint32_t>(std::min<std::uint64_t>(tickNs, UINT32_MAX));
        sample.ioNs = static_cast<std::uint32_t>(std::min<std::uint64_t>(ioNs, UINT32_MAX));
        sample.status = st;
        sample.buttons = s.sample.buttons;
        sample.proxyM = s.transform.positionToDevice(out.render.proxy);
        sample.velocityMps = s.sample.velocity;
        sample.hasVelocity = s.sample.hasVelocity;
        sample.orientation = s.sample.orientation;
        sample.hasOrientation = s.sample.hasOrientation;
        sample.angularVelocity = s.sample.angularVelocity;
        sample.hasAngularVelocity = s.sample.hasAngularVelocity;
        sample.contactCount = out.render.contactCount;
        sample.missedDeadline = missed;
        (void)s.recorder->push(sample);
    }
    ++s.tick;
    DeviceMetrics::bump(m.ticks);
    m.heartbeatNs.store(done, std::memory_order_relaxed);

    // The next deadline. A tick whose force came after the next deadline missed it; skip the
    // slots it overran instead of bursting to catch up, and tell the device they went by.
    s.deadlineNs += s.periodNs;
    if (missed) {
        DeviceMetrics::bump(m.missedDeadlines);
        s.consecutiveMisses = std::min(s.consecutiveMisses + 1, s.missLimit); // saturates
        const std::uint64_t skipped = (done - s.deadlineNs) / s.periodNs + 1;
        s.deadlineNs += skipped * s.periodNs;
        s.device->periodsSkipped(skipped);
    } else {
        s.consecutiveMisses = 0;
    }
    return true;
}

std::uint64_t Runtime::warm(Channel& ch) noexcept {
    ServoState& s = ch.servo;
    const WorldSnapshot& snap = mWorld.acquire(*s.reader); // the tick claims it again
    const std::uint64_t sum = warmUpTick(snap, s.haptic.renderer(), std::as_bytes(std::span(&s, 1)),
                                         s.lastPosition, s.lastStep, s.dtS);
    asm volatile("" : : "r"(sum) : "memory"); // what was read counts as used
    return sum;
}

void Runtime::leaveServo(Channel& ch) noexcept {
    ServoState& s = ch.servo;
    DeviceMetrics& m = ch.metrics;
    (void)s.device->write(Vec3(0.0));
    storeVec(m.forceN, Vec3(0.0));
    // Tell the control thread this hand touches nothing now (a grasp must not hold on to it).
    ContactReport none;
    none.tick = s.tick;
    none.devicePoint = s.lastPosition;
    none.proxy = s.lastPosition;
    ch.contacts.publish(none);
    m.running.store(false, std::memory_order_release);
}

void Runtime::startThread(Channel& ch) {
    startServo(ch, now());
    ch.record.thread = std::thread([this, &ch] { servoMain(ch); });
}

void Runtime::servoMain(Channel& ch) {
    // Set-up: may allocate (the real-time grant's note), nothing below the loop entry does.
    ChannelRecord& c = ch.record;
    if (mOptions.realtime) {
        c.grant = rt::makeCurrentThreadRealtime(mOptions.fifoPriority, c.cpu);
    } else {
        rt::tightenTimerSlack();
        c.grant.note = "real-time scheduling not requested";
    }
    DeviceMetrics& m = ch.metrics;
    m.threadId.store(static_cast<int>(gettid()), std::memory_order_relaxed);
    m.realtime.store(c.grant.fifo, std::memory_order_relaxed);
    ServoState& s = ch.servo;
    s.deadlineNs = rt::nowNs() + s.periodNs;

    rt::setInServoLoop(true);
    const std::uint64_t warmNs = std::min(mWarmUpNs, s.periodNs / 2); // documented
    while (!s.stop.load(std::memory_order_acquire)) {
        if (warmNs > 0 && s.deadlineNs > warmNs) {
            // Wake warmNs early (after spinning the part of --spin-us before that, if longer),
            // touch the tick's working set, spin to the deadline; the device is read after it.
            const std::uint64_t spinBefore =
                mOptions.spinNs > warmNs ? mOptions.spinNs - warmNs : 0;
            rt::sleepUntilNs(s.deadlineNs - warmNs, spinBefore);
            (void)warm(ch);
            spinUntilNs(s.deadlineNs);
        } else {
            rt::sleepUntilNs(s.deadlineNs, mOptions.spinNs);
        }
        if (!servoTick(ch, rt::nowNs())) {
            break;
        }
    }
    leaveServo(ch);
    rt::setInServoLoop(false);
}

bool Runtime::step(std::size_t i, std::uint64_t nowNs) {
    requireStepped("step");
    Channel& ch = *mChannels.at(i);
    ServoState& s = ch.servo;
    if (!ch.metrics.running.load(std::memory_order_acquire) || nowNs < s.deadlineNs) {
        return false; // not running, or asleep until its deadline
    }
    mClock->set(nowNs);
    rt::setInServoLoop(true);
    if (mWarmUpNs > 0) {
        (void)warm(ch); // the step mode has no sleep to wake from; it warms up so tests cover it
    }
    const bool ticked = !s.stop.load(std::memory_order_acquire) && servoTick(ch, nowNs);
    if (!ticked) {
        leaveServo(ch);
    }
    rt::setInServoLoop(false);
    mClock->set(nowNs); // the other devices' threads did not wait for this one
    return ticked;
}

void Runtime::stepAll(std::uint64_t nowNs) {
    requireStepped("stepAll");
    for (std::size_t i = 0; i < mChannels.size(); ++i) {
        if (mChannels[i]->record.group < 0) {
            (void)step(i, nowNs);
        }
    }
    stepGroups(nowNs); // GroupedServo.cpp: each group's members in deadline order
    supervise(nowNs);
}

void Runtime::runUntil(std::uint64_t untilNs) {
    requireStepped("runUntil");
    std::uint64_t at = mClock->nowNs();
    for (;;) {
        // The next event: a running servo's deadline, or a recovering device's reopen time.
        std::uint64_t next = UINT64_MAX;
        for (const auto& chp : mChannels) {
            const Channel& ch = *chp;
            if (ch.metrics.running.load(std::memory_order_acquire)) {
                next = std::min(next, std::max(ch.servo.deadlineNs, at));
            } else if (ch.record.recovering.load(std::memory_order_acquire)) {
                next = std::min(next, std::max(ch.record.nextReopenNs, at));
            }
        }
        if (next > untilNs) {
            break;
        }
        stepAll(next);
        at = next;
    }
    mClock->set(untilNs);
    if (at < untilNs) {
        supervise(untilNs);
    }
}

} // namespace hapto
