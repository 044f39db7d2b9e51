// The servo loop: a servo thread sleeps to each absolute deadline and runs its device's
// ServoStep (ServoStep.h: the step and its fault rules, written once); the step mode runs the
// same step from the caller's thread at the times the caller gives (step). Also the warm-up a
// thread runs before its deadline (warmUpTick, ServoLoop.h). Nothing below a servo thread's
// loop entry allocates, locks, throws or makes a syscall beyond the device's own I/O, the clock
// and the sleep.

#include "hapto/runtime/ServoLoop.h"

#include "Channel.h"
#include "DynamicsChannel.h"

#include "hapto/core/CpuPause.h"
#include "hapto/core/Finite.h"

#include <algorithm>
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
    ServoStep& s = ch.servo;
    s.ports.world = &mWorld;
    s.ports.metrics = &ch.metrics;
    s.ports.contacts = &ch.contacts;
    s.ports.externalForce = &ch.externalForce;
    s.ports.effects = &ch.effects;
    s.ports.effectsPublished = &ch.effectsPublished;
    s.ports.clock = mClock;
    s.ports.bodies = mDynamics ? &mDynamics->poses : nullptr;
    s.ports.startNs = mStartNs;
    s.start(nowNs);
}

std::uint64_t Runtime::warm(Channel& ch) noexcept {
    const std::uint64_t sum = ch.servo.warm();
    asm volatile("" : : "r"(sum) : "memory"); // what was read counts as used
    return sum;
}

void Runtime::leaveServo(Channel& ch) noexcept {
    ch.servo.leave();
}

void Runtime::startThread(Channel& ch) {
    startServo(ch, now());
    ch.record.thread = std::thread([this, &ch] { servoMain(ch); });
}

void Runtime::servoMain(Channel& ch) {
    // Set-up: may allocate (the real-time grant's note), nothing below the loop entry does.
    ChannelRecord& c = ch.record;
    rt::nameCurrentThread("hapto-servo");
    if (mOptions.realtime) {
        c.grant = rt::makeCurrentThreadRealtime(mOptions.fifoPriority, c.cpu);
    } else {
        rt::tightenTimerSlack();
        c.grant.note = "real-time scheduling not requested";
    }
    DeviceMetrics& m = ch.metrics;
    m.threadId.store(static_cast<int>(gettid()), std::memory_order_relaxed);
    m.realtime.store(c.grant.fifo, std::memory_order_relaxed);
    ServoStep& s = ch.servo;
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
        if (!ch.servo.run(rt::nowNs())) {
            break;
        }
    }
    leaveServo(ch);
    rt::setInServoLoop(false);
}

bool Runtime::step(std::size_t i, std::uint64_t nowNs) {
    requireStepped("step");
    Channel& ch = *mChannels.at(i);
    ServoStep& s = ch.servo;
    if (!ch.metrics.running.load(std::memory_order_acquire) || nowNs < s.deadlineNs) {
        return false; // not running, or asleep until its deadline
    }
    mClock->set(nowNs);
    rt::setInServoLoop(true);
    if (mWarmUpNs > 0) {
        (void)warm(ch); // the step mode has no sleep to wake from; it warms up so tests cover it
    }
    const bool ticked = !s.stop.load(std::memory_order_acquire) && s.run(nowNs);
    if (!ticked) {
        leaveServo(ch);
    }
    rt::setInServoLoop(false);
    mClock->set(nowNs); // the other devices' threads did not wait for this one
    return ticked;
}

void Runtime::stepAll(std::uint64_t nowNs) {
    requireStepped("stepAll");
    (void)stepDynamicsIfDue(nowNs); // a step due at t before the servo ticks due at t
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
        // The next event: a running servo's deadline, a recovering device's reopen time, or
        // the dynamics' next step.
        std::uint64_t next = std::max(nextDynamicsDeadlineNs(), at);
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
