// Two-handed grasping on the runtime's step mode: the servo ticks and the control loop take
// turns on the test's thread, one millisecond of the test's clock at a time, so every run
// moves the cube along the same path.

#include "MeshShapes.h"
#include "ScriptedDevice.h"

#include "hapto/index/Cursor.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/index/Overlap.h"
#include "hapto/runtime/GraspController.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <algorithm>

using namespace hapto;
using test::ScriptedDevice;

namespace {

using test::kMs;

// Piecewise-linear path through (tick, point) keyframes, held after the last.
ScriptedDevice::Path keyframes(std::vector<std::pair<std::uint64_t, Vec3>> keys) {
    return [keys](std::uint64_t t) {
        if (t <= keys.front().first) {
            return keys.front().second;
        }
        for (std::size_t i = 1; i < keys.size(); ++i) {
            if (t <= keys[i].first) {
                const double u =
                    double(t - keys[i - 1].first) / double(keys[i].first - keys[i - 1].first);
                return glm::mix(keys[i - 1].second, keys[i].second, u);
            }
        }
        return keys.back().second;
    };
}

// The grasp scene's cube (id 0) spans x -0.075..-0.025 at y -0.075. A hand on each side:
// approach (0.3 s), squeeze 2 mm (about 1.6 N each at 800 N/m) until 1.2 s, lift by `lift`
// (1 s), move by `carry` (2 s), move by `lower` (1 s), then open: each hand moves `open`
// outwards (0.3 s). Hand speeds stay at or under 5 cm/s, as in the simulated grasp scripts:
// the control loop, one millisecond behind the servo ticks, moves the object a fraction of a
// millimetre behind the hands, well within the squeeze.
struct Hands {
    ScriptedDevice::Path left, right;
};
Hands graspPaths(Vec3 lift, Vec3 carry, Vec3 lower, double open) {
    const Vec3 l0(-0.11, -0.075, 0), lIn(-0.073, -0.075, 0);
    const Vec3 r0(0.012, -0.075, 0), rIn(-0.027, -0.075, 0);
    const auto path = [&](Vec3 from, Vec3 in, double side) {
        return keyframes({{0, from},
                          {300, in},
                          {1200, in},
                          {2200, in + lift},
                          {4200, in + lift + carry},
                          {5200, in + lift + carry + lower},
                          {5500, in + lift + carry + lower + Vec3(side * open, 0, 0)}});
    };
    return {path(l0, lIn, -1.0), path(r0, rIn, 1.0)};
}

struct GraspRig {
    ManualClock clock;
    World world;
    std::unique_ptr<Runtime> runtime;
    std::unique_ptr<GraspController> grasp;
    std::vector<Vec3> positions; // the object's centre at every control step

    GraspRig(Scene scene, Hands hands)
        : world(std::move(scene), IndexSpec::parse(kDefaultIndexSpec)) {
        world.useClock(clock);
        world.setRestDelay(std::chrono::milliseconds(50));
        std::vector<RuntimeDevice> rds;
        const char* names[2] = {"left", "right"};
        ScriptedDevice::Path paths[2] = {hands.left, hands.right};
        for (int i = 0; i < 2; ++i) {
            DeviceConfig c;
            c.name = names[i];
            c.kind = DeviceKind::Scripted;
            c.maxForceN = 8.5;
            rds.push_back({std::make_unique<ScriptedDevice>(names[i], paths[i]), c, nullptr});
        }
        RuntimeOptions o;
        o.realtime = false;
        runtime = std::make_unique<Runtime>(world, std::move(rds), o);
        grasp = std::make_unique<GraspController>(world, *runtime, 0, 1);
    }

