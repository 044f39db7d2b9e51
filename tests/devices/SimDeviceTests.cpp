#include "TestMeshes.h"

#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/HandModel.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace hapto;

namespace {

DeviceConfig simConfig(std::string_view script, std::uint64_t seed, Vec3 translation = Vec3(0.0)) {
    DeviceConfig c;
    c.name = "hand";
    c.kind = DeviceKind::Sim;
    c.transform.translation = translation;
    SimConfig s;
    s.script = parseHandScript(script).value();
    s.seed = seed;
    c.params = s;
    return c;
}

SimConfig& sim(DeviceConfig& c) {
    return std::get<SimConfig>(c.params);
}

// Depth (m) of p below the face of an axis-aligned box whose outward normal is n.
double depthBelowFace(const SceneObject& o, const Vec3& n, const Vec3& p) {
    const double plane = glm::dot(o.center, n) + glm::dot(o.halfExtents, glm::abs(n));
    return plane - glm::dot(p, n);
}

// A penalty renderer for one box face: F = k * depth * n while p is inside the box.
Vec3 penaltyForce(const SceneObject& o, const Vec3& n, const Vec3& p, double k) {
    return o.contains(p) ? k * depthBelowFace(o, n, p) * n : Vec3(0.0);
}

std::vector<Vec3> run(SimDevice& d, int ticks) {
    std::vector<Vec3> out;
    out.reserve(ticks);
    DeviceState s;
    for (int i = 0; i < ticks; ++i) {
        REQUIRE(d.read(s) == DeviceStatus::Ok);
        out.push_back(s.position);
    }
    return out;
}

} // namespace

TEST_CASE("hand model: a constant force moves the equilibrium by F / k") {
    HandModel hand(0.15, 300.0, 1.0);
    hand.reset(Vec3(0.0));
    const Vec3 f(1.5, -0.6, 0.3);
    for (int i = 0; i < 5000; ++i) {
        hand.step(Vec3(0.01, 0, 0), f, 1e-3);
    }
    const Vec3 expected = Vec3(0.01, 0, 0) + f / 300.0;
    CHECK(glm::length(hand.position() - expected) < 1e-9);
    CHECK(glm::length(hand.velocity()) < 1e-9);
    CHECK(hand.damping() == Approx(2.0 * std::sqrt(300.0 * 0.15)));
}

TEST_CASE("hand model: stable and non-overshooting at 100 Hz") {
    HandModel hand(0.15, 300.0, 1.0);
    hand.reset(Vec3(0.0));
    double maxX = 0.0;
    for (int i = 0; i < 500; ++i) {
        hand.step(Vec3(0.05, 0, 0), Vec3(0.0), 1e-2);
        maxX = std::max(maxX, hand.position().x);
    }
    CHECK(maxX <= 0.05 + 1e-12);
    CHECK(hand.position().x == Approx(0.05).margin(1e-6));
}

TEST_CASE("sim: same seed gives the same trajectory bit for bit, another seed differs") {
    const Scene scene = makeDefaultScene();
    for (const char* script : {"walk", "free", "slide"}) {
        INFO(script);
        SimDevice a(simConfig(script, 7), scene), b(simConfig(script, 7), scene),
            c(simConfig(script, 8), scene);
        REQUIRE(a.open() == DeviceStatus::Ok);
        REQUIRE(b.open() == DeviceStatus::Ok);
        REQUIRE(c.open() == DeviceStatus::Ok);
        const auto pa = run(a, 4000), pb = run(b, 4000), pc = run(c, 4000);
        CHECK(pa == pb);
        CHECK(pa != pc);
        // Reopening starts over exactly.
        REQUIRE(a.open() == DeviceStatus::Ok);
        CHECK(run(a, 4000) == pa);
    }
}

