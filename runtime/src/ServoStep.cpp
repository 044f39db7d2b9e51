// One device's servo step (ServoStep.h has the design note and the fault rules).

#include "hapto/runtime/ServoStep.h"

#include "hapto/core/Finite.h"
#include "hapto/devices/TraceRecorder.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/ServoLoop.h"

#include <algorithm>
#include <cmath>
#include <span>

namespace hapto {
namespace {

/// Stores a vector into three relaxed atomics. [servo]
void storeVec(std::atomic<double> (&dst)[3], const Vec3& v) noexcept {
    for (int i = 0; i < 3; ++i) {
        dst[i].store(v[i], std::memory_order_relaxed);
    }
}

/// A reading with a non-finite position, velocity, orientation or angular velocity. [servo]
bool nonFinite(const DeviceState& s) noexcept {
    const Quat& q = s.orientation;
    return !finite(s.position) || (s.hasVelocity && !finite(s.velocity)) ||
           (s.hasOrientation && !(finite(Vec3(q.x, q.y, q.z)) && std::isfinite(q.w))) ||
           (s.hasAngularVelocity && !finite(s.angularVelocity));
}

} // namespace

static_assert(sizeof(ServoStep) == 21824, "update the size in ServoStep.h");

void ServoStep::setTiming(std::uint64_t period, int limit, double lateWakeupFraction,
                          std::uint64_t stallTimeoutNs) noexcept {
    periodNs = period;
    dtS = static_cast<double>(period) * 1e-9;
    lateNs = static_cast<std::uint64_t>(lateWakeupFraction * static_cast<double>(period));
    // A wake-up this late means the thread could not run (starved by a CPU hog, or the host)
    // for K periods while the device held its last force: that step commands zero.
    missLimit = std::max(1, limit);
    starvedNs = static_cast<std::uint64_t>(missLimit) * period;
    stallNs = stallTimeoutNs;
}

std::uint64_t ServoStep::now() const noexcept {
    return ports.clock ? ports.clock->nowNs() : rt::nowNs();
}

void ServoStep::start(std::uint64_t nowNs) noexcept {
    stop.store(false, std::memory_order_release);
    haptic.reset(); // the proxy starts on the first point; force grows from zero
    first = true;
    consecutiveMisses = 0;
    deadlineNs = nowNs + periodNs;
    ports.metrics->heartbeatNs.store(nowNs);
    ports.metrics->running.store(true);
}

void ServoStep::fault(FaultKind kind, DeviceStatus status, std::uint64_t atNs) noexcept {
    DeviceMetrics& m = *ports.metrics;
    m.faultStatus.store(static_cast<std::uint8_t>(status), std::memory_order_relaxed);
    m.faultNs.store(atNs, std::memory_order_relaxed);
    m.fault.store(kind, std::memory_order_release);
    (void)device->write(Vec3(0.0));
}

bool ServoStep::readDevice(std::uint64_t& readDone) noexcept {
    DeviceMetrics& m = *ports.metrics;
    const DeviceStatus st = device->read(sample);
    readDone = now();
    if (st != DeviceStatus::Ok) {
        fault(FaultKind::ReadFailed, st, readDone);
        return false;
    }
    if (stop.load(std::memory_order_acquire)) {
        return false; // stopped (or the watchdog fired) while inside read(): zero, on leaving
    }
    const std::uint64_t beat = m.heartbeatNs.load(std::memory_order_relaxed);
    if (readDone > beat && readDone - beat > stallNs) {
        // No step for longer than the watchdog allows: the same fault the supervisor gives
        // a hung servo (whichever sees it first), so a step never ends such a gap with force.
        FaultKind none = FaultKind::None;
        if (m.fault.compare_exchange_strong(none, FaultKind::Watchdog)) {
            m.faultNs.store(beat, std::memory_order_relaxed);
        }
        return false;
    }
    if (nonFinite(sample)) {
        fault(FaultKind::NonFinite, DeviceStatus::BadData, readDone);
        return false;
    }
    return true;
}

Vec3 ServoStep::devicePoint(Vec3& v) noexcept {
    // The contact point: the tool tip, position + R * tip (R the stylus orientation, or the
    // device's axes on a device without one), which is the gimbal centre for a zero tip. Its
    // velocity adds the stylus's turn, w x (R * tip), where the device measures w.
    const Vec3 tip = sample.hasOrientation ? sample.orientation * toolTip : toolTip;
    const Vec3 p = transform.positionToWorld(sample.position + tip);
    if (first) {
        lastPosition = p;
        first = false;
    }
    lastStep = p - lastPosition;
    const Vec3 tipTurn =
        sample.hasAngularVelocity ? glm::cross(sample.angularVelocity, tip) : Vec3(0.0);
    v = sample.hasVelocity ? transform.velocityToWorld(sample.velocity + tipTurn)
                           : (p - lastPosition) / dtS;
    lastPosition = p;
    return p;
}

void ServoStep::takeNewEffects() noexcept {
    // Effects the control thread changed since the last step: copied in now. A read that races
    // a newer publish fails and is tried again next step; the servo never waits for it.
    if (ports.effectsPublished->load(std::memory_order_acquire) != effectsApplied) {
        EffectSet fresh;
        std::uint64_t writes = 0;
        if (ports.effects->read(fresh, writes)) {
            haptic.setEffects(fresh);
            effectsApplied = writes;
        }
    }
}

bool ServoStep::run(const std::uint64_t wake, ServoStepProbe* probe) noexcept {
    DeviceMetrics& m = *ports.metrics;
    const std::uint64_t lateness = wake > deadlineNs ? wake - deadlineNs : 0;
    std::uint64_t readDone = 0;
    if (!readDevice(readDone)) {
        return false;
    }
    const WorldSnapshot& snap = ports.world->acquire(*reader);
    Vec3 v{0.0};
    const Vec3 p = devicePoint(v);
    Vec3 external{0.0};
    (void)ports.externalForce->read(external);
    takeNewEffects();
    if (probe != nullptr) {
        probe->endNs[0] = readDone;
        probe->endNs[1] = rt::nowNs();
        haptic.timeStages(&probe->tickStages);
    }
    haptic.placeBodies(ports.bodies, wake);
    const TickOutput out = haptic.tick(snap, p, v, dtS, external, sample);
    if (probe != nullptr) {
        haptic.timeStages(nullptr);
    }
    if (out.newSnapshot) {
        DeviceMetrics::bump(m.snapshotsSeen);
    }
    if (out.hookNonFinite) {
        DeviceMetrics::bump(m.hookNonFinite);
    }
    if (stop.load(std::memory_order_acquire)) {
        return false; // stopped while rendering: leaving writes zero, not this force
    }

    Vec3 force = out.forceN;
    if (consecutiveMisses >= missLimit || lateness >= starvedNs) {
        force = Vec3(0.0);
        haptic.zeroForce();
        DeviceMetrics::bump(m.zeroedForMisses);
    }
    const Vec3 deviceForce = transform.forceToDevice(force);
    const std::uint64_t writeStart = now();
    const DeviceStatus st = device->write(deviceForce);
    const std::uint64_t done = now();
    if (st != DeviceStatus::Ok) {
        fault(FaultKind::WriteFailed, st, done);
        return false;
    }
    if (force == out.forceN) {
        (void)haptic.handBack(dtS); // the hand got the force: the bodies get its reaction
    }

    // Record. A force written after the next deadline missed it (the rule at the end).
    const bool missed = done > deadlineNs + periodNs;
    const std::uint64_t tickNs = done - wake;
    const std::uint64_t ioNs = (readDone - wake) + (done - writeStart);
    m.tickNs.record(tickNs);
    m.latenessNs.record(lateness);
    m.ioNs.record(ioNs);
    if (lateness > lateNs) {
        DeviceMetrics::bump(m.lateWakeups);
    }
    publish(out, p, force, snap.version);
    record(out, deviceForce, wake, tickNs, ioNs, missed);
    ++tick;
    DeviceMetrics::bump(m.ticks);
    m.heartbeatNs.store(done, std::memory_order_relaxed);
    advanceDeadline(done, missed);
    if (probe != nullptr) {
        std::copy(probe->tickStages.begin(), probe->tickStages.end(), probe->endNs.begin() + 2);
        probe->endNs[7] = done;
        probe->endNs[8] = rt::nowNs();
        probe->tick = out;
        probe->devicePointM = p;
        probe->forceN = force;
    }
    return true;
}

void ServoStep::publish(const TickOutput& out, const Vec3& p, const Vec3& force,
                        std::uint64_t version) noexcept {
    DeviceMetrics& m = *ports.metrics;
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
    m.leafAtVersion.store((version & 0xFFFFFFFFu) << 32 | out.deviceLeaf,
                          std::memory_order_relaxed);
    ContactReport report;
    report.tick = tick;
    report.devicePoint = p;
    report.proxy = out.render.proxy;
    report.force = force;
    report.contactCount = out.render.contactCount;
    for (std::uint32_t c = 0; c < out.render.contactCount && c < report.objects.size(); ++c) {
        report.objects[c] = out.render.contacts[c].id;
        report.normals[c] = out.render.contacts[c].normal;
    }
    ports.contacts->publish(report);
}

void ServoStep::record(const TickOutput& out, const Vec3& deviceForce, std::uint64_t wake,
                       std::uint64_t tickNs, std::uint64_t ioNs, bool missed) noexcept {
    if (!recorder) {
        return;
    }
    TraceSample s{};
    s.tick = tick;
    s.timeNs = wake - ports.startNs;
    stateToSample(sample, s);
    s.forceN = deviceForce;
    s.computeNs = static_cast<std::uint32_t>(std::min<std::uint64_t>(tickNs, UINT32_MAX));
    s.ioNs = static_cast<std::uint32_t>(std::min<std::uint64_t>(ioNs, UINT32_MAX));
    s.status = DeviceStatus::Ok;
    s.proxyM = transform.positionToDevice(out.render.proxy);
    s.contactCount = out.render.contactCount;
    s.missedDeadline = missed;
    (void)recorder->push(s);
}

void ServoStep::advanceDeadline(std::uint64_t done, bool missed) noexcept {
    // The next deadline. A step whose force came after the next deadline missed it; skip the
    // slots it overran instead of bursting to catch up, and tell the device they went by.
    deadlineNs += periodNs;
    if (missed) {
        DeviceMetrics::bump(ports.metrics->missedDeadlines);
        consecutiveMisses = std::min(consecutiveMisses + 1, missLimit); // saturates
        const std::uint64_t skipped = (done - deadlineNs) / periodNs + 1;
        deadlineNs += skipped * periodNs;
        device->periodsSkipped(skipped);
    } else {
        consecutiveMisses = 0;
    }
}

std::uint64_t ServoStep::warm() noexcept {
    const WorldSnapshot& snap = ports.world->acquire(*reader); // the step claims it again
    return warmUpTick(snap, haptic.renderer(), std::as_bytes(std::span(this, 1)), lastPosition,
                      lastStep, dtS);
}

void ServoStep::leave() noexcept {
    DeviceMetrics& m = *ports.metrics;
    (void)device->write(Vec3(0.0));
    storeVec(m.forceN, Vec3(0.0));
    // Tell the control thread this hand touches nothing now (a grasp must not hold on to it).
    ContactReport none;
    none.tick = tick;
    none.devicePoint = lastPosition;
    none.proxy = lastPosition;
    ports.contacts->publish(none);
    m.running.store(false, std::memory_order_release);
}

} // namespace hapto
