// hapto's dynamics against Bullet 3.24 (double precision) and against the analytic results,
// over the same scenarios (BulletReference.h): a drop onto a floor (box and sphere), a bounce,
// a box on a ramp (holding and sliding), a stack of three boxes.
//
// First Bullet is checked against the analytic results, so that it is a reference worth
// comparing with; then hapto's trajectories are held to the same analytic values and
// tolerances, and to Bullet's where no analytic value exists (how far a stack drifts).
//
// Tolerances, and why (both simulators are semi-implicit Euler at dt = 1 ms):
// - Landing time: within 2 dt of sqrt(2h/g). Euler reaches the floor half a step early
//   (y_n = h - g dt^2 n (n + 1) / 2), and the step that meets the floor may be the one before
//   the crossing (a speculative contact) or the one after it (a penetrating one): [-1.5, +1] dt.
// - Rest height: within 0.25 mm of the analytic height. A resting contact keeps up to the
//   penetration slop (hapto: 0.1 mm; Bullet: none, but one step's gravity sag g dt^2 = 0.01 mm
//   before the split impulse pushes it back), and both remove only part of an overlap per step.
// - Ramp: after 1 s a sliding box has moved a t^2 / 2 with a = g (sin - mu_d cos) within 2 %
//   (Euler's bias is dt / t = 0.1 %; the rest is the solvers': iterations over 4 contact
//   points, and how each starts the slide from rest; measured: Bullet -0.4 %, hapto -1.5 %),
//   and hapto within 2 % of Bullet's; a holding one moves under 0.5 mm (creep).
// - Stack: over 2 s each box stays within 0.5 mm horizontally of where it started (what a
//   solver's asymmetry lets creep: a stable stack has none, an unstable one walks off by
//   centimetres), and the k-th box from the floor within k * 0.1 mm + 0.05 mm vertically: each
//   contact below it may keep hapto's 0.1 mm slop, plus the gravity sag of a step and what the
//   partial correction has not yet removed (hapto measured 0.09, 0.17, 0.20 mm; Bullet 0.03).
// - Bounce: the first apex after impact is e^2 h within 5 % (the impact speed is Euler's,
//   sqrt(2gh) within g dt = 0.7 %, squared; the apex is sampled once a step).
// - Free fall (before any contact): hapto and Bullet within 1e-9 m, the same integrator.
#include "BulletReference.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

using namespace hapto;
using namespace hapto::reference;