TEST_CASE("sim: periods the servo skipped move the hand on as reading through them would, under "
          "the force last written") {
    const Scene scene = makeDefaultScene();
    const Vec3 f(0.5, -0.3, 0.2);
    for (const std::uint64_t skipped :
         {std::uint64_t{1}, std::uint64_t{5}, SimDevice::kMaxSkippedSteps, std::uint64_t{1000}}) {
        INFO(skipped << " periods skipped");
        SimDevice read(simConfig("slide", 3), scene), skip(simConfig("slide", 3), scene);
        REQUIRE(read.open() == DeviceStatus::Ok);
        REQUIRE(skip.open() == DeviceStatus::Ok);
        DeviceState s;
        for (int i = 0; i < 300; ++i) {
            REQUIRE(read.write(f) == DeviceStatus::Ok);
            REQUIRE(skip.write(f) == DeviceStatus::Ok);
            REQUIRE(read.read(s) == DeviceStatus::Ok);
            REQUIRE(skip.read(s) == DeviceStatus::Ok);
        }
        for (std::uint64_t i = 0; i < skipped; ++i) {
            REQUIRE(read.read(s) == DeviceStatus::Ok);
        }
        const Vec3 before = skip.handPosition();
        skip.periodsSkipped(skipped);
        // The clock and the script agree whatever the gap.
        CHECK(skip.tick() == read.tick());
        CHECK(skip.timeS() == read.timeS());
        CHECK(skip.targetWorld() == read.targetWorld());
        CHECK(skip.phase() == read.phase());
        DeviceState r;
        REQUIRE(skip.read(s) == DeviceStatus::Ok);
        REQUIRE(read.read(r) == DeviceStatus::Ok);
        CHECK(s.sequence == r.sequence);
        CHECK(skip.handPosition() != before);
        if (skipped <= SimDevice::kMaxSkippedSteps) {
            // Every skipped period stepped the hand: the same hand, bit for bit.
            CHECK(skip.handPosition() == read.handPosition());
        } else {
            // Only the last kMaxSkippedSteps were stepped (bounded work): the hand started
            // them from where it was, so it trails, but it stays finite.
            CHECK(std::isfinite(glm::length(skip.handPosition())));
        }
    }
    // A closed device ignores it.
    SimDevice closed(simConfig("slide", 3), scene);
    closed.periodsSkipped(10);
    CHECK(closed.tick() == 0);
}

TEST_CASE("sim: the device feels the force written to it") {
    const Scene empty; // nothing to touch: the hand holds still at its start
    DeviceConfig c = simConfig("touch", 1);
    sim(c).noiseM = 0.0;
    sim(c).resolutionM = 0.0;
    SimDevice d(c, empty);
    REQUIRE(d.open() == DeviceStatus::Ok);
    const Vec3 f(0.0, 2.0, -1.0);
    DeviceState s;
    for (int i = 0; i < 5000; ++i) {
        REQUIRE(d.write(f) == DeviceStatus::Ok);
        REQUIRE(d.read(s) == DeviceStatus::Ok);
    }
    CHECK(glm::length(s.position - f / 300.0) < 1e-9);
    // Forces beyond the limit are clamped; non-finite ones refused.
    CHECK(d.write(Vec3(100.0, 0, 0)) == DeviceStatus::Ok);
    CHECK(d.write(Vec3(NAN, 0, 0)) == DeviceStatus::BadData);
    d.close();
    CHECK(d.read(s) == DeviceStatus::NotOpen);
    CHECK(d.write(f) == DeviceStatus::NotOpen);
}

TEST_CASE("sim free: never enters a solid over a long run in random scenes") {
    for (std::uint64_t seed : {1u, 2u, 3u}) {
        RandomOptions opt;
        opt.count = 150;
        opt.seed = seed;
        opt.keepClear = 0.03;
        opt.rotate = seed == 2;
        const Scene scene = makeRandomScene(opt);
        SimDevice d(simConfig("free", seed), scene);
        REQUIRE(d.open() == DeviceStatus::Ok);
        DeviceState s;
        Aabb visited = Aabb::empty();
        int inside = 0;
        for (int i = 0; i < 120000; ++i) { // 2 minutes at 1 kHz
            REQUIRE(d.read(s) == DeviceStatus::Ok);
            const Vec3 p = d.handPositionWorld();
            visited.expand(p);
            if (i % 2 == 0) {
                for (const SceneObject& o : scene.objects()) {
                    inside += o.contains(p);
                }
            }
        }
        INFO("seed " << seed);
        CHECK(inside == 0);
        CHECK(glm::length(visited.size()) > 0.03); // it did move about
        CHECK(d.phase() == ScriptPhase::Move);
    }
}

