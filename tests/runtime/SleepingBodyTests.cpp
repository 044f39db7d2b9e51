// Sleeping bodies in the static index (World::setRestingBodies, Runtime::maintain, the servo's
// BodyCoupling), in step mode: a body asleep for the rest delay re-enters the index at its rest
// pose and is rendered from it exactly as a static object there; a touch wakes it in the next
// dynamics step with every impulse of the hand accounted for; waking publishes nothing on the
// servo or dynamics path (the snapshot changes only in maintain()), which allocates nothing; a
// later maintain() takes the body out over the same index; stepped runs are byte-identical; and
// 20 sleeping plates within one tick's reach are all felt, where only 16 awake ones are placed.
// This binary replaces the global operator new (tests/support/CountingNew.h) to count the
// allocations made inside servo ticks and dynamics steps.

#include "CountingNew.h"
#include "MeshShapes.h"
#include "ScriptedDevice.h"

#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/HapticTick.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/Runtime.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

namespace {
[[maybe_unused]] const bool gFlagsServo = [] {
    hapto::test::gFlagAllocation = []() noexcept { return hapto::rt::inServoLoop(); };
    return true;
}();
} // namespace

namespace hapto::test {
namespace {

constexpr ObjectId kBoxId = 9;
constexpr double kMassKg = 0.05;
constexpr double kHalfM = 0.02;

Material stiff() {
    Material m;
    m.stiffness = 500.0;
    return m;
}

/// No gravity, dynamics at 1 kHz.
void weightless(Scene& scene) {
    ScenePhysics physics;
    physics.rateHz = 1000.0;
    physics.gravity = Vec3(0.0);
    scene.setPhysics(physics);
}

/// The 4 cm body: a box, or the same box as a closed 12-triangle mesh.
SceneObject shapeAt(bool mesh, const Vec3& center, const Quat& rotation = Quat(1, 0, 0, 0)) {
    return mesh ? makeMesh(kBoxId, center, boxMesh(Vec3(kHalfM)), rotation, stiff())
                : makeBox(kBoxId, center, Vec3(kHalfM), rotation, stiff());
}

/// A 4 cm, 50 g dynamic box (or box mesh) at the origin drifting at 1 mm/s along x (below the
/// sleep speed, 2 mm/s), so it falls asleep after 0.5 s about 0.5 mm from where it started.
Scene driftingBox(bool mesh = false) {
    SceneObject box = shapeAt(mesh, Vec3(0.0));
    box.body.dynamic = true;
    box.body.massKg = kMassKg;
    box.body.inertia = Mat3(kMassKg * (2.0 * kHalfM) * (2.0 * kHalfM) / 6.0);
    box.body.velocity = Vec3(1e-3, 0.0, 0.0);
    Scene scene(Aabb{Vec3(-0.125), Vec3(0.125)}, {box});
    weightless(scene);
    return scene;
}

/// Away from the box until tick 800, then in to 1 mm inside its +x face (rest pose x about
/// 0.0005) over 20 ticks, and held there: the box is pushed off along -x.
ScriptedDevice::Path pushAt800() {
    return [](std::uint64_t t) {
        const double s = t < 800 ? 0.0 : std::min(1.0, static_cast<double>(t - 800) / 20.0);
        return Vec3(0.06 + s * (0.0195 - 0.06), 0.0, 0.0);
    };
}

/// A stepped session of one scripted hand (1 kHz) over the drifting box; `history` keeps
/// every force written (the device's history allocates on the servo path: off for the
/// allocation test).
struct SleepRig {
    ManualClock clock;
    World world;
    ScriptedDevice* hand = nullptr;
    std::unique_ptr<Runtime> runtime;
    std::uint64_t t0 = 0;

