#include "hapto/runtime/GodObjectRenderer.h"

#include "RenderTestSupport.h"

#include <catch2/catch.hpp>

#include <glm/gtc/constants.hpp>

#include <cmath>

using namespace hapto;
using hapto::test::pressFrom;
using hapto::test::RenderRig;
using hapto::test::stroke;

namespace {

constexpr double kFrictionK = 1000.0; // N/m
constexpr double kFrictionD = 0.002;  // m
constexpr double kMuS = 0.5;
constexpr double kMuD = 0.3;
constexpr double kFrictionTol = 1e-4; // N (the 10 nm skin adds k x 1e-8 = 1e-5 N to the normal)

Material rough(double muS = kMuS, double muD = kMuD) {
    Material m;
    m.stiffness = kFrictionK;
    m.staticFriction = muS;
    m.dynamicFriction = muD;
    return m;
}

} // namespace

TEST_CASE("touch: a static press on a rough face gives a pure normal force") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough())});
    GodObjectRenderer r;
    RenderOutput out = pressFrom(r, rig, Vec3(0.01, 0.06, 0.0), Vec3(0.01, 0.05 - kFrictionD, 0.0));
    for (int i = 0; i < 100; ++i) { // hold still
        out = r.update(rig.scene, rig.all(), Vec3(0.01, 0.05 - kFrictionD, 0.0), Vec3(0.0), 1e-3);
    }
    CHECK(out.force.x == Approx(0.0).margin(1e-12));
    CHECK(out.force.z == Approx(0.0).margin(1e-12));
    CHECK(out.force.y == Approx(kFrictionK * kFrictionD).margin(kFrictionTol));
    CHECK_FALSE(out.sliding);
}

TEST_CASE("the proxy sticks until the static cone breaks, then slides at mu_d") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough())});
    GodObjectRenderer r;
    const double y = 0.05 - kFrictionD;
    pressFrom(r, rig, Vec3(0.0, 0.06, 0.0), Vec3(0.0, y, 0.0));
    const double step = 1.7e-5;                 // m per tick: 17 mm/s
    const double breakAway = kMuS * kFrictionD; // 1 mm: where mu_s says the proxy lets go
    double slipAt = -1.0;
    double lastStuckX = 0.0;
    const CandidateSet cands = rig.all();
    for (int i = 1; i <= 200; ++i) {
        const double x = step * i;
        const RenderOutput out =
            r.update(rig.scene, cands, Vec3(x, y, 0.0), Vec3(0.017, 0, 0), 1e-3);
        CHECK(out.force.y == Approx(kFrictionK * kFrictionD).margin(kFrictionTol));
        if (slipAt < 0.0 && !out.sliding) {
            // Sticking: the proxy stays where it touched; tangential force is k x, against motion.
            CHECK(out.proxy.x == Approx(0.0).margin(1e-9));
            CHECK(out.force.x == Approx(-kFrictionK * x).margin(kFrictionTol));
            lastStuckX = x;
        } else {
            if (slipAt < 0.0) {
                slipAt = x;
            }
            // Sliding: tangential force is mu_d |normal force|, against the motion.
            CHECK(out.sliding);
            CHECK(out.force.x == Approx(-kMuD * out.force.y).margin(kFrictionTol));
            CHECK(out.proxy.x == Approx(x - kMuD * kFrictionD).margin(1e-7));
        }
    }
    REQUIRE(slipAt > 0.0);
    CHECK(lastStuckX <= breakAway + 1e-7);
    CHECK(slipAt > breakAway);
    CHECK(slipAt <= breakAway + step + 1e-7);
}