TEST_CASE("sim touch: presses on the nearest surface with press_n, whatever its stiffness") {
    // The hand's 300 N/m spring is in series with the surface: pressing its target a fixed
    // F / 300 m past the surface gave F k / (k + 300) (1.09 N at 800 N/m for 1.5 N).
    const Scene scene = makeDefaultScene();
    for (const double kSurface : {300.0, 800.0, 1000.0, 3000.0, 10000.0}) {
        for (const double pressN : {0.5, 1.5, 4.0}) {
            INFO("surface " << kSurface << " N/m, press_n " << pressN << " N");
            DeviceConfig c = simConfig("touch", 1, Vec3(0.01, 0.0, 0.0));
            sim(c).pressForceN = pressN;
            sim(c).noiseM = 0.0; // exact readings: at 10^4 N/m a 10 um quantum is 0.1 N
            sim(c).resolutionM = 0.0;
            SimDevice d(c, scene);
            REQUIRE(d.open() == DeviceStatus::Ok);
            REQUIRE(d.script()->object().has_value());
            const SceneObject& o = scene.object(*scene.slotOf(*d.script()->object()));
            const Vec3 n = d.script()->contactNormal();
            DeviceState s;
            Vec3 force(0.0);
            std::vector<double> depths, forces;
            for (int i = 0; i < 12000; ++i) {
                REQUIRE(d.write(force) == DeviceStatus::Ok);
                REQUIRE(d.read(s) == DeviceStatus::Ok);
                const Vec3 p = c.transform.positionToWorld(s.position);
                force = penaltyForce(o, n, p, kSurface);
                if (i >= 11000) {
                    depths.push_back(o.contains(p) ? depthBelowFace(o, n, p) : -1.0);
                    forces.push_back(glm::dot(force, n));
                }
            }
            CHECK(d.phase() == ScriptPhase::Hold);
            // Steady at press_n, within 0.1 %, as deep as that force needs.
            const auto [lo, hi] = std::minmax_element(forces.begin(), forces.end());
            CHECK(*lo == Approx(pressN).epsilon(0.001));
            CHECK(*hi == Approx(pressN).epsilon(0.001));
            const auto [shallow, deep] = std::minmax_element(depths.begin(), depths.end());
            CHECK(*shallow == Approx(pressN / kSurface).epsilon(0.001));
            CHECK(*deep == Approx(pressN / kSurface).epsilon(0.001));
            CHECK(d.pressExtraM() > 0.0);
        }
    }
}

TEST_CASE("sim touch: the press never overshoots press_n, and does not wind up while it feels "
          "nothing") {
    const Scene scene = makeDefaultScene();
    for (const double kSurface : {300.0, 800.0, 3000.0}) {
        INFO("surface " << kSurface << " N/m");
        DeviceConfig c = simConfig("touch", 1, Vec3(0.01, 0.0, 0.0));
        sim(c).noiseM = 0.0;
        sim(c).resolutionM = 0.0;
        SimDevice d(c, scene);
        REQUIRE(d.open() == DeviceStatus::Ok);
        const SceneObject& o = scene.object(*scene.slotOf(*d.script()->object()));
        const Vec3 n = d.script()->contactNormal();
        DeviceState s;
        Vec3 force(0.0);
        double most = 0.0;
        for (int i = 0; i < 12000; ++i) {
            REQUIRE(d.write(force) == DeviceStatus::Ok);
            REQUIRE(d.read(s) == DeviceStatus::Ok);
            force = penaltyForce(o, n, c.transform.positionToWorld(s.position), kSurface);
            most = std::max(most, glm::dot(force, n));
        }
        CHECK(most <= 1.5 * 1.002);
        CHECK(glm::dot(force, n) == Approx(1.5).epsilon(1e-4));
        // The surface gone (nothing felt), the press holds its depth: it does not wind up.
        const double extra = d.pressExtraM();
        for (int i = 0; i < 2000; ++i) {
            REQUIRE(d.write(Vec3(0.0)) == DeviceStatus::Ok);
            REQUIRE(d.read(s) == DeviceStatus::Ok);
        }
        CHECK(d.pressExtraM() == extra);
    }
}

