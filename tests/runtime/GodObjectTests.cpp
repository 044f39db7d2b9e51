#include "hapto/core/Random.h"
#include "hapto/runtime/ForceSafety.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/scenes/Generators.h"

#include "MeshShapes.h"
#include "RenderTestSupport.h"

#include <catch2/catch.hpp>

#include <glm/gtc/constants.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

using namespace hapto;
using hapto::test::pressFrom;
using hapto::test::RenderRig;
using hapto::test::stroke;

namespace {

constexpr double kK = 1000.0;  // N/m
constexpr double kD = 0.002;   // m, press depth
constexpr double kTol = 1e-4;  // N: covers the 10 nm skin (k x 1e-8 = 1e-5 N) with room
constexpr double kTolM = 1e-7; // m

Material stiff(double k = kK) {
    Material m;
    m.stiffness = k;
    return m;
}

void checkVec(const Vec3& got, const Vec3& want, double margin) {
    CHECK(got.x == Approx(want.x).margin(margin));
    CHECK(got.y == Approx(want.y).margin(margin));
    CHECK(got.z == Approx(want.z).margin(margin));
}

Quat someRotation(double angle, Vec3 axis) {
    return glm::angleAxis(angle, glm::normalize(axis));
}

} // namespace

TEST_CASE("pressing d into a face gives k*d along the face normal") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    GodObjectRenderer r;
    const RenderOutput out = pressFrom(r, rig, Vec3(0.01, 0.06, 0.0), Vec3(0.01, 0.05 - kD, 0.0));
    checkVec(out.force, Vec3(0.0, kK * kD, 0.0), kTol);
    checkVec(out.proxy, Vec3(0.01, 0.05, 0.0), kTolM);
    REQUIRE(out.contactCount == 1);
    CHECK(out.contacts[0].id == 1);
    checkVec(out.contacts[0].normal, Vec3(0, 1, 0), 1e-12);
    CHECK(out.contacts[0].depth == Approx(kD).margin(kTolM));
    CHECK(out.status == RenderStatus::Ok);
    CHECK_FALSE(out.sliding);
}

TEST_CASE("free motion gives no force and the proxy follows the device") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05))});
    GodObjectRenderer r;
    const RenderOutput out = pressFrom(r, rig, Vec3(0.1, 0.1, 0.1), Vec3(0.07, 0.08, 0.06));
    CHECK(out.force == Vec3(0.0));
    CHECK(out.proxy == Vec3(0.07, 0.08, 0.06));
    CHECK(out.contactCount == 0);
}

TEST_CASE("a rotated box pushes along its rotated face normal, on every face") {
    const Quat q = someRotation(0.7, Vec3(1.0, 2.0, -0.5));
    const Vec3 c(0.02, -0.01, 0.03);
    const Vec3 h(0.04, 0.03, 0.02);
    const RenderRig rig({makeBox(9, c, h, q, stiff())});
    const Obb obb = rig.scene.object(0).obb();
    for (int axis = 0; axis < 3; ++axis) {
        for (const double side : {-1.0, 1.0}) {
            const Vec3 n = side * obb.axes[axis];
            const Vec3 t = obb.axes[(axis + 1) % 3] * (0.3 * h[(axis + 1) % 3]);
            const Vec3 face = c + n * h[axis] + t;
            GodObjectRenderer r;
            const RenderOutput out = pressFrom(r, rig, face + 0.01 * n, face - kD * n);
            checkVec(out.force, kK * kD * n, kTol);
            checkVec(out.proxy, face, kTolM);
            CHECK(out.contactCount == 1);
        }
    }
}

TEST_CASE("an edge pushes along its bisector and the proxy sits on the edge") {
    const Quat q = GENERATE(Quat(1, 0, 0, 0), someRotation(0.5, Vec3(0.3, -1.0, 0.4)));
    const Vec3 c(0.01, 0.02, -0.01);
    const double h = 0.03;
    const RenderRig rig({makeBox(1, c, Vec3(h), q, stiff())});
    const Obb obb = rig.scene.object(0).obb();
    const Vec3 edge = c + h * obb.axes[0] + h * obb.axes[1] + 0.2 * h * obb.axes[2];
    const Vec3 bisector = glm::normalize(obb.axes[0] + obb.axes[1]);
    GodObjectRenderer r;
    const RenderOutput out = pressFrom(r, rig, edge + 0.01 * bisector, edge - kD * bisector);
    checkVec(out.force, kK * kD * bisector, kTol);
    checkVec(out.proxy, edge, kTolM);
    CHECK(out.contactCount == 2);
}