TEST_CASE("after sliding stops the proxy sticks again, holding the mu_d offset") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough())});
    GodObjectRenderer r;
    const double y = 0.05 - kFrictionD;
    pressFrom(r, rig, Vec3(0.0, 0.06, 0.0), Vec3(0.0, y, 0.0));
    stroke(r, rig, Vec3(0.0, y, 0.0), Vec3(0.01, y, 0.0), 100);
    RenderOutput out;
    for (int i = 0; i < 20; ++i) {
        out = r.update(rig.scene, rig.all(), Vec3(0.01, y, 0.0), Vec3(0.0), 1e-3);
    }
    CHECK_FALSE(out.sliding);
    CHECK(out.force.x == Approx(-kMuD * kFrictionK * kFrictionD).margin(kFrictionTol));
    // Reversing: the proxy stays put until the offset reaches mu_s the other way.
    out = r.update(rig.scene, rig.all(), Vec3(0.0095, y, 0.0), Vec3(0.0), 1e-3);
    CHECK_FALSE(out.sliding);
    CHECK(out.proxy.x == Approx(0.01 - kMuD * kFrictionD).margin(1e-9));
}

TEST_CASE("sliding on a rotated face in any direction: friction opposes the motion") {
    const Quat q = glm::angleAxis(0.6, glm::normalize(Vec3(1.0, 0.5, -0.3)));
    const Vec3 c(0.01, 0.0, -0.02);
    const RenderRig rig({makeBox(1, c, Vec3(0.05), q, rough())});
    const Obb obb = rig.scene.object(0).obb();
    const Vec3 n = obb.axes[2];
    const Vec3 face = c + 0.05 * n;
    for (const double angle : {0.0, 1.0, 2.5, 4.0}) {
        const Vec3 dir = std::cos(angle) * obb.axes[0] + std::sin(angle) * obb.axes[1];
        GodObjectRenderer r;
        const Vec3 pressed = face - kFrictionD * n;
        pressFrom(r, rig, face + 0.01 * n, pressed);
        const RenderOutput out = stroke(r, rig, pressed, pressed + 0.01 * dir, 200);
        CHECK(out.sliding);
        CHECK(glm::dot(out.force, n) == Approx(kFrictionK * kFrictionD).margin(kFrictionTol));
        CHECK(glm::dot(out.force, dir) ==
              Approx(-kMuD * kFrictionK * kFrictionD).margin(kFrictionTol));
        const Vec3 rest = out.force - glm::dot(out.force, n) * n - glm::dot(out.force, dir) * dir;
        CHECK(glm::length(rest) == Approx(0.0).margin(kFrictionTol));
    }
}

TEST_CASE("sliding along a box's convex edge pressed into it: the proxy stays on the edge and "
          "trails by mu_d x penetration") {
    // The top-front edge of a 10 cm cube (along x at y = z = 5 cm), the device pressed
    // kFrictionD into it along the diagonal and drawn along it: the proxy rests on both faces
    // (Zilles & Salisbury), and once it slips it is kMuD x kFrictionD behind the device.
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough())});
    GodObjectRenderer r;
    const double in = 0.05 - kFrictionD / std::sqrt(2.0);
    pressFrom(r, rig, Vec3(0.0, 0.06, 0.06), Vec3(0.0, in, in));
    const double step = 1e-4; // m per tick: 0.1 m/s
    const double skin = GodObjectRenderer::kSkinM;
    const double penetration = std::sqrt(2.0) * (0.05 + skin - in);
    int slid = 0;
    for (int i = 1; i <= 100; ++i) {
        const double x = step * i;
        const RenderOutput out =
            r.update(rig.scene, rig.all(), Vec3(x, in, in), Vec3(0.1, 0.0, 0.0), 1e-3);
        REQUIRE(out.contactCount == 2);
        CHECK(out.proxy.y == Approx(0.05 + skin).margin(1e-12));
        CHECK(out.proxy.z == Approx(0.05 + skin).margin(1e-12));
        if (out.sliding) {
            ++slid;
            CHECK(out.proxy.x == Approx(x - kMuD * penetration).margin(1e-9));
            const double normal = std::hypot(out.force.y, out.force.z);
            CHECK(normal == Approx(kFrictionK * penetration).margin(kFrictionTol));
            CHECK(out.force.x == Approx(-kMuD * normal).margin(kFrictionTol));
        } else {
            CHECK(out.proxy.x == Approx(0.0).margin(1e-12)); // stuck where it first held
        }
    }
    CHECK(slid > 80);
}