TEST_CASE("sim grasp: the squeeze settles at press_n, and the press's extra depth is gone once "
          "the hand has let go") {
    // One hand of the grasp on the grasp scene's cube (800 N/m), which stays where it is here:
    // the hand presses its -x face until the lift takes it off, then releases.
    const Scene scene = makeGraspScene();
    const SceneObject& cube = scene.object(*scene.slotOf(0));
    DeviceConfig c = simConfig("grasp-left", 1, Vec3(-0.12, -0.04, 0));
    sim(c).object = 0;
    sim(c).pressForceN = 2.0;
    sim(c).noiseM = 0.0;
    sim(c).resolutionM = 0.0;
    SimDevice d(c, scene);
    REQUIRE(d.open() == DeviceStatus::Ok);
    const Vec3 n(-1.0, 0.0, 0.0);
    DeviceState s;
    Vec3 force(0.0);
    double squeezeN = 0.0, extraWhileSqueezing = 0.0;
    for (int i = 0; i < 9000; ++i) {
        REQUIRE(d.write(force) == DeviceStatus::Ok);
        REQUIRE(d.read(s) == DeviceStatus::Ok);
        force =
            penaltyForce(cube, n, c.transform.positionToWorld(s.position), cube.material.stiffness);
        if (std::abs(d.timeS() - 4.45) < 1e-9) {
            squeezeN = glm::dot(force, n);
            extraWhileSqueezing = d.pressExtraM();
        }
    }
    CHECK(squeezeN == Approx(2.0).epsilon(0.01));
    CHECK(extraWhileSqueezing == Approx(2.0 / cube.material.stiffness).epsilon(0.02));
    CHECK(d.phase() == ScriptPhase::Done);
    CHECK(d.pressExtraM() < 1e-9);
}

TEST_CASE("sim slide: moves along the surface while pressing on it") {
    const Scene scene = makeDefaultScene();
    DeviceConfig c = simConfig("slide", 1, Vec3(-0.01, 0.0, 0.0));
    SimDevice d(c, scene);
    REQUIRE(d.open() == DeviceStatus::Ok);
    const SceneObject& o = scene.object(*scene.slotOf(*d.script()->object()));
    const Vec3 n = d.script()->contactNormal();
    DeviceState s;
    Vec3 force(0.0);
    int sliding = 0, inContact = 0;
    double maxDepth = 0.0;
    Aabb along = Aabb::empty(); // the contact point's travel within the face plane
    for (int i = 0; i < 20000; ++i) {
        REQUIRE(d.write(force) == DeviceStatus::Ok);
        REQUIRE(d.read(s) == DeviceStatus::Ok);
        const Vec3 p = c.transform.positionToWorld(s.position);
        force = penaltyForce(o, n, p, 800.0);
        if (d.phase() == ScriptPhase::Slide) {
            ++sliding;
            inContact += o.contains(p);
            maxDepth = std::max(maxDepth, depthBelowFace(o, n, p));
            along.expand(p - glm::dot(p, n) * n);
        }
    }
    REQUIRE(sliding > 10000);
    CHECK(inContact > 0.98 * sliding);
    CHECK(glm::length(along.size()) > 0.02); // centimetres along the face
    CHECK(maxDepth < 0.004);
}

