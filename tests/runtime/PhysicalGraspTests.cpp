// Two hands hold a body with mass by friction alone (issue 37 item 6), in step mode: the
// Runtime's servo ticks and dynamics steps on a ManualClock, two position-controlled scripted
// hands squeezing a 100 g, 5 cm cube from -x and +x on the axis through its centre of mass,
// lifting it 2 cm off a floor and holding it still for 5 s.
//
// What the physics says (Coulomb, the god-object's friction at each hand's contact):
//   - the hands press with F1 = F2 = k d (k the cube's 800 N/m, d how far each device point is
//     inside its face); static friction can hold up to mu_s (F1 + F2), so the cube is held when
//     mu_s (F1 + F2) > m g and slides when it is below, with a = g - mu_d (F1 + F2) / m;
//   - while it hangs still, Newton's second law: the hands' vertical forces on it sum to m g.

#include "CubeScene.h"
#include "ScriptedDevice.h"

#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/Runtime.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <vector>

namespace hapto::test {
namespace {

constexpr double kMassKg = 0.1;
constexpr double kHalfM = 0.025;     // the cube's half edge
constexpr double kStiffness = 800.0; // N/m, the cube's (and so each hand's contact spring)
constexpr double kMuS = 0.6, kMuD = 0.5;
constexpr double kG = 9.81;
constexpr double kLiftM = 0.02;

// A floor (top at y = 0) and the cube resting on it, centred at (0, kHalfM, 0).
Scene graspScene() {
    Material floorMaterial;
    floorMaterial.staticFriction = 0.3;
    floorMaterial.dynamicFriction = 0.2;
    Material rubbery;
    rubbery.stiffness = kStiffness;
    rubbery.staticFriction = kMuS;
    rubbery.dynamicFriction = kMuD;
    SceneObject cube = makeBox(1, Vec3(0.0, kHalfM, 0.0), Vec3(kHalfM), Quat(1, 0, 0, 0), rubbery);
    cube.body.dynamic = true;
    cube.body.massKg = kMassKg;
    cube.body.inertia = Mat3(kMassKg * (2.0 * kHalfM) * (2.0 * kHalfM) / 6.0); // a cube's
    std::vector<SceneObject> objects{
        makeBox(0, Vec3(0.0, -0.005, 0.0), Vec3(0.1, 0.005, 0.1), Quat(1, 0, 0, 0), floorMaterial),
        cube};
    Scene scene({Vec3(-0.1, -0.01, -0.1), Vec3(0.1, 0.1, 0.1)}, std::move(objects));
    scene.setPhysics(ScenePhysics{}); // g = 9.81 m/s^2 along -y, 1 kHz
    return scene;
}

double smooth(double tau) {
    tau = std::clamp(tau, 0.0, 1.0);
    return tau * tau * (3.0 - 2.0 * tau);
}

// Hand `side` (-1 left, +1 right) at time t (s): from 2 cm off its face in to depth(t) inside
// it over 0.3 s, on the axis through the centre of mass; up kLiftM over 0.5 s from 0.5 s.
Vec3 handAt(double side, double t, const std::function<double(double)>& depth) {
    const double face = kHalfM;
    const double x = side * (face + 0.02 - (0.02 + depth(t)) * smooth(t / 0.3));
    const double y = kHalfM + kLiftM * smooth((t - 0.5) / 0.5);
    return {x, y, 0.0};
}

// The runtime, two scripted hands at 1 kHz and the step mode's clock.
struct GraspRig {
    ManualClock clock;
    World world;
    std::unique_ptr<Runtime> runtime;
    std::uint64_t t0 = 0;