TEST_CASE("a corner pushes out of the corner and the proxy sits on it") {
    const Quat q = GENERATE(Quat(1, 0, 0, 0), someRotation(1.1, Vec3(1.0, 1.0, 0.2)));
    const Vec3 c(0.0, 0.01, 0.0);
    const Vec3 h(0.02, 0.03, 0.04);
    const RenderRig rig({makeBox(1, c, h, q, stiff())});
    const Obb obb = rig.scene.object(0).obb();
    const Vec3 corner = c + h.x * obb.axes[0] - h.y * obb.axes[1] + h.z * obb.axes[2];
    const Vec3 out3 = glm::normalize(obb.axes[0] - obb.axes[1] + obb.axes[2]);
    GodObjectRenderer r;
    const RenderOutput out = pressFrom(r, rig, corner + 0.01 * out3, corner - kD * out3);
    checkVec(out.force, kK * kD * out3, kTol);
    checkVec(out.proxy, corner, kTolM);
    CHECK(out.contactCount == 3);
}

TEST_CASE("near an edge the proxy keeps to the face, past the edge the force is zero") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    GodObjectRenderer r;
    pressFrom(r, rig, Vec3(0.0, 0.06, 0.0), Vec3(0.0, 0.05 - kD, 0.0));
    // Slide toward the +x edge at constant depth: the force stays normal to the top face.
    RenderOutput out = stroke(r, rig, Vec3(0.0, 0.05 - kD, 0.0), Vec3(0.049, 0.05 - kD, 0.0), 100);
    checkVec(out.force, Vec3(0.0, kK * kD, 0.0), kTol);
    // Off the edge into free space: no force, no ghost.
    out = stroke(r, rig, Vec3(0.049, 0.05 - kD, 0.0), Vec3(0.052, 0.05 - kD, 0.0), 6);
    CHECK(out.force == Vec3(0.0));
    CHECK(out.contactCount == 0);
}

TEST_CASE("a sphere pushes radially, also after sliding around it") {
    const Vec3 c(0.01, -0.02, 0.0);
    const double radius = 0.03;
    const RenderRig rig({makeSphere(4, c, radius, stiff())});
    hapto::Random rng(7);
    for (int trial = 0; trial < 10; ++trial) {
        const Vec3 u = glm::normalize(Vec3(rng.normal(), rng.normal(), rng.normal()));
        GodObjectRenderer r;
        RenderOutput out = pressFrom(r, rig, c + (radius + 0.01) * u, c + (radius - kD) * u);
        checkVec(out.force, kK * kD * u, kTol);
        checkVec(out.proxy, c + radius * u, kTolM);
        // Slide along a great circle at constant depth (about 6 mm, 1 mm/tick at most).
        const Vec3 v = glm::normalize(glm::cross(u, Vec3(0.3, 0.4, 0.5)));
        for (int i = 1; i <= 10; ++i) {
            const double a = 0.02 * i;
            const Vec3 dir = std::cos(a) * u + std::sin(a) * v;
            out = r.update(rig.scene, rig.all(), c + (radius - kD) * dir, Vec3(0.0), 1e-3);
            checkVec(out.force, kK * kD * dir, 2e-3); // converges within the tick
            CHECK(glm::length(out.proxy - c) == Approx(radius).margin(1e-6));
        }
    }
}

TEST_CASE("a fast stroke through a 2 mm plate never pops through") {
    // 1 m/s at 1 kHz is 1 mm per tick; the plate is 2 mm thick.
    const Quat q = GENERATE(Quat(1, 0, 0, 0), someRotation(0.3, Vec3(1.0, 0.0, 1.0)));
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05, 0.001, 0.05), q, stiff())});
    const Vec3 n = rig.scene.object(0).obb().axes[1];
    const Vec3 t = rig.scene.object(0).obb().axes[0];
    GodObjectRenderer r;
    const Vec3 from = 0.006 * n + 0.002 * t;
    const Vec3 to = -0.012 * n - 0.002 * t; // ends well below the plate
    r.reset(from);
    const CandidateSet cands = rig.all();
    for (int i = 1; i <= 18; ++i) {
        const Vec3 p = from + (to - from) * (i / 18.0);
        const RenderOutput out = r.update(rig.scene, cands, p, (to - from) * (1000.0 / 18), 1e-3);
        CHECK(glm::dot(out.proxy, n) >= 0.001); // on the entry side, or above it
        CHECK(glm::dot(out.force, n) >= 0.0);
    }
    CHECK(glm::dot(r.proxy(), n) == Approx(0.001).margin(kTolM));
    // And in a single 5 cm jump (50 m/s at 1 kHz) straight through.
    r.reset(0.01 * n);
    const RenderOutput out = r.update(rig.scene, cands, -0.04 * n, Vec3(0.0), 1e-3);
    CHECK(glm::dot(out.proxy, n) == Approx(0.001).margin(kTolM));
    checkVec(out.force, kK * 0.041 * n, kTol);
}