TEST_CASE("sim walk: stays in the scene bounds below the speed cap") {
    const Scene scene = makeDefaultScene();
    DeviceConfig c = simConfig("walk", 3);
    SimDevice d(c, scene);
    REQUIRE(d.open() == DeviceStatus::Ok);
    DeviceState s;
    double maxSpeed = 0.0;
    int outside = 0;
    const Aabb b = scene.bounds();
    for (int i = 0; i < 120000; ++i) {
        REQUIRE(d.read(s) == DeviceStatus::Ok);
        REQUIRE(s.hasVelocity);
        maxSpeed = std::max(maxSpeed, glm::length(s.velocity));
        outside += !b.contains(c.transform.positionToWorld(s.position));
    }
    CHECK(outside == 0);
    CHECK(maxSpeed <= 0.5);
    CHECK(maxSpeed > 0.2); // hand speeds, not a crawl
}

TEST_CASE("sim: quantisation and noise stay within what is configured") {
    const Scene scene = makeDefaultScene();
    for (const auto& [noise, resolution] : std::vector<std::pair<double, double>>{
             {1e-4, 1e-3}, {5e-6, 0.0}, {0.0, 2e-5}, {0.0, 0.0}}) {
        DeviceConfig c = simConfig("walk", 5);
        sim(c).noiseM = noise;
        sim(c).resolutionM = resolution;
        SimDevice d(c, scene);
        REQUIRE(d.open() == DeviceStatus::Ok);
        DeviceState s;
        double maxError = 0.0;
        bool onGrid = true;
        for (int i = 0; i < 5000; ++i) {
            REQUIRE(d.read(s) == DeviceStatus::Ok);
            for (int k = 0; k < 3; ++k) {
                maxError = std::max(maxError, std::abs(s.position[k] - d.handPosition()[k]));
                if (resolution > 0.0) {
                    const double q = s.position[k] / resolution;
                    onGrid = onGrid && std::abs(q - std::round(q)) < 1e-6;
                }
            }
        }
        INFO("noise " << noise << " resolution " << resolution);
        CHECK(maxError <= noise + 0.5 * resolution + 1e-12);
        CHECK(onGrid);
        if (noise == 0.0 && resolution == 0.0) {
            CHECK(maxError == 0.0);
        } else {
            CHECK(maxError > 0.1 * (noise + 0.5 * resolution)); // the effect is there
        }
    }
}

TEST_CASE("sim: workspace transforms put left and right where the configuration says") {
    const Scene scene = makeDefaultScene();
    DeviceConfig left = simConfig("touch", 1, Vec3(-0.02, 0, 0));
    DeviceConfig right = simConfig("touch", 1, Vec3(0.02, 0, 0));
    // Right device turned 90 degrees about +y and scaled: device +x is world -z.
    right.transform.rotation = glm::angleAxis(std::numbers::pi / 2, Vec3(0, 1, 0));
    right.transform.scale = 2.0;
    for (DeviceConfig* c : {&left, &right}) {
        sim(*c).noiseM = 0.0;
        sim(*c).resolutionM = 0.0;
    }
    SimDevice l(left, scene), r(right, scene);
    REQUIRE(l.open() == DeviceStatus::Ok);
    REQUIRE(r.open() == DeviceStatus::Ok);
    CHECK(glm::length(l.handPositionWorld() - Vec3(-0.02, 0, 0)) < 1e-12);
    CHECK(glm::length(r.handPositionWorld() - Vec3(0.02, 0, 0)) < 1e-12);
    DeviceState sl, sr;
    for (int i = 0; i < 3000; ++i) {
        REQUIRE(l.read(sl) == DeviceStatus::Ok);
        REQUIRE(r.read(sr) == DeviceStatus::Ok);
        // Readings are device-frame; mapped back they are the hand in the world.
        REQUIRE(glm::length(left.transform.positionToWorld(sl.position) - l.handPositionWorld()) <
                1e-12);
        REQUIRE(glm::length(right.transform.positionToWorld(sr.position) - r.handPositionWorld()) <
                1e-12);
    }
    CHECK(l.handPositionWorld().x < r.handPositionWorld().x);
    CHECK(glm::length(right.transform.positionToWorld(Vec3(0.01, 0, 0)) - Vec3(0.02, 0, -0.02)) <
          1e-12);
    // A world force along -z pushes the rotated device along its +x.
    CHECK(glm::length(right.transform.forceToDevice(Vec3(0, 0, -1)) - Vec3(1, 0, 0)) < 1e-12);
}