    explicit GraspRig(std::function<double(double)> depth)
        : world(graspScene(), IndexSpec::parse(kDefaultIndexSpec)) {
        world.useClock(clock);
        std::vector<RuntimeDevice> devices;
        for (int i = 0; i < 2; ++i) {
            const double side = i == 0 ? -1.0 : 1.0;
            auto d = std::make_unique<ScriptedDevice>(
                "d" + std::to_string(i), [side, depth](std::uint64_t tick) {
                    return handAt(side, static_cast<double>(tick) * 1e-3, depth);
                });
            d->useClock(&clock);
            devices.push_back({std::move(d), scriptedConfig(i, 1000.0), nullptr});
        }
        RuntimeOptions options;
        options.realtime = false;
        runtime = std::make_unique<Runtime>(world, std::move(devices), options);
        t0 = clock.nowNs();
        REQUIRE(runtime->startStepped(clock) == 2);
    }
    void runTo(double s) { runtime->runUntil(t0 + static_cast<std::uint64_t>(s * 1e9)); }
    BodyPose body() const { return runtime->bodyPoses()->read(0); }
    // The force last sent to hand i (N): minus what the hand exerts on the cube.
    Vec3 force(std::size_t i) const {
        ContactReport c;
        REQUIRE(runtime->lastTick(i, c));
        return c.force;
    }
    Vec3 hand(std::size_t i) const {
        ContactReport c;
        REQUIRE(runtime->lastTick(i, c));
        return c.devicePoint;
    }
    // The cube's centre of mass relative to the hands' midpoint.
    Vec3 offset() const { return body().centerOfMass - 0.5 * (hand(0) + hand(1)); }
};

} // namespace

TEST_CASE("two hands squeezing with mu_s (F1 + F2) = 2.4 m g hold a 100 g cube for 5 s - slip "
          "under 1 mm, and their vertical forces sum to its weight") {
    const double depth = 2.0 / kStiffness; // F = 2 N a hand: mu_s (F1 + F2) = 2.4 N > 0.98 N
    GraspRig rig([depth](double) { return depth; });
    rig.runTo(1.5); // squeezed by 0.3 s, lifted by 1.0 s, 0.5 s to settle
    const double y0 = rig.body().centerOfMass.y;
    CHECK(y0 > kHalfM + kLiftM - 0.003); // it went up with the hands (the hand's spring, below)
    const Vec3 start = rig.offset();
    double slip = 0.0, supportSum = 0.0, squeeze = 0.0;
    double ringFirst = 0.0, ringLast = 0.0; // largest |support - m g| in the first, last 0.5 s
    int samples = 0;
    for (int ms = 1; ms <= 5000; ++ms) {
        rig.runTo(1.5 + ms * 1e-3);
        slip = std::max(slip, glm::length(rig.offset() - start));
        const Vec3 f0 = rig.force(0), f1 = rig.force(1);
        const double support = -(f0.y + f1.y); // what the hands push the cube up with
        supportSum += support;
        const double off = std::abs(support - kMassKg * kG);
        if (ms <= 500) {
            ringFirst = std::max(ringFirst, off);
        } else if (ms > 4500) {
            ringLast = std::max(ringLast, off);
        }
        squeeze += 0.5 * (f1.x - f0.x); // the cube pushes the left hand to -x, the right to +x
        ++samples;
    }
    INFO("slip " << slip * 1000 << " mm; support mean " << supportSum / samples
                 << " N against m g = " << kMassKg * kG << " N, off by at most " << ringFirst
                 << " N in the first 0.5 s and " << ringLast << " N in the last; squeeze "
                 << squeeze / samples << " N");
    CHECK(slip < 0.001);
    // The mean over 5 s: the impulses the cube received equal m g T + m (v_end - v_start), and
    // a cube held still changes speed by far under 1 mm/s (1e-4 kg m/s over 5 s: 2e-5 N), so
    // 0.1 % of m g is a bound with room.
    CHECK(supportSum / samples == Approx(kMassKg * kG).epsilon(0.001));
    // Tick by tick the support rings about m g: the lift sets the cube swinging on the hands'
    // two tangential contact springs (2 x 800 N/m on 100 g: 20 Hz). A passive coupling never
    // feeds that ring: it must be smaller in the last 0.5 s than in the first, and by half at
    // least (measured: 0.19 N -> 0.025 N, a decay time of about 2.2 s).
    CHECK(ringLast < 0.5 * ringFirst);
    // Each hand squeezed with k d = 2 N.
    CHECK(squeeze / samples == Approx(2.0).epsilon(0.02));
}

TEST_CASE("two hands squeezing with mu_s (F1 + F2) = 0.6 m g cannot lift the cube - it stays on "
          "the floor while the hands slide up its sides") {
    const double depth = 0.5 / kStiffness; // F = 0.5 N a hand: mu_s (F1 + F2) = 0.6 N < 0.98 N
    GraspRig rig([depth](double) { return depth; });
    rig.runTo(0.45);
    const Vec3 start = rig.offset();
    const double y0 = rig.body().centerOfMass.y;
    rig.runTo(1.2);
    const double slid = start.y - rig.offset().y; // the cube's fall relative to the hands
    INFO("the cube moved " << (rig.body().centerOfMass.y - y0) * 1000 << " mm; slid " << slid * 1000
                           << " mm relative to the hands");
    CHECK(slid > 0.9 * kLiftM);
    CHECK(std::abs(rig.body().centerOfMass.y - y0) < 0.001);
}

TEST_CASE("a held cube whose squeeze drops to mu_s (F1 + F2) = 0.37 m g slides down between the "
          "hands with Coulomb friction mu_d F_n at each and a = g - mu_d (F1 + F2) / m") {
    // Held at 2 N a hand, lifted, then from 1.5 s the squeeze drops to 0.3 N a hand
    // (mu_s (F1 + F2) = 0.36 N < m g = 0.98 N).
    const double held = 2.0 / kStiffness, light = 0.3 / kStiffness;
    GraspRig rig([=](double t) { return t < 1.5 ? held : light; });
    rig.runTo(1.5);
    const Vec3 start = rig.offset();
    // Every millisecond of the slide: each hand's friction (along y) is mu_d times its normal
    // force (along x), and the slide relative to the hands is recorded.
    std::vector<double> slid(61, 0.0), normalSum(61, 0.0);
    double worstCoulomb = 0.0;
    for (int ms = 1; ms <= 60; ++ms) {
        rig.runTo(1.5 + ms * 1e-3);
        slid[ms] = start.y - rig.offset().y;
        for (std::size_t i = 0; i < 2; ++i) {
            const Vec3 f = rig.force(i);
            normalSum[ms] += std::abs(f.x);
            if (ms > 2) { // from the third tick: the first let the stuck proxy's lag go
                worstCoulomb =
                    std::max(worstCoulomb, std::abs(-f.y - kMuD * std::abs(f.x)) / std::abs(f.x));
            }
        }
    }
    // The acceleration from the second difference over 20 ms (20, 40, 60 ms: whatever the first
    // ticks did, the stuck proxies' lag, m g / 2 k = 0.6 mm a hand, let go as a shift) against
    // g - mu_d (F1 + F2) / m with the normal forces the hands had over those 40 ms.
    const double measured = (slid[60] - 2.0 * slid[40] + slid[20]) / (0.02 * 0.02);
    double normal = 0.0;
    for (int ms = 21; ms <= 60; ++ms) {
        normal += normalSum[ms] / 40.0;
    }
    const double a = kG - kMuD * normal / kMassKg;
    INFO("slid " << slid[20] * 1000 << ", " << slid[40] * 1000 << ", " << slid[60] * 1000
                 << " mm at 20, 40, 60 ms: a = " << measured << " m/s^2; g - mu_d (F1 + F2) / m = "
                 << a << " m/s^2 with F1 + F2 = " << normal << " N (the squeeze set: 0.6 N); "
                 << "friction off mu_d F_n by " << worstCoulomb * 100 << " % at most");
    CHECK(slid[20] > 0.001); // it slides, measurably
    // Coulomb at each tick: the renderer's slip trails the frictionless proxy by exactly
    // mu_d x penetration, so |F_t| = mu_d |F_n| up to rounding.
    CHECK(worstCoulomb < 1e-6);
    // The step integrates what the hands hand back (symplectic Euler, exact for a constant
    // force); the force grows over the window, which the 20 ms central difference follows to
    // second order: 2 %.
    CHECK(measured == Approx(a).epsilon(0.02));
}

} // namespace hapto::test