TEST_CASE("a jump through a row of plates stops at the first plate in its way, whatever order "
          "the candidates come in") {
    // Three 2 mm plates (two of them tilted) and a sphere, 1 cm apart on one line, and one
    // 5 cm jump through all of them: a pass keeps the nearest entry it has found and skips
    // what lies beyond it, so every order of the candidates must give the first plate's face.
    const Quat tilt = someRotation(0.2, Vec3(1.0, 0.0, 1.0));
    const RenderRig rig(
        {makeBox(1, Vec3(0.0, 0.00, 0.0), Vec3(0.02, 0.001, 0.02), Quat(1, 0, 0, 0), stiff()),
         makeBox(2, Vec3(0.0, -0.01, 0.0), Vec3(0.02, 0.001, 0.02), tilt, stiff()),
         makeSphere(3, Vec3(0.0, -0.02, 0.0), 0.004, stiff()),
         makeBox(4, Vec3(0.0, -0.03, 0.0), Vec3(0.02, 0.001, 0.02), tilt, stiff())});
    std::vector<std::uint32_t> order{0, 1, 2, 3};
    int orders = 0;
    do {
        CandidateSet cands;
        cands.add(order);
        GodObjectRenderer r;
        r.reset(Vec3(0.0, 0.01, 0.0));
        const RenderOutput out = r.update(rig.scene, cands, Vec3(0.0, -0.04, 0.0), Vec3(0.0), 1e-3);
        INFO("order " << order[0] << order[1] << order[2] << order[3]);
        CHECK(out.proxy.y == Approx(0.001).margin(kTolM));
        REQUIRE(out.contactCount == 1);
        CHECK(out.contacts[0].slot == 0);
        checkVec(out.force, kK * Vec3(0.0, 0.041, 0.0), kTol);
        ++orders;
    } while (std::next_permutation(order.begin(), order.end()));
    CHECK(orders == 24);
}