    // One millisecond: the servo ticks due in it, world upkeep, one control step.
    void millisecond() {
        runtime->runUntil(clock.nowNs() + kMs);
        runtime->maintain();
        grasp->step(0.001);
        positions.push_back(object().center);
    }
    // Runs until `ticks` device ticks have passed, then lets a falling object land.
    void run(std::uint64_t ticks) {
        REQUIRE(runtime->startStepped(clock) == 2);
        while (runtime->metrics(0).ticks.load() < ticks && runtime->anyRunning()) {
            millisecond();
        }
        for (int i = 0; i < 2000 && grasp->state() == GraspState::Falling; ++i) {
            millisecond();
        }
        CHECK(runtime->report().devices[0].faults == 0);
        CHECK(runtime->report().devices[1].faults == 0);
        runtime->stop();
        world.setRestDelay(std::chrono::nanoseconds(0));
        world.settle();
    }
    const SceneObject& object() const {
        const WorldSnapshot& s = world.current();
        return s.scene->object(*s.scene->slotOf(0));
    }
    // True when the index's leaf at p names object 0 (a box by its slot, a mesh by any of its
    // triangles).
    bool indexFindsAt(const Vec3& p) const {
        const WorldSnapshot& s = world.current();
        Cursor c(*s.index);
        const auto r = c.locate(p);
        const std::uint32_t slot = *s.scene->slotOf(0);
        return std::any_of(r.candidates.begin(), r.candidates.end(),
                           [&](std::uint32_t item) { return s.scene->objectSlotOf(item) == slot; });
    }
};

} // namespace

TEST_CASE("two hands lift, carry and put down the cube, the index then finds it at its new place") {
    const Vec3 start(-0.05, -0.075, 0);
    // Lift 5 cm, carry 10 cm along +x, lower 5 cm, then open the hands 3 cm each.
    GraspRig rig(makeGraspScene(),
                 graspPaths(Vec3(0, 0.05, 0), Vec3(0.10, 0, 0), Vec3(0, -0.05, 0), 0.03));
    rig.run(5800);
    CHECK(rig.grasp->graspStarts().size() == 1);
    CHECK(rig.grasp->graspEnds().size() == 1); // let go once, after putting it down
    // Step mode: the same session again moves the cube along the very same path.
    GraspRig again(makeGraspScene(),
                   graspPaths(Vec3(0, 0.05, 0), Vec3(0.10, 0, 0), Vec3(0, -0.05, 0), 0.03));
    again.run(5800);
    CHECK(again.positions == rig.positions);
    CHECK(again.grasp->graspStarts() == rig.grasp->graspStarts());
    CHECK(rig.grasp->graspedSteps() > 2500);
    const Vec3 end = rig.object().center;
    CHECK(end.x == Approx(start.x + 0.10).margin(0.004));
    CHECK(end.y == Approx(start.y).margin(0.004));
    CHECK(end.z == Approx(start.z).margin(0.002));
    // The highest point of the path is the lift.
    double top = -1;
    for (const Vec3& p : rig.positions) {
        top = std::max(top, p.y);
    }
    CHECK(top == Approx(start.y + 0.05).margin(0.004));
    // Back in the index once at rest: found at the new place, not at the old one.
    CHECK_FALSE(rig.world.isMoving(0));
    CHECK(rig.indexFindsAt(end));
    CHECK_FALSE(rig.indexFindsAt(start));
    CHECK(rig.grasp->massKg() == Approx(500.0 * 0.05 * 0.05 * 0.05));
}

TEST_CASE("letting go in mid-air drops the cube onto the floor") {
    // Lift 5 cm, no carry, no lowering, then both hands open 3 cm in mid-air.
    GraspRig rig(makeGraspScene(), graspPaths(Vec3(0, 0.05, 0), Vec3(0), Vec3(0), 0.03));
    rig.run(5800);
    CHECK(rig.grasp->graspStarts().size() == 1);
    CHECK(rig.grasp->graspEnds().size() == 1);
    double top = -1;
    for (const Vec3& p : rig.positions) {
        top = std::max(top, p.y);
    }
    CHECK(top > -0.075 + 0.04);                                     // it was up there
    CHECK(rig.object().aabb().min.y == Approx(-0.10).margin(5e-4)); // fell back to the floor
    CHECK(rig.object().center.x == Approx(-0.05).margin(0.003));
    CHECK(rig.grasp->state() == GraspState::Idle);
}

TEST_CASE("a one-handed press never lifts the cube") {
    Hands hands = graspPaths(Vec3(0, 0.05, 0), Vec3(0.10, 0, 0), Vec3(0, -0.05, 0), 0.03);
    hands.right = [](std::uint64_t) { return Vec3(0.06, 0.05, 0.06); }; // far away, in free space
    GraspRig rig(makeGraspScene(), hands);
    rig.run(5800);
    CHECK(rig.grasp->graspStarts().empty());
    CHECK(rig.grasp->graspedSteps() == 0);
    CHECK(rig.object().center == Vec3(-0.05, -0.075, 0));
    for (const Vec3& p : rig.positions) {
        CHECK(p.y == -0.075);
    }
}