TEST_CASE("sim grasp: two hands squeeze one object from -x and +x, lift, carry, release") {
    // Sparser than the default scene, whose 200 overlapping cubes leave almost no object free
    // on both sides.
    RandomOptions opt;
    opt.count = 40;
    opt.seed = 7;
    opt.keepClear = 0.04;
    const Scene scene = makeRandomScene(opt);
    DeviceConfig lc = simConfig("grasp-left", 1, Vec3(-0.02, 0, 0));
    DeviceConfig rc = simConfig("grasp-right", 2, Vec3(0.02, 0, 0));
    lc.name = "left";
    rc.name = "right";
    SimDevice l(lc, scene), r(rc, scene);
    REQUIRE(l.open() == DeviceStatus::Ok);
    REQUIRE(r.open() == DeviceStatus::Ok);
    REQUIRE(l.script()->object().has_value());
    REQUIRE(l.script()->object() == r.script()->object());
    const SceneObject& o = scene.object(*scene.slotOf(*l.script()->object()));

    std::vector<ScriptPhase> seen;
    DeviceState sl, sr;
    int approachInside = 0;
    Vec3 squeezeL(0.0), squeezeR(0.0), liftedL(0.0), carriedL(0.0);
    bool buttonWhileLifting = true;
    for (int i = 0; i < 9500; ++i) {
        REQUIRE(l.read(sl) == DeviceStatus::Ok);
        REQUIRE(r.read(sr) == DeviceStatus::Ok);
        REQUIRE(l.phase() == r.phase()); // one timetable
        if (seen.empty() || seen.back() != l.phase()) {
            seen.push_back(l.phase());
        }
        if (l.phase() == ScriptPhase::Approach) {
            for (const SceneObject& other : scene.objects()) {
                approachInside += other.contains(l.handPositionWorld());
                approachInside += other.contains(r.handPositionWorld());
            }
        }
        if (l.phase() == ScriptPhase::Lift) {
            buttonWhileLifting = buttonWhileLifting && (sl.buttons & 1u) && (sr.buttons & 1u);
        }
        const double t = l.timeS();
        if (std::abs(t - 4.4) < 1e-9) {
            squeezeL = l.handPositionWorld();
            squeezeR = r.handPositionWorld();
        }
        if (std::abs(t - GraspTimes::kLiftEnd) < 1e-9) {
            liftedL = l.handPositionWorld();
        }
        if (std::abs(t - GraspTimes::kCarryEnd) < 1e-9) {
            carriedL = l.handPositionWorld();
        }
    }
    const std::vector<ScriptPhase> expected = {
        ScriptPhase::Approach, ScriptPhase::Reach,   ScriptPhase::Squeeze, ScriptPhase::Lift,
        ScriptPhase::Carry,    ScriptPhase::PutDown, ScriptPhase::Release, ScriptPhase::Done};
    CHECK(seen == expected);
    CHECK(approachInside == 0);
    CHECK(buttonWhileLifting);
    // Squeezing: each hand just inside its own side (no renderer here pushes back).
    CHECK(squeezeL.x < o.center.x);
    CHECK(squeezeR.x > o.center.x);
    CHECK(o.contains(squeezeL));
    CHECK(o.contains(squeezeR));
    CHECK(std::abs(squeezeL.y - o.center.y) < 0.002);
    CHECK(std::abs(squeezeR.z - o.center.z) < 0.002);
    // Lifted by 5 cm (+y), then carried 10 cm (+x).
    CHECK(liftedL.y - squeezeL.y == Approx(0.05).margin(0.003));
    CHECK(carriedL.x - liftedL.x == Approx(0.10).margin(0.003));
    // Released: both hands off the object's put-down place.
    SceneObject moved = o;
    moved.center += Vec3(0.10, 0, 0);
    CHECK_FALSE(moved.contains(l.handPositionWorld()));
    CHECK_FALSE(moved.contains(r.handPositionWorld()));
    CHECK(sl.buttons == 0u);
}