TEST_CASE("sliding across the seam of two boxes side by side has no snag") {
    const RenderRig rig({makeBox(1, Vec3(-0.05, 0.0, 0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff()),
                         makeBox(2, Vec3(0.05, 0.0, 0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    GodObjectRenderer r;
    pressFrom(r, rig, Vec3(-0.02, 0.06, 0.0), Vec3(-0.02, 0.05 - kD, 0.0));
    const CandidateSet cands = rig.all();
    bool sawSecond = false;
    // 0.1 mm per tick, with the device exactly on the seam at tick 200.
    for (int i = 0; i <= 400; ++i) {
        const double x = -0.02 + 1e-4 * i;
        const RenderOutput out =
            r.update(rig.scene, cands, Vec3(x, 0.05 - kD, 0.0), Vec3(0.1, 0, 0), 1e-3);
        CHECK(out.force.x == Approx(0.0).margin(kTol));
        CHECK(out.force.y == Approx(kK * kD).margin(kTol));
        CHECK(out.proxy.x == Approx(x).margin(kTolM));
        sawSecond = sawSecond || (out.contactCount > 0 && out.contacts[0].id == 2);
    }
    CHECK(sawSecond);
    // And back, fast (1 mm per tick).
    const RenderOutput out =
        stroke(r, rig, Vec3(0.02, 0.05 - kD, 0.0), Vec3(-0.02, 0.05 - kD, 0.0), 40);
    checkVec(out.force, Vec3(0.0, kK * kD, 0.0), kTol);
}

TEST_CASE("sliding down the side of a box on a box has no snag") {
    const RenderRig rig({makeBox(1, Vec3(0.0, -0.05, 0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff()),
                         makeBox(2, Vec3(0.0, 0.05, 0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    GodObjectRenderer r;
    pressFrom(r, rig, Vec3(0.06, 0.02, 0.0), Vec3(0.05 - kD, 0.02, 0.0));
    const CandidateSet cands = rig.all();
    for (int i = 0; i <= 400; ++i) {
        const double y = 0.02 - 1e-4 * i;
        const RenderOutput out =
            r.update(rig.scene, cands, Vec3(0.05 - kD, y, 0.0), Vec3(0.0), 1e-3);
        CHECK(out.force.x == Approx(kK * kD).margin(kTol));
        CHECK(out.force.y == Approx(0.0).margin(kTol));
    }
}

TEST_CASE("a crease between two boxes pushes along the bisector") {
    // A floor (top at y = 0) and a wall standing on it (its +x face at x = 0).
    const RenderRig rig(
        {makeBox(1, Vec3(0.0, -0.05, 0.0), Vec3(0.1, 0.05, 0.1), Quat(1, 0, 0, 0), stiff()),
         makeBox(2, Vec3(-0.05, 0.05, 0.0), Vec3(0.05, 0.05, 0.1), Quat(1, 0, 0, 0), stiff())});
    const Vec3 bisector = glm::normalize(Vec3(1.0, 1.0, 0.0));
    GodObjectRenderer r;
    RenderOutput out = pressFrom(r, rig, 0.01 * bisector, -kD * bisector);
    checkVec(out.force, kK * kD * bisector, kTol);
    checkVec(out.proxy, Vec3(0.0), kTolM);
    REQUIRE(out.contactCount == 2);
    CHECK(out.contacts[0].slot != out.contacts[1].slot);
    // Slide along the crease line: the force stays on the bisector.
    out = stroke(r, rig, -kD * bisector, -kD * bisector + Vec3(0, 0, 0.03), 60);
    checkVec(out.force, kK * kD * bisector, kTol);
    checkVec(out.proxy, Vec3(0.0, 0.0, 0.03), kTolM);
    // Approached from the floor side, sliding into the wall: same answer.
    r.reset(Vec3(0.03, 0.01, 0.0));
    stroke(r, rig, Vec3(0.03, 0.01, 0.0), Vec3(0.03, -kD / std::sqrt(2.0), 0.0), 10);
    out = stroke(r, rig, Vec3(0.03, -kD / std::sqrt(2.0), 0.0), -kD * bisector, 40);
    checkVec(out.force, kK * kD * bisector, kTol);
}

TEST_CASE("two renderers (two devices) keep their own proxies") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    const CandidateSet cands = rig.all();
    auto pathA = [](int i) { return Vec3(0.01 * std::sin(i * 0.01), 0.055 - 1e-5 * i, 0.0); };
    auto pathB = [](int i) { return Vec3(0.056 - 1e-5 * i, 0.0, 0.01 * std::cos(i * 0.02)); };
    GodObjectRenderer soloA, soloB, a, b;
    soloA.reset(pathA(0));
    soloB.reset(pathB(0));
    a.reset(pathA(0));
    b.reset(pathB(0));
    std::vector<RenderOutput> expectA, expectB;
    for (int i = 1; i <= 800; ++i) {
        expectA.push_back(soloA.update(rig.scene, cands, pathA(i), Vec3(0.0), 1e-3));
    }
    for (int i = 1; i <= 800; ++i) {
        expectB.push_back(soloB.update(rig.scene, cands, pathB(i), Vec3(0.0), 1e-3));
    }
    for (int i = 1; i <= 800; ++i) { // interleaved
        const RenderOutput oa = a.update(rig.scene, cands, pathA(i), Vec3(0.0), 1e-3);
        const RenderOutput ob = b.update(rig.scene, cands, pathB(i), Vec3(0.0), 1e-3);
        REQUIRE(oa.force == expectA[i - 1].force);
        REQUIRE(oa.proxy == expectA[i - 1].proxy);
        REQUIRE(ob.force == expectB[i - 1].force);
        REQUIRE(ob.proxy == expectB[i - 1].proxy);
    }
    CHECK(expectA.back().force.y > 1.0); // both really were in contact
    CHECK(expectB.back().force.x > 1.0);
}

TEST_CASE("only candidate objects are rendered, duplicates and bad slots are harmless") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff()),
                         makeBox(2, Vec3(0.3, 0.0, 0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    const Vec3 from(0.0, 0.06, 0.0);
    const Vec3 to(0.0, 0.05 - kD, 0.0);
    GodObjectRenderer r;

    const std::vector<std::uint32_t> onlyFar{1};
    CandidateSet far;
    far.add(onlyFar);
    r.reset(from);
    RenderOutput out = r.update(rig.scene, far, to, Vec3(0.0), 1e-3);
    CHECK(out.force == Vec3(0.0)); // box 1 is not a candidate: not touched
    CHECK(out.objectsTested == 1);

    const std::vector<std::uint32_t> leafA{0, 1, 0};
    const std::vector<std::uint32_t> leafB{1, 0, 77}; // 77: no such slot
    const std::vector<std::uint32_t> moving{0};
    CandidateSet dup;
    dup.add(leafA);
    dup.add(leafB);
    dup.add(moving);
    while (dup.count < CandidateSet::kMaxSpans) {
        dup.add({}); // empty spans cost nothing
    }
    CHECK_FALSE(dup.add(moving)); // one span more than fits
    CHECK(dup.overflowed);
    r.reset(from);
    out = r.update(rig.scene, dup, to, Vec3(0.0), 1e-3);
    GodObjectRenderer ref;
    ref.reset(from);
    const RenderOutput want = ref.update(rig.scene, rig.all(), to, Vec3(0.0), 1e-3);
    CHECK(out.force == want.force);
    CHECK(out.proxy == want.proxy);
    CHECK(out.contactCount == 1);
    CHECK(out.objectsTested == 7);
    CHECK(out.status == RenderStatus::CandidatesDropped);
    CHECK(r.counters().candidatesDropped == 1);
}

TEST_CASE("a proxy reset inside an object passes out of it without force") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    GodObjectRenderer r;
    RenderOutput out = pressFrom(r, rig, Vec3(0.0, 0.0, 0.0), Vec3(0.0, 0.07, 0.0), 30);
    CHECK(out.force == Vec3(0.0));
    // Once outside, the box is solid again.
    out = stroke(r, rig, Vec3(0.0, 0.07, 0.0), Vec3(0.0, 0.05 - kD, 0.0), 30);
    checkVec(out.force, Vec3(0.0, kK * kD, 0.0), kTol);
}

TEST_CASE("a proxy held on a face, an edge, a corner, a sphere or a facet starts each tick on "
          "the planes it rests on: one pass a tick, the same force") {
    // The first solve starts with the last tick's planes the proxy still touches, so a held
    // tick does not spend a pass meeting them again at t = 0. Each hand is pressed in along
    // the normal it is held by (`out`, from outside).
    const Quat none(1, 0, 0, 0);
    const auto [name, object, hand, out, contacts] =
        GENERATE_REF(table<const char*, SceneObject, Vec3, Vec3, std::uint8_t>(
            {{"face", makeBox(1, Vec3(0.0), Vec3(0.05), none, stiff()), Vec3(0.01, 0.05 - kD, 0.0),
              Vec3(0, 1, 0), 1},
             {"edge", makeBox(1, Vec3(0.0), Vec3(0.05), none, stiff()),
              Vec3(0.01, 0.05 - kD, 0.05 - kD), Vec3(0, 1, 1), 2},
             {"corner", makeBox(1, Vec3(0.0), Vec3(0.05), none, stiff()), Vec3(0.05 - kD), Vec3(1),
              3},
             {"sphere", makeSphere(1, Vec3(0.0), 0.05, stiff()), Vec3(0.0, 0.05 - kD, 0.0),
              Vec3(0, 1, 0), 1},
             {"facet", makeMesh(1, Vec3(0.0), test::boxMesh(Vec3(0.05)), none, stiff()),
              Vec3(0.01, 0.05 - kD, 0.0), Vec3(0, 1, 0), 1}}));
    INFO(name);
    const RenderRig rig({object});
    GodObjectRenderer r;
    const RenderOutput pressed = pressFrom(r, rig, hand + 0.01 * glm::normalize(out), hand);
    REQUIRE(pressed.contactCount == contacts);
    for (int i = 0; i < 5; ++i) {
        const RenderOutput held = r.update(rig.scene, rig.all(), hand, Vec3(0.0), 1e-3);
        CHECK(held.iterations == 1);
        CHECK(held.contactCount == contacts);
        checkVec(held.force, pressed.force, 1e-12);
        checkVec(held.proxy, pressed.proxy, 1e-15);
    }
}

TEST_CASE("a surface changed, turned or taken away under a held proxy carries no plane into the "
          "next tick") {
    // The proxy rests on the top face (y = 5 cm) of a box with the hand 1 mm inside. Then the
    // scene changes under it, the object keeping its id and centre: the planes the proxy starts
    // the next tick with come from the scene as it is then, so no old face holds it.
    const RenderRig before({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    const Vec3 hand(0.0, 0.049, 0.0);
    const auto [name, object, stillHeld] = GENERATE(table<const char*, SceneObject, bool>(
        {{"shrunk to 4 cm", makeBox(1, Vec3(0.0), Vec3(0.04), Quat(1, 0, 0, 0), stiff()), false},
         {"turned a little",
          makeBox(1, Vec3(0.0), Vec3(0.05), someRotation(0.01, Vec3(0, 0, 1)), stiff()), true},
         {"a sphere of 4.5 cm", makeSphere(1, Vec3(0.0), 0.045, stiff()), false},
         {"moved away", makeBox(1, Vec3(0.5), Vec3(0.05), Quat(1, 0, 0, 0), stiff()), false}}));
    INFO(name);
    GodObjectRenderer r;
    REQUIRE(pressFrom(r, before, Vec3(0.0, 0.06, 0.0), hand).contactCount == 1);
    const RenderRig after({object});
    const RenderOutput out = r.update(after.scene, after.all(), hand, Vec3(0.0), 1e-3);
    if (!stillHeld) {
        // Nothing at the hand any more: the proxy follows it, without force.
        CHECK(out.contactCount == 0);
        checkVec(out.force, Vec3(0.0), 1e-12);
        checkVec(out.proxy, hand, 1e-12);
    } else {
        // The turned face still holds the hand, about 1 mm under it, along its own normal.
        REQUIRE(out.contactCount == 1);
        const Vec3 n = after.scene.object(0).obb().axes[1];
        CHECK(glm::dot(out.force, n) == Approx(glm::length(out.force)).epsilon(1e-9));
        CHECK(glm::length(out.force) == Approx(kK * 0.001).epsilon(0.05));
    }
}

TEST_CASE("a touched object that moves pushes the proxy (and the hand) with it") {
    RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    GodObjectRenderer r;
    const Vec3 hand(0.0, 0.0495, 0.0);
    pressFrom(r, rig, Vec3(0.0, 0.06, 0.0), hand);
    RenderOutput out;
    for (int i = 1; i <= 10; ++i) { // the box rises 0.1 mm per tick into the still hand
        rig.scene.setPose(0, Vec3(0.0, 1e-4 * i, 0.0), Quat(1, 0, 0, 0));
        out = r.update(rig.scene, rig.all(), hand, Vec3(0.0), 1e-3);
    }
    checkVec(out.force, Vec3(0.0, kK * (0.0005 + 0.001), 0.0), kTol);
    CHECK(out.proxy.y == Approx(0.051).margin(kTolM));
}

TEST_CASE("a rough object carried sideways takes the contact point with it") {
    Material rough = stiff();
    rough.staticFriction = 0.8;
    rough.dynamicFriction = 0.6;
    RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough)});
    GodObjectRenderer r;
    const Vec3 hand(0.0, 0.0495, 0.0);
    pressFrom(r, rig, Vec3(0.0, 0.06, 0.0), hand);
    RenderOutput out;
    for (int i = 1; i <= 10; ++i) { // the box slides 0.1 mm per tick along +x under the hand
        rig.scene.setPose(0, Vec3(1e-4 * i, 0.0, 0.0), Quat(1, 0, 0, 0));
        out = r.update(rig.scene, rig.all(), hand, Vec3(0.0), 1e-3);
    }
    // The proxy rode along 1 mm; the hand, left behind, is dragged after the box (+x), within
    // the static cone: tangential 1 mm vs normal 0.5 mm at mu_s 0.8 would slip, so it slides at
    // mu_d: |Ft| = mu_d |Fn|.
    CHECK(out.proxy.x > 0.0);
    CHECK(out.force.x > 0.0);
    CHECK(out.force.y == Approx(kK * 0.0005).margin(kTol));
    CHECK(out.force.x == Approx(0.6 * out.force.y).margin(kTol));
    // Without friction the box slides under the hand without dragging it.
    RenderRig smooth({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    GodObjectRenderer s;
    pressFrom(s, smooth, Vec3(0.0, 0.06, 0.0), hand);
    for (int i = 1; i <= 10; ++i) {
        smooth.scene.setPose(0, Vec3(1e-4 * i, 0.0, 0.0), Quat(1, 0, 0, 0));
        out = s.update(smooth.scene, smooth.all(), hand, Vec3(0.0), 1e-3);
    }
    CHECK(out.force.x == Approx(0.0).margin(kTol));
}

TEST_CASE("damping resists the approach and never pulls into the surface") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    RendererConfig config;
    config.damping = 2.0; // N*s/m
    GodObjectRenderer r(config);
    const CandidateSet cands = rig.all();
    r.reset(Vec3(0.0, 0.06, 0.0));
    r.update(rig.scene, cands, Vec3(0.0, 0.05 - kD, 0.0), Vec3(0.0), 1e-3);
    RenderOutput out =
        r.update(rig.scene, cands, Vec3(0.0, 0.05 - kD, 0.0), Vec3(0, -0.1, 0), 1e-3);
    CHECK(out.force.y == Approx(kK * kD + 2.0 * 0.1).margin(kTol));
    out = r.update(rig.scene, cands, Vec3(0.0, 0.05 - kD, 0.0), Vec3(0, 0.5, 0), 1e-3);
    CHECK(out.force.y == Approx(kK * kD - 2.0 * 0.5).margin(kTol));
    out = r.update(rig.scene, cands, Vec3(0.0, 0.05 - kD, 0.0), Vec3(0, 5.0, 0), 1e-3);
    CHECK(out.force.y == Approx(0.0).margin(1e-12));
    // Velocity not given (NaN): estimated from positions over dt.
    const double nan = std::numeric_limits<double>::quiet_NaN();
    out = r.update(rig.scene, cands, Vec3(0.0, 0.05 - kD - 1e-4, 0.0), Vec3(nan), 1e-3);
    CHECK(out.force.y == Approx(kK * (kD + 1e-4) + 2.0 * 0.1).margin(kTol));
    CHECK_THROWS_AS(GodObjectRenderer(RendererConfig{-1.0, 10}), std::invalid_argument);
    CHECK_THROWS_AS(GodObjectRenderer(RendererConfig{0.0, 0}), std::invalid_argument);
}

TEST_CASE("NaN or inf device input gives zero force, keeps the proxy, and is counted") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), stiff())});
    GodObjectRenderer r;
    ForceSafety safety;
    pressFrom(r, rig, Vec3(0.0, 0.06, 0.0), Vec3(0.0, 0.05 - kD, 0.0));
    const Vec3 proxy = r.proxy();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    for (const Vec3& bad : {Vec3(nan, 0, 0), Vec3(0, inf, 0), Vec3(0, 0, -inf)}) {
        const RenderOutput out = r.update(rig.scene, rig.all(), bad, Vec3(0.0), 1e-3);
        CHECK(out.force == Vec3(0.0));
        CHECK(out.status == RenderStatus::NonFiniteInput);
        CHECK(r.proxy() == proxy);
        CHECK(safety.filter(out.force) == Vec3(0.0));
        if (std::isnan(bad.x)) {
            CHECK(safety.filter(bad) == Vec3(0.0)); // a NaN force straight into safety
        } else {
            // An infinite force has a direction: the maximum along it, grown at the rate limit.
            const Vec3 f = safety.filter(bad);
            CHECK(glm::length(f) > 0.0);
            CHECK(glm::dot(f, bad) > 0.0);
            safety.reset();
        }
    }
    CHECK(r.counters().nonFiniteInput == 3);
    CHECK(safety.counters().nonFinite == 1);
    CHECK(safety.counters().overflowed == 2);
    // Good input again: rendering resumes from the kept proxy.
    const RenderOutput out =
        r.update(rig.scene, rig.all(), Vec3(0.0, 0.05 - kD, 0.0), Vec3(0.0), 1e-3);
    checkVec(out.force, Vec3(0.0, kK * kD, 0.0), kTol);
}

TEST_CASE("random walks in random rotated scenes: proxy never inside, force never above max") {
    const std::uint64_t seed = GENERATE(1, 2, 3);
    RandomOptions options;
    options.count = 120;
    options.seed = seed;
    options.rotate = true;
    options.cubeSize = 0.03;
    options.keepClear = 0.03;
    const RenderRig rig(makeRandomScene(options));
    const CandidateSet cands = rig.all();
    GodObjectRenderer r;
    ForceSafety safety; // PHANToM 1.0 defaults: 8.5 N, 1 N per tick
    hapto::Random rng(seed * 977);
    Vec3 p(0.0);
    Vec3 v(0.0);
    r.reset(p);
    std::uint64_t contactTicks = 0;
    std::uint64_t multiContactTicks = 0;
    double worstRaw = 0.0;
    double worstSafe = 0.0;
    std::uint64_t insideTicks = 0;
    for (int tick = 0; tick < 20000; ++tick) {
        v += Vec3(rng.normal(), rng.normal(), rng.normal()) * 0.05; // m/s
        if (glm::length(v) > 1.0) {
            v = glm::normalize(v); // at most 1 m/s: 1 mm per tick
        }
        p += v * 1e-3;
        for (int i = 0; i < 3; ++i) { // stay in the work cube
            if (std::abs(p[i]) > 0.12) {
                v[i] = -v[i];
                p[i] = std::clamp(p[i], -0.12, 0.12);
            }
        }
        const RenderOutput out = r.update(rig.scene, cands, p, v, 1e-3);
        REQUIRE(out.status == RenderStatus::Ok);
        REQUIRE(std::isfinite(out.force.x + out.force.y + out.force.z));
        for (const SceneObject& o : rig.scene.objects()) {
            if (o.contains(out.proxy)) {
                ++insideTicks;
            }
        }
        contactTicks += out.contactCount > 0;
        multiContactTicks += out.contactCount > 1;
        worstRaw = std::max(worstRaw, glm::length(out.force));
        worstSafe = std::max(worstSafe, glm::length(safety.filter(out.force)));
    }
    CHECK(insideTicks == 0);
    CHECK(worstSafe <= 8.5 + 1e-12);
    CHECK(contactTicks > 1000); // the walk really touched things
    CHECK(worstRaw > 8.5);      // ... hard enough for the clamp to matter
    INFO("multi-contact ticks: " << multiContactTicks);
    CHECK(safety.counters().clamped > 0);
}

TEST_CASE("a tick solved again over more candidate spans gives what a fresh solve gives, "
          "reading only the new spans") {
    // HapticTick solves a tick again when the proxy reached leaves no span listed, with their
    // spans appended; the renderer then keeps its near list and reads only the new spans
    // (extendNextUpdate). Each tick here is solved over the first k of four spans, then again
    // over all four, by a renderer told to extend and by one building afresh: the two must
    // agree bit for bit, and the extending one must read fewer candidates over the walk (and
    // in a tick at most the new spans more, when its kept list does not cover the solve).
    const bool mesh = GENERATE(false, true);
    RandomOptions options;
    options.count = 160;
    options.seed = 7;
    options.rotate = true;
    options.cubeSize = 0.03;
    options.keepClear = 0.03;
    const Scene cubes = makeRandomScene(options);
    std::vector<SceneObject> objects(cubes.objects().begin(), cubes.objects().end());
    if (mesh) { // a fine torus (3 200 triangles) in the middle of the cubes, and a sphere
        objects.push_back(makeMesh(1000, Vec3(0.0), test::torusMesh(0.06, 0.025, 80, 20)));
        objects.push_back(makeSphere(1001, Vec3(0.0, 0.0, 0.09), 0.02));
    }
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)}, std::move(objects));
    const std::vector<std::uint32_t> items = test::indexedItems(scene);
    // Four sorted spans, as leaves are: items dealt round-robin.
    std::array<std::vector<std::uint32_t>, 4> parts;
    for (std::size_t i = 0; i < items.size(); ++i) {
        parts[i % 4].push_back(items[i]);
    }
    GodObjectRenderer extending, fresh;
    hapto::Random rng(mesh ? 11 : 5);
    Vec3 p(0.0, 0.0, 0.12);
    Vec3 v(0.0);
    extending.reset(p);
    fresh.reset(p);
    std::uint64_t contactTicks = 0, readExtending = 0, readFresh = 0;
    for (int tick = 0; tick < 10000; ++tick) {
        v += Vec3(rng.normal(), rng.normal(), rng.normal()) * 0.05;
        if (glm::length(v) > 1.0) {
            v = glm::normalize(v); // at most 1 mm per tick
        }
        p = glm::clamp(p + v * 1e-3, Vec3(-0.12), Vec3(0.12));
        const std::size_t k = static_cast<std::size_t>(rng.uniform() * 4.0);
        CandidateSet first, all;
        for (std::size_t s = 0; s < 4; ++s) {
            if (s < k) {
                first.add(parts[s]);
            }
            all.add(parts[s]);
        }
        const GodObjectRenderer::State start = fresh.state();
        REQUIRE(start.proxy == extending.proxy());
        (void)extending.update(scene, first, p, v, 1e-3);
        extending.restore(start);
        extending.extendNextUpdate();
        const RenderOutput got = extending.update(scene, all, p, v, 1e-3);
        const RenderOutput want = fresh.update(scene, all, p, v, 1e-3);
        INFO("tick " << tick << ", first solve over " << k << " spans");
        test::requireSameOutput(got, want);
        // It reads the new spans, plus a full list only when the kept one does not cover
        // this solve (the friction solve's tight triangle list, say).
        std::size_t added = 0;
        for (std::size_t s = k; s < 4; ++s) {
            added += parts[s].size();
        }
        REQUIRE(got.objectsTested <= want.objectsTested + added);
        readExtending += got.objectsTested;
        readFresh += want.objectsTested;
        contactTicks += got.contactCount > 0;
    }
    CHECK(contactTicks > 300); // the walk touched things (5-6 % of its ticks)
    INFO("candidates read: " << readExtending << " extending, " << readFresh << " afresh");
    CHECK(readExtending < 0.8 * readFresh);
}

