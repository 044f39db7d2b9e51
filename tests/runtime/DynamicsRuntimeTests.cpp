// The runtime's dynamics thread (DynamicsLoop.cpp), in step mode: its published poses are the
// Dynamics' own, bit for bit; its steps interleave with the servo ticks the same way every run;
// the report carries it; a session with bodies and no device runs; impulses handed to the
// table reach the body once; a non-finite body is stopped, not a crash; a stalled dynamics
// thread is noticed by the supervision, which freezes the bodies for the hands. One threaded case
// ([realtime]) checks the thread starts, steps and stops.

#include "CubeScene.h"
#include "SteppedRig.h"

#include "hapto/dynamics/Dynamics.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/runtime/Session.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <unistd.h>

namespace hapto::test {
namespace {

constexpr ObjectId kBodyId = 9;

/// A 1 cm, 50 g dynamic sphere with its inertia 2/5 m r^2.
SceneObject ball(ObjectId id, Vec3 center, Vec3 velocity = Vec3(0.0)) {
    SceneObject o = makeSphere(id, center, 0.01);
    o.body.dynamic = true;
    o.body.massKg = 0.05;
    o.body.inertia = Mat3(0.4 * 0.05 * 0.01 * 0.01);
    o.body.velocity = velocity;
    return o;
}

/// The cube scene with a ball far from the devices (x = 0.08), stepping at `rateHz`.
Scene sceneWithBall(double rateHz, Vec3 gravity = Vec3(0.0, -9.81, 0.0),
                    std::vector<SceneObject> extra = {}) {
    Scene base = cubeScene();
    std::vector<SceneObject> objects(base.objects().begin(), base.objects().end());
    objects.push_back(ball(kBodyId, Vec3(0.08, 0.1, 0.0)));
    for (SceneObject& o : extra) {
        objects.push_back(std::move(o));
    }
    Scene scene(base.bounds(), std::move(objects));
    ScenePhysics physics;
    physics.rateHz = rateHz;
    physics.gravity = gravity;
    scene.setPhysics(physics);
    return scene;
}

/// The bits of every field a pose publishes but its time.
bool sameBits(const BodyPose& a, const BodyPose& b) {
    const double fa[] = {
        a.center.x,       a.center.y,          a.center.z,          a.rotation.w,
        a.rotation.x,     a.rotation.y,        a.rotation.z,        a.centerOfMass.x,
        a.centerOfMass.y, a.centerOfMass.z,    a.velocity.x,        a.velocity.y,
        a.velocity.z,     a.angularVelocity.x, a.angularVelocity.y, a.angularVelocity.z};
    const double fb[] = {
        b.center.x,       b.center.y,          b.center.z,          b.rotation.w,
        b.rotation.x,     b.rotation.y,        b.rotation.z,        b.centerOfMass.x,
        b.centerOfMass.y, b.centerOfMass.z,    b.velocity.x,        b.velocity.y,
        b.velocity.z,     b.angularVelocity.x, b.angularVelocity.y, b.angularVelocity.z};
    return std::memcmp(fa, fb, sizeof fa) == 0 && a.step == b.step;
}

/// Body i of `d` as the runtime would publish it.
BodyPose alone(const Dynamics& d, std::size_t i) {
    BodyPose p;
    d.objectPose(i, p.center, p.rotation);
    const BodyState& b = d.bodies()[i];
    p.centerOfMass = b.position;
    p.velocity = b.velocity;
    p.angularVelocity = b.angularVelocity;
    p.step = d.stepCount();
    return p;
}

RuntimeOptions notRealtime() {
    RuntimeOptions o;
    o.realtime = false;
    return o;
}

/// A stepped runtime over `scene` with no device.
struct NoDeviceRig {
    ManualClock clock;
    World world;
    Runtime runtime;
    explicit NoDeviceRig(Scene scene)
        : world(std::move(scene), IndexSpec::parse(kDefaultIndexSpec)),
          runtime(world, {}, notRealtime()) {
        world.useClock(clock);
    }
};

std::string fileBytes(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// One stepped 0.2 s session of two scripted devices at 1 kHz and a ball stepped at 500 Hz,
/// its bodies recorded to `trace`; returns the report's JSON.
std::string steppedSession(const std::filesystem::path& trace) {
    SteppedRig rig(2, 1000.0, {}, {}, sceneWithBall(500.0));
    BodyTraceRecorder recorder(trace, rig.runtime->bodyIds(), rig.runtime->dynamicsRateHz());
    SessionOptions options;
    options.durationS = 0.2;
    options.controlPeriodNs = 1'000'000;
    options.steppedClock = &rig.clock;
    options.bodyRecorder = &recorder;
    Session session(*rig.runtime, std::move(options));
    REQUIRE(session.start() == 2);
    REQUIRE(session.run() == SessionEnd::Duration);
    return reportToJson(session.stop());
}

} // namespace

TEST_CASE("a falling body's published pose matches the Dynamics run alone, bit for bit") {
    // Servo ticks at 1 kHz, dynamics at 500 Hz: every other servo tick has a step before it.
    SteppedRig rig(2, 1000.0, {}, {}, sceneWithBall(500.0));
    REQUIRE(rig.runtime->hasDynamics());
    REQUIRE(rig.start() == 2);
    const WorldSnapshot& first = rig.world.current();
    Dynamics reference(first.scene, first.index);
    const BodyPoseTable& table = *rig.runtime->bodyPoses();
    REQUIRE(table.size() == 1);
    CHECK(sameBits(table.read(0), alone(reference, 0))); // step 0: the scene's pose
    for (int ms = 1; ms <= 300; ++ms) {
        rig.runTo(ms);
        while (reference.stepCount() < static_cast<std::uint64_t>(ms / 2)) {
            reference.step();
        }
        const BodyPose p = table.read(0);
        REQUIRE(sameBits(p, alone(reference, 0)));
        REQUIRE(p.timeNs == rig.t0 + p.step * 2'000'000); // the step's deadline
    }
    CHECK(table.read(0).centerOfMass.y < 0.1 - 0.5 * 9.81 * 0.29 * 0.29); // it fell
}

TEST_CASE("two stepped sessions with a dynamic body give byte-identical reports and traces") {
    const auto dir = std::filesystem::temp_directory_path() /
                     ("hapto-dynamics-runtime-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    const std::string a = steppedSession(dir / "a.trace");
    const std::string b = steppedSession(dir / "b.trace");
    CHECK(a == b);
    const std::string ta = fileBytes(dir / "a.trace");
    CHECK(!ta.empty());
    CHECK(ta == fileBytes(dir / "b.trace"));
    const BodyTrace trace = readBodyTrace(dir / "a.trace");
    CHECK(trace.ids == std::vector<ObjectId>{kBodyId});
    CHECK(trace.rateHz == 500.0);
    REQUIRE(trace.samples.size() == 101); // step 0 and 100 steps of 2 ms
    CHECK(trace.samples.front().timeNs == 0);
    CHECK(trace.samples.back().timeNs == 200'000'000);
    CHECK(trace.samples.back().velocity.y < 0.0);
    std::filesystem::remove_all(dir);
}

TEST_CASE("the run report has the dynamics thread and each body") {
    SteppedRig rig(1, 1000.0, {}, {}, sceneWithBall(500.0));
    REQUIRE(rig.start() == 1);
    rig.runTo(100);
    const RunReport r = rig.runtime->report();
    REQUIRE(r.dynamics.has_value());
    CHECK(r.dynamics->rateHz == 500.0);
    CHECK(r.dynamics->steps == 50);
    CHECK(r.dynamics->missedDeadlines == 0);
    CHECK(r.dynamics->stoppedBodies == 0);
    CHECK(r.dynamics->stable);
    REQUIRE(r.dynamics->bodies.size() == 1);
    CHECK(r.dynamics->bodies[0].id == kBodyId);
    CHECK(r.stable == (r.dynamics->stable && r.devices[0].stable));
    const auto json = nlohmann::json::parse(reportToJson(r));
    CHECK(json["dynamics"]["rate_hz"] == 500.0);
    CHECK(json["dynamics"]["steps"] == 50);
    CHECK(json["dynamics"]["stable"] == true);
    CHECK(json["dynamics"]["step_ns"].contains("p999"));
    CHECK(json["dynamics"]["bodies"][0]["id"] == kBodyId);
    CHECK(json["dynamics"]["bodies"][0].contains("deepest_penetration_m"));
    CHECK(json["dynamics"]["bodies"][0].contains("largest_energy_gain_j"));

    SteppedRig plain(1, 1000.0); // no dynamic body: no dynamics in the report
    REQUIRE(plain.start() == 1);
    plain.runTo(10);
    CHECK(!plain.runtime->report().dynamics.has_value());
    CHECK(!nlohmann::json::parse(reportToJson(plain.runtime->report())).contains("dynamics"));
}

/// A stepped session of 0.05 s over the rig.
SessionOptions shortSession(NoDeviceRig& rig) {
    SessionOptions options;
    options.durationS = 0.05;
    options.steppedClock = &rig.clock;
    return options;
}

TEST_CASE("a session with a dynamic body and no device runs to its duration") {
    NoDeviceRig rig(sceneWithBall(1000.0));
    Session session(rig.runtime, shortSession(rig));
    CHECK(session.start() == 0);
    CHECK(session.run() == SessionEnd::Duration);
    const RunReport& r = session.stop();
    REQUIRE(r.dynamics.has_value());
    CHECK(r.dynamics->steps == 50);
    CHECK(r.stable);
    CHECK(!rig.runtime.anyRunning());

    NoDeviceRig none(cubeScene()); // nothing to run: the session ends at once
    Session empty(none.runtime, shortSession(none));
    CHECK(empty.start() == 0);
    CHECK(empty.run() == SessionEnd::NoneRunning);
}

TEST_CASE("an impulse added to the table reaches the body at the next step, exactly once") {
    NoDeviceRig rig(sceneWithBall(1000.0, Vec3(0.0)));
    const WorldSnapshot& first = rig.world.current();
    Dynamics reference(first.scene, first.index);
    const std::uint64_t t0 = rig.clock.nowNs();
    rig.runtime.startStepped(rig.clock);
    BodyPoseTable& table = *rig.runtime.bodyPoses();
    const Vec3 push(1e-3, 0.0, 0.0); // N s
    REQUIRE(table.addImpulse(0, push * 0.25, Vec3(0.0)));
    REQUIRE(table.addImpulse(0, push * 0.75, Vec3(0.0))); // two hands' ticks, summed
    rig.runtime.runUntil(t0 + 10'000'000);
    reference.applyImpulse(0, push, Vec3(0.0));
    for (int k = 0; k < 10; ++k) {
        reference.step();
    }
    const BodyPose p = table.read(0);
    CHECK(sameBits(p, alone(reference, 0)));
    CHECK(p.velocity.x == Approx(push.x / 0.05).epsilon(1e-9)); // once, not twice
    Vec3 left(1.0), leftAngular(1.0);
    table.takeImpulse(0, left, leftAngular);
    CHECK(left == Vec3(0.0)); // nothing left over to be counted again
}

TEST_CASE("a body whose state turns non-finite is stopped and reported, the others go on") {
    std::vector<SceneObject> extra;
    extra.push_back(
        ball(11, Vec3(-0.08, 0.1, 0.0), Vec3(std::numeric_limits<double>::infinity(), 0.0, 0.0)));
    NoDeviceRig rig(sceneWithBall(1000.0, Vec3(0.0, -9.81, 0.0), std::move(extra)));
    const std::uint64_t t0 = rig.clock.nowNs();
    rig.runtime.startStepped(rig.clock);
    rig.runtime.runUntil(t0 + 20'000'000);
    const BodyPoseTable& table = *rig.runtime.bodyPoses();
    REQUIRE(rig.runtime.bodyIds()[1] == 11);
    const BodyPose stopped = table.read(1);
    CHECK(stopped.velocity == Vec3(0.0));
    CHECK(std::isfinite(stopped.centerOfMass.x));
    CHECK(stopped.step == 20);
    CHECK(table.read(0).velocity.y < 0.0); // the other body still falls
    const RunReport r = rig.runtime.report();
    REQUIRE(r.dynamics.has_value());
    CHECK(r.dynamics->stoppedBodies == 1);
    CHECK(r.dynamics->bodies[1].stopped);
    CHECK(!r.dynamics->bodies[0].stopped);
    CHECK(!r.dynamics->stable);
    CHECK(!r.stable);
}

/// A stepped runtime with no device whose watchdog bound is 20 ms + one 1 ms period.
struct StallRig {
    ManualClock clock;
    World world;
    Runtime runtime;
    std::uint64_t t0 = 0;
    static RuntimeOptions options() {
        RuntimeOptions o = notRealtime();
        o.stallTimeoutNs = 20'000'000;
        return o;
    }
    explicit StallRig(Scene scene)
        : world(std::move(scene), IndexSpec::parse(kDefaultIndexSpec)),
          runtime(world, {}, options()) {
        world.useClock(clock);
        t0 = clock.nowNs();
        runtime.startStepped(clock);
    }
    std::uint64_t at(double ms) const { return t0 + static_cast<std::uint64_t>(ms * 1e6); }
};

TEST_CASE("a stalled dynamics thread is noticed by the supervision and its bodies are frozen") {
    // No gravity, the ball drifts at 0.1 m/s: a servo extrapolating its pose would move it.
    std::vector<SceneObject> extra;
    extra.push_back(ball(11, Vec3(-0.08, 0.1, 0.0), Vec3(0.1, 0.0, 0.0)));
    StallRig rig(sceneWithBall(1000.0, Vec3(0.0), std::move(extra)));
    const BodyPoseTable& table = *rig.runtime.bodyPoses();
    rig.runtime.runUntil(rig.at(10)); // 10 steps, the state due at 10 ms
    const BodyPose before = table.read(1);
    REQUIRE(before.step == 10);
    REQUIRE(before.velocity.x == 0.1);
    // The dynamics thread stops stepping (nothing runs it), the supervision goes on: a state
    // 21 ms old is within the bound, 22 ms is not.
    for (int ms = 11; ms <= 31; ++ms) {
        rig.runtime.supervise(rig.at(ms));
    }
    CHECK(rig.runtime.report().dynamics->fault.empty());
    CHECK(table.read(1).velocity.x == 0.1);
    rig.runtime.supervise(rig.at(32));
    const BodyPose frozen = table.read(1);
    CHECK(frozen.velocity == Vec3(0.0));
    CHECK(frozen.angularVelocity == Vec3(0.0));
    CHECK(frozen.centerOfMass == before.centerOfMass); // where it last was, not extrapolated
    CHECK(frozen.step == 10);
    CHECK(frozen.timeNs == before.timeNs);
    const RunReport r = rig.runtime.report();
    REQUIRE(r.dynamics.has_value());
    CHECK(r.dynamics->fault ==
          "watchdog: no step for 22.0 ms (bound 21.0 ms); bodies frozen at step 10");
    CHECK(r.dynamics->faultS == Approx(0.032).margin(1e-12));
    CHECK(!r.dynamics->stable);
    CHECK(!r.stable);
    const auto json = nlohmann::json::parse(reportToJson(r));
    CHECK(json["dynamics"]["fault"] == r.dynamics->fault);

    // The thread comes back: it publishes nothing, steps no more, drops the hands' impulses.
    REQUIRE(rig.runtime.bodyPoses()->addImpulse(1, Vec3(1e-3, 0.0, 0.0), Vec3(0.0)));
    rig.runtime.runUntil(rig.at(100));
    CHECK(sameBits(table.read(1), frozen));
    CHECK(table.read(0).velocity == Vec3(0.0));
    CHECK(rig.runtime.report().dynamics->steps == 10);
    Vec3 left(1.0), leftAngular(1.0);
    rig.runtime.bodyPoses()->takeImpulse(1, left, leftAngular);
    CHECK(left == Vec3(0.0));
}

TEST_CASE("a dynamics thread on time is never frozen, and devices stay up when it stalls") {
    // On time: a 100 Hz dynamics (10 ms period) and 1 kHz servos for 0.3 s, supervised every
    // servo tick: the published state is at most one period old, well within the bound.
    RuntimeOptions options;
    options.stallTimeoutNs = 20'000'000;
    SteppedRig rig(2, 1000.0, {}, options, sceneWithBall(100.0));
    REQUIRE(rig.start() == 2);
    rig.runTo(300);
    RunReport r = rig.runtime->report();
    CHECK(r.dynamics->fault.empty());
    CHECK(r.dynamics->steps == 30);
    // Stalled: the servos tick and are supervised, the dynamics is not stepped.
    for (int ms = 301; ms <= 340; ++ms) {
        for (std::size_t i = 0; i < 2; ++i) {
            (void)rig.runtime->step(i, rig.t0 + static_cast<std::uint64_t>(ms) * 1'000'000);
        }
        rig.runtime->supervise(rig.t0 + static_cast<std::uint64_t>(ms) * 1'000'000);
    }
    r = rig.runtime->report();
    CHECK(!r.dynamics->fault.empty());
    CHECK(r.dynamics->faultS == Approx(0.331).margin(1e-12)); // 300 ms state + 30 ms bound + 1
    CHECK(rig.runtime->bodyPoses()->read(0).velocity == Vec3(0.0));
    for (const DeviceReport& d : r.devices) {
        CHECK(d.fault.empty()); // the hands go on, feeling the body where it stopped
        CHECK(d.ticks == 340);
    }
}

TEST_CASE("the dynamics thread steps on the wall clock and stops with the runtime", "[realtime]") {
    World world(sceneWithBall(1000.0), IndexSpec::parse(kDefaultIndexSpec));
    Runtime runtime(world, {}, notRealtime());
    runtime.start();
    CHECK(runtime.anyRunning());
    const BodyPoseTable& table = *runtime.bodyPoses();
    for (int i = 0; i < 2000 && table.read(0).step < 5; ++i) {
        usleep(1000);
    }
    CHECK(table.read(0).step >= 5);
    runtime.stop();
    CHECK(!runtime.anyRunning());
    const std::uint64_t after = table.read(0).step;
    usleep(5000);
    CHECK(table.read(0).step == after); // no step after stop()
    REQUIRE(runtime.report().dynamics.has_value());
    CHECK(runtime.report().dynamics->steps == after);
}

} // namespace hapto::test