TEST_CASE("sim grasp: a flat object lying 1.5 cm from a wall is reached without entering the "
          "wall: the hand stands off nearer and comes down into the gap") {
    // A 1.5 cm slab on the floor (like a torus lying flat), its +x face 1.5 cm from a 2 cm
    // ridge: the usual 2 cm stand-off on the +x side would be inside the ridge.
    const Scene scene({Vec3(-0.15, -0.10, -0.15), Vec3(0.15)},
                      {makeBox(0, Vec3(-0.05, -0.0925, 0), Vec3(0.03, 0.0075, 0.03)),
                       makeBox(1, Vec3(0, -0.09, 0), Vec3(0.005, 0.01, 0.04))});
    const SceneObject& slab = scene.object(0);
    const SceneObject& ridge = scene.object(1);
    DeviceConfig lc = simConfig("grasp-left", 1, Vec3(-0.12, -0.04, 0));
    DeviceConfig rc = simConfig("grasp-right", 2, Vec3(0.04, -0.04, 0));
    sim(lc).object = 0;
    sim(rc).object = 0;
    SimDevice l(lc, scene), r(rc, scene);
    REQUIRE(l.open() == DeviceStatus::Ok);
    REQUIRE(r.open() == DeviceStatus::Ok);
    DeviceState sl, sr;
    int inRidge = 0;
    int inSlabBeforeReach = 0;
    Vec3 squeezeL(0.0), squeezeR(0.0);
    for (int i = 0; i < 4500; ++i) {
        REQUIRE(l.read(sl) == DeviceStatus::Ok);
        REQUIRE(r.read(sr) == DeviceStatus::Ok);
        inRidge += ridge.contains(l.handPositionWorld()) + ridge.contains(r.handPositionWorld());
        if (l.phase() == ScriptPhase::Approach) {
            inSlabBeforeReach +=
                slab.contains(l.handPositionWorld()) + slab.contains(r.handPositionWorld());
        }
        if (std::abs(l.timeS() - 4.4) < 1e-9) {
            squeezeL = l.handPositionWorld();
            squeezeR = r.handPositionWorld();
        }
    }
    CHECK(inRidge == 0);
    CHECK(inSlabBeforeReach == 0);
    // Squeezing: each hand just inside its own side, at the slab's mid-height.
    CHECK(slab.contains(squeezeL));
    CHECK(slab.contains(squeezeR));
    CHECK(squeezeL.x < slab.center.x);
    CHECK(squeezeR.x > slab.center.x);
    CHECK(std::abs(squeezeR.y - slab.center.y) < 0.002);
}

TEST_CASE("sim: any number of devices run side by side without sharing state") {
    const Scene scene = makeDefaultScene();
    std::vector<std::unique_ptr<Device>> devices;
    for (int i = 0; i < 8; ++i) {
        DeviceConfig c = simConfig(i % 2 ? "walk" : "free", 11, Vec3(0.004 * i - 0.014, 0, 0));
        c.name = "d" + std::to_string(i);
        devices.push_back(makeDevice(c, scene));
        REQUIRE(devices.back()->open() == DeviceStatus::Ok);
    }
    SimDevice alone(simConfig("walk", 11, Vec3(0.004 * 1 - 0.014, 0, 0)), scene);
    REQUIRE(alone.open() == DeviceStatus::Ok);
    DeviceState s, a;
    for (int t = 0; t < 2000; ++t) {
        for (auto& d : devices) {
            REQUIRE(d->read(s) == DeviceStatus::Ok);
            if (d.get() == devices[1].get()) {
                REQUIRE(alone.read(a) == DeviceStatus::Ok);
                REQUIRE(a.position == s.position);
            }
        }
    }
}