TEST_CASE("the near list reads a candidate once however many spans list it and past its table "
          "of items read too, and forgets them from tick to tick") {
    // Neighbouring leaves list the items that straddle them; the renderer reads each item once
    // per near list (a table of the items read, then a search of the earlier spans once the
    // table is full) and a new list forgets the last one's. Six sorted spans hold every one of
    // 480 cubes twice, so each list reads more items than the table holds; every tick must give
    // what one span listing each cube once, in the order first read, gives.
    RandomOptions options;
    options.count = 480;
    options.seed = 3;
    options.rotate = true;
    options.cubeSize = 0.015;
    const Scene scene = makeRandomScene(options);
    const std::vector<std::uint32_t> items = test::indexedItems(scene);
    std::array<std::vector<std::uint32_t>, 6> parts;
    for (std::size_t i = 0; i < items.size(); ++i) {
        parts[i % 6].push_back(items[i]);
        parts[(i + 1) % 6].push_back(items[i]);
    }
    std::vector<std::uint32_t> once;
    CandidateSet shared;
    for (auto& part : parts) {
        std::sort(part.begin(), part.end());
        for (const std::uint32_t item : part) {
            if (std::find(once.begin(), once.end(), item) == once.end()) {
                once.push_back(item);
            }
        }
        shared.add(part);
    }
    REQUIRE(once.size() == items.size());
    CandidateSet single;
    single.add(once);
    GodObjectRenderer got, want;
    hapto::Random rng(9);
    Vec3 p(0.0, 0.0, 0.1);
    Vec3 v(0.0);
    got.reset(p);
    want.reset(p);
    std::uint64_t contactTicks = 0;
    for (int tick = 0; tick < 3000; ++tick) {
        v += Vec3(rng.normal(), rng.normal(), rng.normal()) * 0.05;
        if (glm::length(v) > 1.0) {
            v = glm::normalize(v); // at most 1 mm per tick
        }
        p += v * 1e-3;
        for (int axis = 0; axis < 3; ++axis) { // bounce off the walls, inside the cubes' reach
            if (std::abs(p[axis]) > 0.1) {
                p[axis] = std::clamp(p[axis], -0.1, 0.1);
                v[axis] = -v[axis];
            }
        }
        const RenderOutput a = got.update(scene, shared, p, v, 1e-3);
        const RenderOutput b = want.update(scene, single, p, v, 1e-3);
        INFO("tick " << tick);
        test::requireSameOutput(a, b);
        REQUIRE(a.objectsTested == 2 * b.objectsTested); // every list read every span
        contactTicks += a.contactCount > 0;
    }
    INFO("ticks in contact: " << contactTicks);
    CHECK(contactTicks > 300); // the walk touched things
}