TEST_CASE("a carried cube never passes through another object: it comes to rest on it",
          "[threads]") {
    // A block under the place the cube is put down: top at y = -0.07.
    Scene base = makeGraspScene();
    std::vector<SceneObject> objects(base.objects().begin(), base.objects().end());
    const SceneObject block = makeBox(9, Vec3(0.05, -0.085, 0), Vec3(0.03, 0.015, 0.03));
    objects.push_back(block);
    GraspRig rig(Scene(base.bounds(), objects),
                 graspPaths(Vec3(0, 0.05, 0), Vec3(0.10, 0, 0), Vec3(0, -0.05, 0), 0.03));
    rig.run(5800);
    CHECK(rig.grasp->graspStarts().size() == 1);
    // Never inside the block (nor the bar it crossed), at any step: test with the cube
    // shrunk by 50 um so resting contact does not count.
    for (const Vec3& p : rig.positions) {
        Obb cube{p, Vec3(0.025 - 5e-5), Mat3(1.0)};
        CHECK_FALSE(overlapsObbObb(cube, block.obb()));
        CHECK_FALSE(overlapsObbObb(cube, base.object(1).obb()));
    }
    // Resting on the block's top: its lowest point there (it may rest a little tilted).
    CHECK(rig.object().aabb().min.y == Approx(-0.07).margin(5e-4));
    CHECK(rig.object().center.x == Approx(0.05).margin(0.004));
}

TEST_CASE("two hands lift, carry and put down a torus mesh, the index then finds it at its new "
          "place",
          "[threads]") {
    // The grasp scene with its cube (id 0) replaced by a closed torus standing in the x-y plane,
    // as wide as the cube (ring 19 mm + tube 6 mm = 25 mm), resting on the floor: the hands
    // squeeze the outside of its ring where the cube's faces were.
    const Scene base = makeGraspScene();
    std::vector<SceneObject> objects(base.objects().begin(), base.objects().end());
    const auto torus = test::torusMesh(0.019, 0.006, 48, 16);
    REQUIRE(torus->closed());
    objects[0] = makeMesh(0, objects[0].center, torus, Quat(1, 0, 0, 0), objects[0].material);
    const Vec3 start = objects[0].center;
    GraspRig rig(Scene(base.bounds(), objects),
                 graspPaths(Vec3(0, 0.05, 0), Vec3(0.10, 0, 0), Vec3(0, -0.05, 0), 0.03));
    rig.run(5800);
    CHECK(rig.grasp->graspStarts().size() == 1);
    CHECK(rig.grasp->graspEnds().size() == 1);
    CHECK(rig.grasp->graspedSteps() > 2500);
    double top = -1;
    for (const Vec3& p : rig.positions) {
        top = std::max(top, p.y);
    }
    CHECK(top == Approx(start.y + 0.05).margin(0.004)); // lifted
    const Vec3 end = rig.object().center;
    CHECK(end.x == Approx(start.x + 0.10).margin(0.004)); // carried
    CHECK(end.y == Approx(start.y).margin(0.004));        // put down
    // Its mass is the volume it encloses (the 48 x 16 torus: a little under 2 pi^2 R r^2).
    const double analytic = 2.0 * glm::pi<double>() * glm::pi<double>() * 0.019 * 0.006 * 0.006;
    CHECK(rig.grasp->massKg() == Approx(500.0 * analytic).epsilon(0.05));
    CHECK(rig.grasp->massKg() < 500.0 * analytic);
    // Back in the index once at rest: its surface is found at the new place, not at the old.
    CHECK_FALSE(rig.world.isMoving(0));
    const Vec3 side(-0.025, 0, 0);
    CHECK(rig.indexFindsAt(end + side));
    CHECK(rig.indexFindsAt(end - side));
    CHECK_FALSE(rig.indexFindsAt(start + side));
    CHECK_FALSE(rig.indexFindsAt(start - side));
}