namespace {

constexpr double kG = 9.81;    // |gravity| of every scenario (ScenePhysics' default), m/s^2
constexpr double kDt = 1e-3;   // the step (s)
constexpr double kDropM = 0.1; // drop height of the lowest point (m)

/// The first time the body's fall is stopped: its vertical velocity rises above half of what
/// free fall would have (-g t / 2). Infinity when it never lands.
double landingTimeS(const Trajectory& t) {
    for (const BodySample& s : t.samples) {
        if (s.timeS > 0 && s.velocity.y > -0.5 * kG * s.timeS) {
            return s.timeS;
        }
    }
    return INFINITY;
}

/// The highest the centre gets after `fromS` (m).
double apexAfter(const Trajectory& t, double fromS) {
    double y = -INFINITY;
    for (const BodySample& s : t.samples) {
        if (s.timeS > fromS) {
            y = std::max(y, s.position.y);
        }
    }
    return y;
}

/// Largest horizontal (x, z) and vertical distances of any sample from the start (m).
struct Drift {
    double horizontalM = 0.0;
    double verticalM = 0.0;
};
Drift driftOf(const Trajectory& t) {
    Drift d;
    const Vec3 start = t.samples.front().position;
    for (const BodySample& s : t.samples) {
        const Vec3 delta = s.position - start;
        d.horizontalM = std::max(d.horizontalM, std::hypot(delta.x, delta.z));
        d.verticalM = std::max(d.verticalM, std::abs(delta.y));
    }
    return d;
}

double rampDisplacementM(const Trajectory& t, double angleRad) {
    return glm::dot(t.samples.back().position - t.samples.front().position, rampDownhill(angleRad));
}

std::vector<Trajectory> bulletRun(const Scene& scene, int steps) {
    return runBullet(scene, steps);
}

/// hapto's run, awake throughout (sleeping would freeze drift rather than measure it).
std::vector<Trajectory> haptoRun(const Scene& scene, int steps) {
    DynamicsOptions options;
    options.sleepAfterS = 0.0;
    return runHapto(std::make_shared<const Scene>(scene), steps, options);
}

// The scenarios' analytic values.
const double kLandingS = std::sqrt(2 * kDropM / kG);
constexpr double kHoldAngle = 20.0 * std::numbers::pi / 180; // tan = 0.364 < mu_d = 0.5
constexpr double kSlideAngle = 30.0 * std::numbers::pi / 180;
constexpr double kSlideMuS = 0.55, kSlideMuD = 0.5; // mu_s < tan 30 deg = 0.577
const double kSlideAccel = kG * (std::sin(kSlideAngle) - kSlideMuD * std::cos(kSlideAngle));

void checkDrop(const Trajectory& t, double halfHeightM) {
    INFO("landing at " << landingTimeS(t) << " s, analytic " << kLandingS << " s");
    CHECK(std::abs(landingTimeS(t) - kLandingS) <= 2 * kDt);
    const double restY = t.samples.back().position.y;
    INFO("rests at " << restY << " m, analytic " << kFloorTopY + halfHeightM << " m");
    CHECK(std::abs(restY - (kFloorTopY + halfHeightM)) <= 2.5e-4);
}

void checkBounce(const Trajectory& t, double e) {
    const double apexM = apexAfter(t, landingTimeS(t)) - (kFloorTopY + kSphereRadiusM);
    INFO("bounces to " << apexM << " m, analytic " << e * e * kDropM << " m");
    CHECK(std::abs(apexM - e * e * kDropM) <= 0.05 * e * e * kDropM);
}

void checkSlide(const Trajectory& t) {
    const double s = rampDisplacementM(t, kSlideAngle);
    const double analytic = kSlideAccel / 2; // after 1 s
    INFO("slid " << s << " m in 1 s, analytic " << analytic << " m");
    CHECK(std::abs(s - analytic) <= 0.02 * analytic);
}

void checkHold(const Trajectory& t) {
    const Drift d = driftOf(t);
    INFO("moved " << d.horizontalM << " m horizontally, " << d.verticalM << " m vertically");
    CHECK(std::hypot(d.horizontalM, d.verticalM) <= 5e-4);
}

void checkStack(const std::vector<Trajectory>& boxes) {
    REQUIRE(boxes.size() == 3);
    for (std::size_t k = 0; k < boxes.size(); ++k) { // bottom to top
        const Drift d = driftOf(boxes[k]);
        INFO("box " << boxes[k].id << " drifted " << d.horizontalM << " m horizontally, "
                    << d.verticalM << " m vertically");
        CHECK(d.horizontalM <= 5e-4);
        CHECK(d.verticalM <= 1e-4 * static_cast<double>(k + 1) + 5e-5);
    }
}

} // namespace

TEST_CASE("Bullet: a dropped box lands at sqrt(2h/g) and rests on the floor", "[reference]") {
    const auto run = bulletRun(dropScene(Shape::Box, kDropM), 1000);
    REQUIRE(run.size() == 1);
    checkDrop(run[0], kBoxEdgeM / 2);
}

TEST_CASE("Bullet: a dropped sphere lands at sqrt(2h/g) and rests on the floor", "[reference]") {
    const auto run = bulletRun(dropScene(Shape::Sphere, kDropM), 1000);
    REQUIRE(run.size() == 1);
    checkDrop(run[0], kSphereRadiusM);
}

TEST_CASE("Bullet: a sphere with restitution e bounces to e^2 h", "[reference]") {
    const auto run = bulletRun(dropScene(Shape::Sphere, kDropM, 0.5), 400);
    REQUIRE(run.size() == 1);
    checkBounce(run[0], 0.5);
}

TEST_CASE("Bullet: a box on a ramp holds when mu exceeds tan(theta)", "[reference]") {
    const auto run = bulletRun(rampScene(kHoldAngle, 0.6, 0.5), 1000);
    REQUIRE(run.size() == 1);
    checkHold(run[0]);
}

TEST_CASE("Bullet: a box on a ramp slides with a = g (sin - mu_d cos)", "[reference]") {
    const auto run = bulletRun(rampScene(kSlideAngle, kSlideMuS, kSlideMuD), 1000);
    REQUIRE(run.size() == 1);
    checkSlide(run[0]);
}