TEST_CASE("friction sliding across the seam of two boxes has no snag") {
    const RenderRig rig({makeBox(1, Vec3(-0.05, 0.0, 0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough()),
                         makeBox(2, Vec3(0.05, 0.0, 0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough())});
    GodObjectRenderer r;
    const double y = 0.05 - kFrictionD;
    pressFrom(r, rig, Vec3(-0.02, 0.06, 0.0), Vec3(-0.02, y, 0.0));
    stroke(r, rig, Vec3(-0.02, y, 0.0), Vec3(-0.015, y, 0.0), 50); // break away first
    const CandidateSet cands = rig.all();
    for (int i = 1; i <= 300; ++i) {
        const double x = -0.015 + 1e-4 * i;
        const RenderOutput out = r.update(rig.scene, cands, Vec3(x, y, 0.0), Vec3(0.1, 0, 0), 1e-3);
        CHECK(out.sliding);
        CHECK(out.force.y == Approx(kFrictionK * kFrictionD).margin(kFrictionTol));
        CHECK(out.force.x == Approx(-kMuD * kFrictionK * kFrictionD).margin(kFrictionTol));
    }
}

TEST_CASE("the touch and sliding conditions give distinct, correct forces") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough(0.4, 0.25))});
    GodObjectRenderer touch, slide;
    const double y = 0.05 - kFrictionD;
    const RenderOutput t = pressFrom(touch, rig, Vec3(0.0, 0.06, 0.0), Vec3(0.0, y, 0.0));
    pressFrom(slide, rig, Vec3(0.0, 0.06, 0.0), Vec3(0.0, y, 0.0));
    const RenderOutput s = stroke(slide, rig, Vec3(0.0, y, 0.0), Vec3(0.0, y, -0.02), 200);
    CHECK(t.force.z == Approx(0.0).margin(1e-12));
    CHECK(s.force.z ==
          Approx(0.25 * kFrictionK * kFrictionD).margin(kFrictionTol)); // against motion in -z
    CHECK(t.force.y == Approx(s.force.y).margin(kFrictionTol));
    CHECK_FALSE(t.sliding);
    CHECK(s.sliding);
}

TEST_CASE("an oblique approach sticks where it first touched") {
    const RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough())});
    GodObjectRenderer r;
    // 1 mm tangential per 5 mm of depth: inside the static cone (0.2 < mu_s = 0.5).
    const RenderOutput out =
        pressFrom(r, rig, Vec3(0.0, 0.053, 0.0), Vec3(0.0012, 0.05 - 0.003, 0.0), 30);
    CHECK(out.proxy.x == Approx(0.0006).margin(1e-7)); // the first touch point (half way)
    CHECK_FALSE(out.sliding);
}

TEST_CASE("a stuck proxy does not hang in the air when its object moves away") {
    RenderRig rig({makeBox(1, Vec3(0.0), Vec3(0.05), Quat(1, 0, 0, 0), rough())});
    GodObjectRenderer r;
    const Vec3 hand(0.0, 0.05 - kFrictionD, 0.0);
    pressFrom(r, rig, Vec3(0.0, 0.06, 0.0), hand);
    rig.scene.setPose(0, Vec3(0.0003, -0.0005, 0.0), Quat(1, 0, 0, 0)); // drops 0.5 mm
    const RenderOutput out = r.update(rig.scene, rig.all(), hand, Vec3(0.0), 1e-3);
    CHECK(out.force.y == Approx(kFrictionK * (kFrictionD - 0.0005)).margin(kFrictionTol));
    CHECK(out.proxy.y == Approx(0.0495).margin(1e-7));
}