    explicit SleepRig(bool history, bool mesh = false)
        : world(driftingBox(mesh), IndexSpec::parse(kDefaultIndexSpec)) {
        world.useClock(clock);
        auto d = std::make_unique<ScriptedDevice>("hand", pushAt800());
        if (history) {
            d->useClock(&clock);
        }
        hand = d.get();
        std::vector<RuntimeDevice> devices;
        devices.push_back({std::move(d), scriptedConfig(0, 1000.0), nullptr});
        RuntimeOptions options;
        options.realtime = false;
        runtime = std::make_unique<Runtime>(world, std::move(devices), options);
        t0 = clock.nowNs();
        REQUIRE(runtime->startStepped(clock) == 1);
    }
    /// Runs to t0 + ms (servo ticks and dynamics steps) and checks that they published no
    /// snapshot: the world changes only in maintain().
    void runTo(int ms) {
        const std::uint64_t version = world.current().version;
        runtime->runUntil(t0 + static_cast<std::uint64_t>(ms) * 1'000'000);
        REQUIRE(world.current().version == version);
    }
    BodyPose body() const { return runtime->bodyPoses()->read(0); }
};

/// The bits of a pose's object pose and velocities.
std::vector<double> bitsOf(const BodyPose& p) {
    return {p.center.x,         p.center.y,   p.center.z,          p.rotation.w,
            p.rotation.x,       p.rotation.y, p.rotation.z,        p.velocity.x,
            p.velocity.y,       p.velocity.z, p.angularVelocity.x, p.angularVelocity.y,
            p.angularVelocity.z};
}

/// One tick from outside (p + 2 cm along `out`) to p, of a fresh tick over `snapshot`.
TickOutput touch(const WorldSnapshot& snapshot, BodyPoseTable* table, std::uint64_t nowNs,
                 const Vec3& p, const Vec3& out) {
    auto tick = std::make_unique<HapticTick>();
    tick->placeBodies(table, nowNs);
    (void)tick->tick(snapshot, p + 0.02 * out, Vec3(0.0), 1e-3, Vec3(0.0));
    tick->placeBodies(table, nowNs);
    return tick->tick(snapshot, p, Vec3(0.0), 1e-3, Vec3(0.0));
}

/// a and b agree to 1e-12 of their size, component by component.
bool close(const Vec3& a, const Vec3& b) {
    for (int k = 0; k < 3; ++k) {
        if (std::abs(a[k] - b[k]) > 1e-12 * (1.0 + std::abs(b[k]))) {
            return false;
        }
    }
    return true;
}

} // namespace

TEST_CASE("a body asleep for the rest delay enters the static index at its rest pose and a "
          "woken one leaves it over the same index") {
    SleepRig rig(false);
    const std::uint32_t slot = rig.world.current().dynamic.at(0);
    int sleepMs = 0;
    for (int ms = 1; ms <= 700 && sleepMs == 0; ++ms) {
        rig.runTo(ms);
        rig.runtime->maintain();
        sleepMs = rig.body().sleeping ? ms : 0;
    }
    REQUIRE(sleepMs >= 500); // 0.5 s below the sleep speed
    // Not yet asleep for the world's rest delay (100 ms) at sleepMs + 99; indexed at + 100.
    for (int ms = sleepMs + 1; ms <= sleepMs + 99; ++ms) {
        rig.runTo(ms);
        rig.runtime->maintain();
    }
    REQUIRE(rig.body().sleeping);
    CHECK(rig.world.restingIndexed() == 0);
    CHECK(rig.world.current().scene->object(slot).body.dynamic);
    rig.runTo(sleepMs + 100);
    rig.runtime->maintain();
    const WorldSnapshot& rested = rig.world.current();
    REQUIRE(rested.restingCount == 1);
    REQUIRE(rested.dynamic.size() == 1);
    CHECK(rested.dynamic[0] == slot); // body 0 keeps its entry
    const BodyPose pose = rig.body();
    const SceneObject& o = rested.scene->object(slot);
    CHECK_FALSE(o.body.dynamic); // a static object of this snapshot's scene
    CHECK(o.center == pose.center);
    CHECK(o.center.x > 4e-4); // it drifted before it slept: not its starting pose
    CHECK(rested.rest[0].center == pose.center);
    CHECK(rested.rest[0].rotation == pose.rotation);
    CHECK(rested.restingBodyAt(slot) == 0);
    CHECK(rig.world.buildsPublished() == 2);
    const SpatialIndex* index = rested.index.get();

    // Pushed from tick 800: the first touch wakes it, and the next maintain() takes it out of
    // the index by a snapshot that shares the index (no build).
    int wokenMs = 0;
    for (int ms = sleepMs + 101; ms <= 900 && wokenMs == 0; ++ms) {
        rig.runTo(ms);
        if (!rig.body().sleeping) {
            wokenMs = ms;
        }
        rig.runtime->maintain();
    }
    REQUIRE(wokenMs > 800);
    CHECK(rig.world.restingIndexed() == 0);
    CHECK(rig.world.current().scene->object(slot).body.dynamic);
    CHECK(rig.world.current().index.get() == index);
    CHECK(rig.world.buildsPublished() == 2);
}

TEST_CASE("a sleeping body is rendered from the index exactly as a static object at its rest "
          "pose",
          "[threads]") {
    const bool mesh = GENERATE(false, true);
    INFO((mesh ? "box mesh" : "box"));
    SleepRig rig(false, mesh);
    for (int ms = 1; ms <= 700; ++ms) {
        rig.runTo(ms);
        rig.runtime->maintain();
    }
    const WorldSnapshot& rested = rig.world.current();
    REQUIRE(rested.restingCount == 1);
    const BodyPose pose = rig.body();
    REQUIRE(pose.sleeping);
    // The same box, static at the rest pose, in a world of its own.
    Scene alone(Aabb{Vec3(-0.125), Vec3(0.125)}, {shapeAt(mesh, pose.center, pose.rotation)});
    const World reference(std::move(alone), IndexSpec::parse(kDefaultIndexSpec));
    BodyPoseTable* table = rig.runtime->bodyPoses();
    const std::uint64_t now = rig.clock.nowNs();
    const std::pair<Vec3, Vec3> faces[] = {{Vec3(1, 0, 0), Vec3(0, 0.005, 0.003)},
                                           {Vec3(0, 1, 0), Vec3(0.004, 0, -0.01)},
                                           {Vec3(0, 0, -1), Vec3(-0.012, 0.002, 0)}};
    for (const auto& [out, along] : faces) {
        const Vec3 p = pose.center + (kHalfM - 1e-3) * out + along; // 1 mm inside the face
        const TickOutput fromIndex = touch(rested, table, now, p, out);
        const TickOutput staticBox = touch(reference.current(), nullptr, now, p, out);
        CHECK(fromIndex.bodiesPlaced == 0); // not from the pose table
        REQUIRE(fromIndex.render.contactCount == 1);
        CHECK(fromIndex.render.contacts[0].id == kBoxId);
        CHECK(std::memcmp(&fromIndex.render.proxy, &staticBox.render.proxy, sizeof(Vec3)) == 0);
        CHECK(std::memcmp(&fromIndex.forceN, &staticBox.forceN, sizeof(Vec3)) == 0);
        // 500 N/m x 1 mm, outward (the renderer's skin adds 5 uN)
        CHECK(glm::length(fromIndex.forceN - 0.5 * out) < 1e-5);
        // Its reaction waits for the sleeping body, as a placed body's does.
        CHECK(close(fromIndex.reactionN, fromIndex.forceN));
    }
}

TEST_CASE("a woken body still in the index is felt where the table has it and not at its rest "
          "pose",
          "[threads]") {
    const bool mesh = GENERATE(false, true);
    INFO((mesh ? "box mesh" : "box"));
    SleepRig rig(false, mesh);
    for (int ms = 1; ms <= 700; ++ms) {
        rig.runTo(ms);
        rig.runtime->maintain();
    }
    REQUIRE(rig.world.restingIndexed() == 1);
    const Vec3 rest = rig.body().center;
    // An application's push (-x, 0.1 m/s) wakes it; no maintain() for 20 ms: the snapshot
    // still holds it in the index at its rest pose.
    REQUIRE(rig.runtime->bodyPoses()->addImpulse(0, Vec3(-0.1 * kMassKg, 0.0, 0.0), Vec3(0.0)));
    for (int ms = 701; ms <= 720; ++ms) {
        rig.runTo(ms);
    }
    const WorldSnapshot& stale = rig.world.current();
    REQUIRE(stale.restingCount == 1);
    const BodyPose now = rig.body();
    REQUIRE_FALSE(now.sleeping);
    REQUIRE(now.center.x < rest.x - 0.0015); // about 2 mm away by now
    BodyPoseTable* table = rig.runtime->bodyPoses();
    const Vec3 out(1, 0, 0);
    // 1 mm inside where its +x face was: 1 mm outside it now, nothing there.
    const TickOutput gone =
        touch(stale, table, rig.clock.nowNs(), rest + (kHalfM - 1e-3) * out, out);
    CHECK(gone.render.contactCount == 0);
    CHECK(gone.forceN == Vec3(0.0));
    // Where its +x face is: felt, placed from the table.
    const TickOutput there =
        touch(stale, table, rig.clock.nowNs(), now.center + (kHalfM - 1e-3) * out, out);
    CHECK(there.bodiesPlaced == 1);
    REQUIRE(there.render.contactCount >= 1);
    CHECK(there.render.contacts[0].id == kBoxId);
    // 500 N/m x 1 mm, less the coupling damping k h on its 0.1 m/s going away (0.05 N).
    CHECK(there.forceN.x > 0.4);
    // The next upkeep takes it out of the index.
    rig.runtime->maintain();
    CHECK(rig.world.restingIndexed() == 0);
}

TEST_CASE("a touch wakes a sleeping body within one dynamics step and no hand impulse is lost "
          "across the switch") {
    SleepRig rig(true);
    int touchMs = 0;
    int wokenMs = 0;
    bool indexedAtTouch = false;
    for (int ms = 1; ms <= 1200; ++ms) {
        const bool asleep = rig.body().sleeping;
        rig.runTo(ms);
        if (touchMs == 0 && rig.hand->lastForce() != Vec3(0.0)) {
            touchMs = ms;
            indexedAtTouch = rig.world.current().restingCount == 1 && asleep;
        }
        if (touchMs != 0 && wokenMs == 0 && !rig.body().sleeping) {
            wokenMs = ms;
        }
        rig.runtime->maintain();
    }
    REQUIRE(touchMs > 800);
    CHECK(indexedAtTouch);         // the first touch was rendered from the index
    CHECK(wokenMs == touchMs + 1); // the step after the touching tick
    // Momentum: everything the hand was sent reached the body (no gravity, no other
    // contact), to the table's 1e-12 N s a tick.
    Vec3 sentNs(0.0);
    std::size_t touching = 0;
    for (const ScriptedDevice::Written& w : rig.hand->forces()) {
        sentNs += w.force * 1e-3;
        touching += w.force != Vec3(0.0) ? 1 : 0;
    }
    CHECK(rig.hand->lastForce() == Vec3(0.0)); // the box has left the hand
    REQUIRE(touching > 0);
    const Vec3 momentum = kMassKg * rig.body().velocity;
    CHECK(momentum.x < -1e-4);
    for (int k = 0; k < 3; ++k) {
        CHECK(std::abs(momentum[k] + sentNs[k]) <= 1e-12 * static_cast<double>(touching) + 1e-15);
    }
}

TEST_CASE("sleeping, indexing, waking and unindexing allocate nothing in servo ticks or "
          "dynamics steps") {
    SleepRig rig(false); // no force history: it would allocate on the servo path
    const std::uint64_t before = gFlaggedAllocations.load();
    const std::uint64_t all = gAllocations.load();
    for (int ms = 1; ms <= 1200; ++ms) {
        rig.runTo(ms);
        rig.runtime->maintain(); // the control thread: builds and publishes here
    }
    CHECK(rig.world.buildsPublished() == 2); // indexed at rest once
    CHECK(rig.world.restingIndexed() == 0);  // and out again once woken
    CHECK(gAllocations.load() > all);        // the counter is live
    CHECK(gFlaggedAllocations.load() == before);
}

TEST_CASE("two stepped runs through sleep, indexing and a wake are byte-identical") {
    std::vector<std::vector<double>> runs[2];
    for (auto& run : runs) {
        SleepRig rig(true);
        for (int ms = 1; ms <= 1000; ++ms) {
            rig.runTo(ms);
            rig.runtime->maintain();
            run.push_back(bitsOf(rig.body()));
        }
        for (const ScriptedDevice::Written& w : rig.hand->forces()) {
            run.push_back({w.force.x, w.force.y, w.force.z});
        }
    }
    REQUIRE(runs[0].size() == runs[1].size());
    for (std::size_t i = 0; i < runs[0].size(); ++i) {
        REQUIRE(runs[0][i].size() == runs[1][i].size());
        CHECK(std::memcmp(runs[0][i].data(), runs[1][i].data(),
                          runs[0][i].size() * sizeof(double)) == 0);
    }
}

TEST_CASE("twenty sleeping plates within one tick's reach are all felt from the index",
          "[threads]") {
    // 20 plates 8 x 0.1 x 8 cm, 2 mm apart, weightless and still: all asleep at 0.5 s,
    // indexed at 0.6 s. Pressing 1 mm into plate k's side puts every plate's bounding sphere
    // (5.7 cm) within the tick's reach, more than DynamicBodySet's 16.
    constexpr int kPlates = 20;
    std::vector<SceneObject> plates;
    for (int k = 0; k < kPlates; ++k) {
        SceneObject o = makeBox(100 + k, Vec3(0.0, 0.002 * (k - 9.5), 0.0),
                                Vec3(0.04, 0.0005, 0.04), Quat(1, 0, 0, 0), stiff());
        o.body.dynamic = true;
        o.body.massKg = 0.01;
        o.body.inertia = Mat3(0.01 * 0.08 * 0.08 / 6.0);
        plates.push_back(o);
    }
    Scene scene(Aabb{Vec3(-0.125), Vec3(0.125)}, plates);
    weightless(scene);
    ManualClock clock;
    World world(std::move(scene), IndexSpec::parse(kDefaultIndexSpec));
    world.useClock(clock);
    RuntimeOptions options;
    options.realtime = false;
    Runtime runtime(world, {}, options);
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 0);
    BodyPoseTable* table = runtime.bodyPoses();
    auto feel = [&](int k) {
        const Vec3 p(0.039, 0.002 * (k - 9.5), 0.0);
        return touch(world.current(), table, clock.nowNs(), p, Vec3(1, 0, 0));
    };
    // Awake (still, before the sleep time): only the first 16 are placed, plate 19 is not felt.
    runtime.runUntil(t0 + 300'000'000);
    runtime.maintain();
    REQUIRE_FALSE(table->read(kPlates - 1).sleeping);
    const TickOutput awake = feel(kPlates - 1);
    CHECK(awake.bodiesPlaced == DynamicBodySet::kMaxBodies);
    CHECK(awake.render.contactCount == 0);
    for (int ms = 301; ms <= 700; ++ms) {
        runtime.runUntil(t0 + static_cast<std::uint64_t>(ms) * 1'000'000);
        runtime.maintain();
    }
    REQUIRE(world.restingIndexed() == kPlates);
    for (int k = 0; k < kPlates; ++k) {
        const TickOutput out = feel(k);
        CHECK(out.bodiesPlaced == 0);
        REQUIRE(out.render.contactCount == 1);
        CHECK(out.render.contacts[0].id == static_cast<ObjectId>(100 + k));
        CHECK(out.forceN.x == Approx(0.5)); // 500 N/m x 1 mm, outward
    }
}

} // namespace hapto::test