TEST_CASE("Bullet: a stack of three boxes stays put", "[reference]") {
    checkStack(bulletRun(stackScene(), 2000));
}

TEST_CASE("Bullet: a body with off-diagonal inertia is refused by name", "[reference]") {
    Scene scene = dropScene(Shape::Box, kDropM);
    std::vector<SceneObject> objects(scene.objects().begin(), scene.objects().end());
    objects[1].body.inertia[0][1] = 1e-6;
    CHECK_THROWS_WITH(runBullet(Scene(scene.bounds(), objects), 1),
                      Catch::Contains("object 1") && Catch::Contains("off-diagonal inertia"));
}

TEST_CASE("hapto vs Bullet: free fall is the same integrator before any contact", "[reference]") {
    const Scene scene = dropScene(Shape::Box, kDropM);
    const auto bullet = bulletRun(scene, 100); // lands at 143 ms
    const auto hapto = haptoRun(scene, 100);
    REQUIRE(hapto.size() == 1);
    for (std::size_t i = 0; i < hapto[0].samples.size(); ++i) {
        INFO("t = " << hapto[0].samples[i].timeS << " s");
        CHECK(glm::length(hapto[0].samples[i].position - bullet[0].samples[i].position) <= 1e-9);
        CHECK(glm::length(hapto[0].samples[i].velocity - bullet[0].samples[i].velocity) <= 1e-9);
    }
}

TEST_CASE("hapto vs Bullet: a dropped box lands and rests as Bullet's does", "[reference]") {
    const Scene scene = dropScene(Shape::Box, kDropM);
    const auto hapto = haptoRun(scene, 1000);
    const auto bullet = bulletRun(scene, 1000);
    REQUIRE(hapto.size() == 1);
    checkDrop(hapto[0], kBoxEdgeM / 2);
    CHECK(std::abs(landingTimeS(hapto[0]) - landingTimeS(bullet[0])) <= 2 * kDt);
}

TEST_CASE("hapto vs Bullet: a dropped sphere lands and rests as Bullet's does", "[reference]") {
    const Scene scene = dropScene(Shape::Sphere, kDropM);
    const auto hapto = haptoRun(scene, 1000);
    const auto bullet = bulletRun(scene, 1000);
    REQUIRE(hapto.size() == 1);
    checkDrop(hapto[0], kSphereRadiusM);
    CHECK(std::abs(landingTimeS(hapto[0]) - landingTimeS(bullet[0])) <= 2 * kDt);
}

TEST_CASE("hapto vs Bullet: a sphere with restitution e bounces to e^2 h", "[reference]") {
    const Scene scene = dropScene(Shape::Sphere, kDropM, 0.5);
    const auto hapto = haptoRun(scene, 400);
    const auto bullet = bulletRun(scene, 400);
    REQUIRE(hapto.size() == 1);
    checkBounce(hapto[0], 0.5);
    const double h = apexAfter(hapto[0], landingTimeS(hapto[0]));
    const double b = apexAfter(bullet[0], landingTimeS(bullet[0]));
    INFO("hapto's apex " << h << " m, Bullet's " << b << " m");
    CHECK(std::abs(h - b) <= 0.05 * 0.25 * kDropM);
}

TEST_CASE("hapto vs Bullet: a box on a ramp holds when mu_s exceeds tan(theta)", "[reference]") {
    const auto hapto = haptoRun(rampScene(kHoldAngle, 0.6, 0.5), 1000);
    REQUIRE(hapto.size() == 1);
    checkHold(hapto[0]);
}

TEST_CASE("hapto vs Bullet: a box on a ramp slides as far as Bullet's in 1 s", "[reference]") {
    const Scene scene = rampScene(kSlideAngle, kSlideMuS, kSlideMuD);
    const auto hapto = haptoRun(scene, 1000);
    const auto bullet = bulletRun(scene, 1000);
    REQUIRE(hapto.size() == 1);
    checkSlide(hapto[0]);
    const double h = rampDisplacementM(hapto[0], kSlideAngle);
    const double b = rampDisplacementM(bullet[0], kSlideAngle);
    INFO("hapto slid " << h << " m, Bullet " << b << " m");
    CHECK(std::abs(h - b) <= 0.02 * kSlideAccel / 2);
}

TEST_CASE("hapto vs Bullet: a stack of three boxes stays put as Bullet's does",
          "[reference][threads]") {
    checkStack(haptoRun(stackScene(), 2000));
}
