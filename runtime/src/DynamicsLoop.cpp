// The dynamics thread: one step of every dynamic body at each of its deadlines (1 /
// ScenePhysics::rateHz), threaded or stepped. Design note: a step takes each body's impulses
// from the BodyPoseTable (what the servo threads handed back since the last step) into the
// Dynamics, steps it, and publishes every body's pose into the table for the servo threads,
// the control thread and the view, timed at the step's deadline on the runtime's clock. A
// body whose state turns non-finite is stopped: its last finite pose is published again with
// zero velocities, its impulses are dropped, and the report counts it; nothing crashes.
// Steps are never skipped: a late step runs at once and the next ones follow back to back
// until they are on time again, so the bodies' time is the session's. Invariants: below the
// loop's entry nothing allocates, locks, logs or throws; the step mode runs the same step, at
// each deadline before the servo ticks due then (ServoLoop.cpp's runUntil and stepAll).
// Each publication is made under the table's publisher token (DynamicsChannel.h): once the
// watchdog has frozen the bodies the step publishes nothing, steps no more and drops the
// hands' impulses.

#include "Channel.h"
#include "DynamicsChannel.h"

#include "hapto/core/Finite.h"

#include <algorithm>
#include <cmath>

namespace hapto {

Runtime::DynamicsChannel::DynamicsChannel(const WorldSnapshot& snapshot,
                                          const RuntimeOptions& options)
    : dynamics(std::make_unique<Dynamics>(snapshot.scene, snapshot.index)),
      poses(dynamics->bodyCount()),
      records(std::make_unique<DynamicsBodyRecord[]>(dynamics->bodyCount())),
      rateHz(snapshot.scene->physics().rateHz),
      periodNs(static_cast<std::uint64_t>(std::llround(1e9 / rateHz))),
      lateNs(
          static_cast<std::uint64_t>(options.lateWakeupFraction * static_cast<double>(periodNs))),
      stallBoundNs(options.stallTimeoutNs + periodNs) {
    for (const BodyState& b : dynamics->bodies()) {
        ids.push_back(b.id);
    }
}

BodyPose bodyPoseOf(const Dynamics& d, std::size_t i, std::uint64_t timeNs) noexcept {
    const BodyState& b = d.bodies()[i];
    BodyPose p;
    d.objectPose(i, p.center, p.rotation);
    p.centerOfMass = b.position;
    p.velocity = b.velocity;
    p.angularVelocity = b.angularVelocity;
    p.timeNs = timeNs;
    p.step = d.stepCount();
    p.sleeping = b.sleeping;
    return p;
}

namespace {

bool finitePose(const BodyPose& p) noexcept {
    return finite(p.center) && finite(p.centerOfMass) && finite(p.velocity) &&
           finite(p.angularVelocity) && std::isfinite(p.rotation.w) &&
           std::isfinite(p.rotation.x) && std::isfinite(p.rotation.y) &&
           std::isfinite(p.rotation.z);
}

BodyTraceSample sampleOf(const BodyPose& p, std::uint32_t body, std::uint64_t sinceStartNs) {
    BodyTraceSample s;
    s.timeNs = sinceStartNs;
    s.body = body;
    s.centerOfMass = p.centerOfMass;
    s.rotation = p.rotation;
    s.velocity = p.velocity;
    s.angularVelocity = p.angularVelocity;
    return s;
}

} // namespace

void Runtime::publishBodies(DynamicsChannel& dc, std::uint64_t timeNs) noexcept {
    const Dynamics& d = *dc.dynamics;
    for (std::size_t i = 0; i < d.bodyCount(); ++i) {
        DynamicsBodyRecord& r = dc.records[i];
        BodyPose p = bodyPoseOf(d, i, timeNs);
        if (r.stopped.load(std::memory_order_relaxed) || !finitePose(p)) {
            if (!r.stopped.exchange(true, std::memory_order_relaxed)) {
                dc.metrics.stoppedBodies.fetch_add(1, std::memory_order_relaxed);
            }
            p = r.lastGood; // where it last was, at rest
            p.velocity = Vec3(0.0);
            p.angularVelocity = Vec3(0.0);
            p.timeNs = timeNs;
            p.step = d.stepCount();
        } else {
            r.lastGood = p;
        }
        dc.poses.publish(i, p);
        const BodyStats& st = d.stats(i);
        r.deepestPenetrationM.store(st.deepestPenetrationM, std::memory_order_relaxed);
        r.largestEnergyGainJ.store(st.largestEnergyGainJ, std::memory_order_relaxed);
        if (dc.recorder) {
            (void)dc.recorder->push(sampleOf(p, static_cast<std::uint32_t>(i), timeNs - mStartNs));
        }
    }
}

namespace {

/// Takes every body's accumulated impulse and torsional budget into the Dynamics (a stopped
/// body's, or every body's once frozen, is taken and dropped).
void takeImpulses(Dynamics& d, BodyPoseTable& poses, const DynamicsBodyRecord* records,
                  bool frozen) noexcept {
    for (std::size_t i = 0; i < d.bodyCount(); ++i) {
        Vec3 linear(0.0), angular(0.0);
        poses.takeImpulse(i, linear, angular);
        const Mat3 torsion = poses.takeTorsion(i); // the hands' torsional friction budget
        if (!frozen && !records[i].stopped.load(std::memory_order_relaxed)) {
            d.applyImpulse(i, linear, angular);
            d.applyHandTorsion(i, torsion); // after the impulses: it stops the spin they leave
        }
    }
}

} // namespace

bool Runtime::publishUnlessFrozen(DynamicsChannel& dc, std::uint64_t timeNs) noexcept {
    DynamicsMetrics& m = dc.metrics;
    int expected = DynamicsMetrics::kFree;
    if (!m.publisher.compare_exchange_strong(expected, DynamicsMetrics::kStepping,
                                             std::memory_order_acquire)) {
        return false; // frozen by the watchdog (no one else ever holds it)
    }
    publishBodies(dc, timeNs);
    m.stateNs.store(timeNs, std::memory_order_relaxed);
    m.publisher.store(DynamicsMetrics::kFree, std::memory_order_release);
    return true;
}

void Runtime::runDynamicsStep(DynamicsChannel& dc, std::uint64_t wakeNs) noexcept {
    DynamicsMetrics& m = dc.metrics;
    const std::uint64_t deadline = dc.deadlineNs;
    dc.deadlineNs = deadline + dc.periodNs; // never skipped: the bodies' time is the session's
    const bool frozen = m.publisher.load(std::memory_order_acquire) == DynamicsMetrics::kFrozen;
    takeImpulses(*dc.dynamics, dc.poses, dc.records.get(), frozen);
    if (frozen) {
        return; // the hands see the frozen poses to the end of the session
    }
    dc.dynamics->step();
    (void)publishUnlessFrozen(dc, deadline); // the state is the one due at the step's deadline
    const std::uint64_t done = now();
    const std::uint64_t lateness = wakeNs > deadline ? wakeNs - deadline : 0;
    m.stepNs.record(done > wakeNs ? done - wakeNs : 0);
    m.latenessNs.record(lateness);
    DeviceMetrics::bump(m.steps);
    if (lateness > dc.lateNs) {
        DeviceMetrics::bump(m.lateWakeups);
    }
    if (done > deadline + dc.periodNs) {
        DeviceMetrics::bump(m.missedDeadlines);
    }
}

void Runtime::startDynamics(std::uint64_t nowNs) {
    DynamicsChannel& dc = *mDynamics;
    dc.deadlineNs = nowNs + dc.periodNs;
    (void)publishUnlessFrozen(dc, nowNs); // step 0: the scene's poses, before any servo reads
    dc.metrics.running.store(true, std::memory_order_release);
    if (!mClock) {
        dc.thread = std::thread([this] { dynamicsMain(); });
    }
}

void Runtime::dynamicsMain() {
    // Set-up: may allocate (the grant's note); nothing below the loop's entry does.
    DynamicsChannel& dc = *mDynamics;
    rt::nameCurrentThread("hapto-dynamics");
    if (mOptions.realtime) {
        // Below the servo threads: a servo tick preempts a dynamics step, never the reverse.
        dc.grant = rt::makeCurrentThreadRealtime(std::max(1, mOptions.fifoPriority - 1), -1);
    } else {
        rt::tightenTimerSlack();
        dc.grant.note = "real-time scheduling not requested";
    }
    dc.metrics.realtime.store(dc.grant.fifo, std::memory_order_relaxed);
    rt::setInServoLoop(true);
    while (!dc.stop.load(std::memory_order_acquire)) {
        rt::sleepUntilNs(dc.deadlineNs, 0);
        runDynamicsStep(dc, rt::nowNs());
    }
    rt::setInServoLoop(false);
}

bool Runtime::stepDynamicsIfDue(std::uint64_t nowNs) {
    if (!mDynamics || !mDynamics->metrics.running.load(std::memory_order_acquire) ||
        nowNs < mDynamics->deadlineNs) {
        return false;
    }
    mClock->set(nowNs);
    rt::setInServoLoop(true);
    runDynamicsStep(*mDynamics, nowNs);
    rt::setInServoLoop(false);
    mClock->set(nowNs); // the servo threads did not wait for the dynamics thread
    return true;
}

void Runtime::stopDynamics() {
    if (!mDynamics) {
        return;
    }
    mDynamics->stop.store(true, std::memory_order_release);
    if (mDynamics->thread.joinable()) {
        mDynamics->thread.join();
    }
    mDynamics->metrics.running.store(false, std::memory_order_release);
    if (!mDynamics->grant.note.empty() &&
        mRealtimeNote.find(mDynamics->grant.note) == std::string::npos) {
        mRealtimeNote += (mRealtimeNote.empty() ? "" : "; ") + mDynamics->grant.note;
    }
}

bool Runtime::hasDynamics() const {
    return mDynamics != nullptr;
}

const BodyPoseTable* Runtime::bodyPoses() const {
    return mDynamics ? &mDynamics->poses : nullptr;
}

BodyPoseTable* Runtime::bodyPoses() {
    return mDynamics ? &mDynamics->poses : nullptr;
}

std::span<const ObjectId> Runtime::bodyIds() const {
    return mDynamics ? std::span<const ObjectId>(mDynamics->ids) : std::span<const ObjectId>();
}

double Runtime::dynamicsRateHz() const {
    return mDynamics ? mDynamics->rateHz : 0.0;
}

void Runtime::setBodyRecorder(BodyTraceRecorder* recorder) {
    if (mStarted) {
        throw std::logic_error("Runtime::setBodyRecorder: before start() or startStepped()");
    }
    if (mDynamics) {
        mDynamics->recorder = recorder;
    }
}

std::uint64_t Runtime::nextDynamicsDeadlineNs() const {
    return mDynamics && mDynamics->metrics.running.load(std::memory_order_acquire)
               ? mDynamics->deadlineNs
               : UINT64_MAX;
}

} // namespace hapto