TEST_CASE("sim: a scripted stylus reports its orientation turning at the given rate, without "
          "one it reports none") {
    const Scene scene = makeDefaultScene();
    DeviceConfig c = simConfig("free", 1);
    const Quat start = glm::angleAxis(0.4, Vec3(1, 0, 0));
    sim(c).orientation = start;
    sim(c).spinRadPerS = Vec3(0.0, 0.0, 2.0); // 2 rad/s about +z
    SimDevice d(c, scene);
    REQUIRE(d.open() == DeviceStatus::Ok);
    DeviceState s;
    for (int t = 1; t <= 500; ++t) {
        REQUIRE(d.read(s) == DeviceStatus::Ok);
    }
    REQUIRE(s.hasOrientation);
    REQUIRE(s.hasAngularVelocity);
    CHECK(s.angularVelocity == Vec3(0.0, 0.0, 2.0));
    CHECK_FALSE(s.hasGimbalAngles);
    CHECK_FALSE(s.hasGripper);
    // 500 ticks of 1 ms: 1 rad about +z after the start orientation.
    const Quat expected = glm::angleAxis(1.0, Vec3(0, 0, 1)) * start;
    for (const Vec3& v : {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}) {
        CHECK(glm::length(s.orientation * v - expected * v) < 1e-12);
    }

    DeviceConfig constant = simConfig("free", 1);
    sim(constant).orientation = start;
    SimDevice still(constant, scene);
    REQUIRE(still.open() == DeviceStatus::Ok);
    REQUIRE(still.read(s) == DeviceStatus::Ok);
    CHECK(s.hasOrientation);
    CHECK(s.orientation == start);
    CHECK(s.angularVelocity == Vec3(0.0));

    SimDevice plain(simConfig("free", 1), scene);
    REQUIRE(plain.open() == DeviceStatus::Ok);
    DeviceState fresh;
    REQUIRE(plain.read(fresh) == DeviceStatus::Ok);
    CHECK_FALSE(fresh.hasOrientation);
    CHECK_FALSE(fresh.hasAngularVelocity);
    CHECK(fresh.orientation == Quat{1, 0, 0, 0});
}

TEST_CASE("sim touch and slide on a mesh: pressed where its triangles are, not its bounding box") {
    // A wavy sheet through the origin, heights within +-1 cm: its bounding box's top face is
    // 1 cm above the sheet's centre, where the sheet itself is at height 0.
    const Scene scene({Vec3(-0.125), Vec3(0.125)},
                      {makeMesh(5, Vec3(0.0), test::makeWavySheet(20, 0.2, 0.01))});
    for (const char* script : {"touch", "slide"}) {
        INFO(script);
        DeviceConfig c = simConfig(script, 1);
        sim(c).object = 5;
        SimDevice d(c, scene);
        REQUIRE(d.open() == DeviceStatus::Ok);
        REQUIRE(d.script()->object() == std::optional<ObjectId>(5));
        CHECK(d.script()->contactNormal().z == Approx(1.0));
        const double depth = sim(c).pressForceN / sim(c).handStiffness;
        bool pressed = false;
        for (const ScriptKeyframe& k : d.script()->keyframes()) {
            if (k.phase == ScriptPhase::Press) {
                pressed = true;
                // The sheet's surface at the centre (height 0) pressed by `depth`, not the
                // box face at 1 cm.
                CHECK(k.target.z == Approx(-depth).margin(1e-6));
                CHECK(std::abs(k.target.x) < 1e-6);
                CHECK(std::abs(k.target.y) < 1e-6);
            }
        }
        CHECK(pressed);
        const std::vector<Vec3> path = run(d, 8000); // free hand: the plan runs to its end
        for (const Vec3& p : path) {
            REQUIRE(std::isfinite(p.x + p.y + p.z));
        }
    }
}
