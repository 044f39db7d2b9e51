// The dynamics solver in step mode against analytic mechanics: free fall, resting, stacking,
// the friction ramp, restitution, rolling and tipping, no tunnelling, exact impulses, energy
// that never grows, sleeping and bit-identical runs. Every bound is stated where it is used,
// with why it is that size. Steps are 1 ms (the default 1 kHz) unless a case says otherwise.

#include "DynamicsTestScenes.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <numbers>

using namespace hapto;
using namespace hapto::test;

namespace {
constexpr double kDt = 1e-3;

// The local y axis of a body in the world.
Vec3 upAxis(const BodyState& b) {
    return b.orientation * Vec3(0, 1, 0);
}

// Total kinetic plus potential energy of every body (J).
double totalEnergy(const Dynamics& d) {
    double e = 0.0;
    for (std::size_t i = 0; i < d.bodyCount(); ++i) {
        e += d.energyJ(i);
    }
    return e;
}
} // namespace

TEST_CASE("free fall lands at sqrt(2h/g)", "[dynamics]") {
    const double h = 0.1, r = 0.02;
    World w({floorBox(1), dynamicSphere(2, Vec3(0, h + r, 0), r, 0.1)}, Vec3(0, -kG, 0), awake());
    double landed = -1.0, fastest = 0.0;
    for (int k = 1; k <= 400 && landed < 0.0; ++k) {
        w.dynamics->step();
        fastest = std::min(fastest, w.body(0).velocity.y);
        // Landed: the fall's speed (about 1.4 m/s) is gone at once, not by gravity.
        if (fastest < -1.0 && w.body(0).velocity.y > -0.1) {
            landed = k * kDt;
        }
    }
    // Symplectic Euler falls g dt^2 k(k+1)/2 in k steps (half a step ahead of the exact
    // parabola), and the speculative contact stops the body at the surface within the step it
    // would cross it: the landing step is within 2 dt of the exact time.
    CHECK(landed == Approx(std::sqrt(2.0 * h / kG)).margin(2.0 * kDt));
    CHECK(w.body(0).position.y == Approx(r).margin(2e-4)); // on the floor, within the slop
}

TEST_CASE("a box at rest on the floor stays for 5 s", "[dynamics]") {
    const Vec3 start(0.1, 0.02, -0.05);
    World w({floorBox(1), dynamicBox(2, start, Vec3(0.03, 0.02, 0.025), 0.3, frictionOf(0.5, 0.4))},
            Vec3(0, -kG, 0), awake());
    double lowest = start.y;
    double drift = 0.0;
    for (int k = 0; k < 5000; ++k) {
        w.dynamics->step();
        lowest = std::min(lowest, w.body(0).position.y);
        drift = std::max(
            drift, std::hypot(w.body(0).position.x - start.x, w.body(0).position.z - start.z));
    }
    // Sink: at most the penetration slop (1e-4 m, left uncorrected on purpose) plus one
    // step's fall under gravity (g dt^2 = 1e-5 m).
    CHECK(start.y - lowest <= 1e-4 + 1e-5);
    // Drift: nothing pushes it sideways; anchors hold it. 1 um is 1000x below what a hand feels.
    CHECK(drift < 1e-6);
    CHECK(glm::length(upAxis(w.body(0)) - Vec3(0, 1, 0)) < 1e-6); // no tilt
    CHECK(w.dynamics->stats(0).deepestPenetrationM <= 1e-4 + 1e-5);
}

TEST_CASE("a stack of three boxes stays for 5 s", "[dynamics][threads]") {
    const double hh = 0.02;
    std::vector<SceneObject> o{floorBox(1)};
    for (int k = 0; k < 3; ++k) {
        o.push_back(dynamicBox(2 + k, Vec3(0.001 * k, hh + 2 * hh * k, 0), Vec3(0.03, hh, 0.03),
                               0.2, frictionOf(0.6, 0.5)));
    }
    World w(std::move(o), Vec3(0, -kG, 0), awake());
    w.run(0.5); // the boxes, placed exactly touching, settle into their contacts' slop
    std::vector<Vec3> settled;
    for (std::size_t k = 0; k < 3; ++k) {
        settled.push_back(w.body(k).position);
    }
    w.run(4.5);
    for (int k = 0; k < 3; ++k) {
        const BodyState& b = w.body(static_cast<std::size_t>(k));
        INFO("box " << k);
        // Each contact may rest up to the slop (1e-4 m) deep plus a step's fall (1e-5 m):
        // box k sinks at most (k + 1) times that.
        CHECK(b.position.y >= hh + 2 * hh * k - (k + 1) * 1.1e-4);
        // Settling shifts a box sideways by less than the slop it sinks into (the offset
        // stack's uneven contact loads tilt it by microradians) ...
        CHECK(std::abs(b.position.x - 0.001 * k) < 1e-4);
        CHECK(std::abs(b.position.z) < 1e-4);
        // ... and then nothing creeps: static anchors hold each box to a tenth of a micrometre.
        CHECK(glm::length(b.position - settled[static_cast<std::size_t>(k)]) < 1e-7);
        CHECK(glm::dot(upAxis(b), Vec3(0, 1, 0)) > 1.0 - 1e-6);
    }
}

namespace {
// A box resting on a ramp inclined by theta about z; returns the distance it moved down the
// slope and its speed along it after `seconds`.
std::pair<double, double> rampRun(double theta, double muS, double muD, double seconds) {
    const Quat tilt = glm::angleAxis(theta, Vec3(0, 0, 1));
    const Vec3 down = tilt * Vec3(-1, 0, 0); // down the slope
    const Vec3 n = tilt * Vec3(0, 1, 0);
    const double half = 0.02;
    World w({makeBox(1, tilt * Vec3(0, -0.05, 0), Vec3(1.0, 0.05, 0.3), tilt, frictionOf(muS, muD)),
             dynamicBox(2, n * half, Vec3(half), 0.2, frictionOf(muS, muD), tilt)},
            Vec3(0, -kG, 0), awake());
    const Vec3 start = w.body(0).position;
    w.run(seconds);
    return {glm::dot(w.body(0).position - start, down), glm::dot(w.body(0).velocity, down)};
}
} // namespace

TEST_CASE("a box on a ramp holds when mu_s > tan(theta)", "[dynamics]") {
    const double theta = 20.0 * std::numbers::pi / 180.0; // tan = 0.364
    const auto [moved, speed] = rampRun(theta, 0.45, 0.3, 2.0);
    // Static friction with an anchor: no creep beyond what one step's drift correction leaves
    // (well under a micrometre).
    CHECK(std::abs(moved) < 1e-6);
    CHECK(std::abs(speed) < 1e-4);
}

TEST_CASE("a box on a ramp slides with a = g(sin - mu_d cos) when mu_s < tan(theta)",
          "[dynamics]") {
    const double theta = 25.0 * std::numbers::pi / 180.0; // tan = 0.466
    const double muD = 0.2, t = 0.5;
    const double a = kG * (std::sin(theta) - muD * std::cos(theta));
    const auto [moved, speed] = rampRun(theta, 0.3, muD, t);
    // The first step still uses mu_s (it was sticking): that costs at most (mu_s - mu_d) g
    // cos dt^2 of distance; 1 % covers it and Euler's step error (dt / t = 0.2 %).
    CHECK(speed == Approx(a * t).epsilon(0.01));
    CHECK(moved == Approx(0.5 * a * t * t).epsilon(0.01));
}

TEST_CASE("restitution e bounces to e^2 h", "[dynamics]") {
    for (const double e : {0.5, 0.8, 1.0}) {
        const double h = 0.1, r = 0.01;
        World w({floorBox(1), dynamicSphere(2, Vec3(0, h + r, 0), r, 0.05, {}, e)}, Vec3(0, -kG, 0),
                awake());
        bool bounced = false;
        double apex = 0.0;
        for (int k = 0; k < 600; ++k) {
            w.dynamics->step();
            const BodyState& b = w.body(0);
            bounced = bounced || b.velocity.y > 0.0;
            if (bounced) {
                apex = std::max(apex, b.position.y - r);
                if (b.velocity.y < 0.0) {
                    break;
                }
            }
        }
        INFO("e = " << e);
        // The bounce happens in the step the ball would reach the floor, up to one step's fall
        // (v dt = 1.4 mm at 1.4 m/s) above it, plus Euler's dt-order error: 2 mm.
        CHECK(apex == Approx(e * e * h).margin(2e-3));
        // Never higher than it fell from, up to symplectic Euler's one-step offset between the
        // discrete and the exact parabola (g dt^2 = 1e-5 m).
        CHECK(apex <= h + kG * kDt * kDt);
    }
}

TEST_CASE("a sphere and a box thrown at 2 m/s do not pass a 2 mm slab", "[dynamics]") {
    const double face = 0.05 - 0.001; // the slab spans x in [0.049, 0.051]
    for (const bool sphere : {true, false}) {
        SceneObject body = sphere ? dynamicSphere(2, Vec3(0, 0, 0), 0.01, 0.05)
                                  : dynamicBox(2, Vec3(0, 0, 0), Vec3(0.01), 0.05);
        body.body.velocity = Vec3(2.0, 0.0, 0.0);
        World w({makeBox(1, Vec3(0.05, 0, 0), Vec3(0.001, 0.1, 0.1)), body}, Vec3(0.0), awake());
        double farthest = -1.0;
        for (int k = 0; k < 200; ++k) {
            w.dynamics->step();
            farthest = std::max(farthest, w.body(0).position.x);
        }
        INFO((sphere ? "sphere" : "box"));
        // The leading face never passes the slab's near face by more than the slop.
        CHECK(farthest + 0.01 <= face + 1e-4);
        CHECK(w.body(0).position.x < face); // still on the near side
    }
}

TEST_CASE("a sphere sliding on the floor ends rolling at 5/7 of its speed", "[dynamics]") {
    const double r = 0.02, v0 = 0.5;
    SceneObject ball = dynamicSphere(2, Vec3(0, r, 0), r, 0.1, frictionOf(0.5, 0.3));
    ball.body.velocity = Vec3(v0, 0, 0);
    World w({floorBox(1, frictionOf(0.5, 0.3)), ball}, Vec3(0, -kG, 0), awake());
    w.run(1.0); // sliding ends after 2 v0 / (7 mu_d g) = 0.05 s
    // A solid sphere: friction's impulse J gives v = v0 - J/m and w r = 5 J / (2 m): they meet
    // at v = 5/7 v0 (angular momentum about the contact point is conserved).
    CHECK(w.body(0).velocity.x == Approx(5.0 / 7.0 * v0).epsilon(0.01));
    CHECK(-w.body(0).angularVelocity.z * r == Approx(w.body(0).velocity.x).epsilon(0.01));
}

TEST_CASE("a box tipped past its balance falls over, one short of it rights itself", "[dynamics]") {
    const Vec3 half(0.01, 0.03, 0.01); // balance angle atan(0.01 / 0.03) = 18.4 degrees
    for (const double degrees : {10.0, 25.0}) {
        const Quat tilt = glm::angleAxis(degrees * std::numbers::pi / 180.0, Vec3(0, 0, 1));
        // Rest the box on its edge at x = 0: the corner (+hx, -hy) rotated lies on the floor.
        const Vec3 corner = tilt * Vec3(half.x, -half.y, 0.0);
        World w({floorBox(1), dynamicBox(2, -corner, half, 0.1, frictionOf(0.9, 0.8), tilt)},
                Vec3(0, -kG, 0), awake());
        w.run(2.0);
        const double upright = glm::dot(upAxis(w.body(0)), Vec3(0, 1, 0));
        INFO(degrees << " degrees");
        if (degrees < 18.4) {
            CHECK(upright > 1.0 - 1e-4);
        } else {
            CHECK(std::abs(upright) < 1e-3); // lying on its side
        }
    }
}

TEST_CASE("applyImpulse changes momentum exactly", "[dynamics]") {
    SceneObject box = dynamicBox(2, Vec3(0.0), Vec3(0.01, 0.02, 0.03), 0.25);
    World w({box}, Vec3(0.0), awake());
    const Vec3 linear(0.01, -0.02, 0.005), angular(1e-4, 2e-4, -3e-4);
    w.dynamics->applyImpulse(0, linear, angular);
    w.dynamics->step();
    const BodyState& b = w.body(0);
    CHECK(glm::length(b.velocity * 0.25 - linear) < 1e-15);
    // Angular momentum I_world w, from the tensor the box was given.
    const Mat3 r = glm::mat3_cast(Quat(1, 0, 0, 0));
    const Vec3 momentum = r * box.body.inertia * glm::transpose(r) * b.angularVelocity;
    CHECK(glm::length(momentum - angular) < 1e-15);
    // The hands' work is counted: no energy gain net of it.
    CHECK(w.dynamics->stats(0).largestEnergyGainJ < 1e-15);
}

TEST_CASE("energy never grows in a closed box of bouncing bodies", "[dynamics][threads]") {
    World w(closedBoxScene(), Vec3(0, -kG, 0), awake());
    const double start = totalEnergy(*w.dynamics);
    double mass = 0.0;
    for (std::size_t i = 0; i < w.dynamics->bodyCount(); ++i) {
        mass += w.scene->object(w.body(i).slot).body.massKg;
    }
    double highest = start;
    for (int k = 0; k < 3000; ++k) {
        w.dynamics->step();
        highest = std::max(highest, totalEnergy(*w.dynamics));
    }
    double deepest = 0.0;
    for (std::size_t i = 0; i < w.dynamics->bodyCount(); ++i) {
        deepest = std::max(deepest, w.dynamics->stats(i).deepestPenetrationM);
    }
    // Contacts add nothing; the one source of gain is the split impulse lifting a body out of
    // an overlap, worth at most m g (depth) per body: the bound.
    CHECK(highest - start <= mass * kG * deepest + 1e-12);
    CHECK(totalEnergy(*w.dynamics) < start); // e = 0.5 bodies and friction dissipate
    CHECK(deepest < 2e-3);
}

TEST_CASE("two stepped runs are byte-identical", "[dynamics][threads]") {
    World a(closedBoxScene()), b(closedBoxScene());
    a.run(1.0);
    b.run(1.0);
    REQUIRE(a.dynamics->bodyCount() == b.dynamics->bodyCount());
    CHECK(std::memcmp(a.dynamics->bodies().data(), b.dynamics->bodies().data(),
                      sizeof(BodyState) * a.dynamics->bodyCount()) == 0);
}

TEST_CASE("the same steps whatever the index", "[dynamics][threads]") {
    // The broad phase sorts each body's candidates by item, so the index's kind and leaf
    // order cannot change a contact or its order: the states agree bit for bit.
    World octree(closedBoxScene()), grid(closedBoxScene(), Vec3(0, -kG, 0), {}, 1000.0, "grid:7"),
        brute(closedBoxScene(), Vec3(0, -kG, 0), {}, 1000.0, "brute");
    for (World* w : {&octree, &grid, &brute}) {
        w->run(1.0);
    }
    const std::size_t bytes = sizeof(BodyState) * octree.dynamics->bodyCount();
    CHECK(std::memcmp(octree.dynamics->bodies().data(), grid.dynamics->bodies().data(), bytes) ==
          0);
    CHECK(std::memcmp(octree.dynamics->bodies().data(), brute.dynamics->bodies().data(), bytes) ==
          0);
}

/// A floor strewn with a 20 x 20 field of static 5 mm cubes 1 cm apart (401 static items),
/// a sphere rolling and a box sliding across it, and a sphere dropped onto it.
std::vector<SceneObject> cubeFieldScene() {
    std::vector<SceneObject> o{floorBox(1)};
    for (int i = 0; i < 20; ++i) {
        for (int k = 0; k < 20; ++k) {
            o.push_back(makeBox(static_cast<ObjectId>(2 + 20 * i + k),
                                Vec3(-0.095 + 0.01 * i, 0.0025, -0.095 + 0.01 * k), Vec3(0.0025),
                                glm::angleAxis(0.1 * (i + k), Vec3(0, 1, 0)),
                                frictionOf(0.5, 0.4)));
        }
    }
    SceneObject rolling = dynamicSphere(500, Vec3(-0.12, 0.016, 0.0), 0.01, 0.05);
    rolling.body.velocity = Vec3(0.6, 0.0, 0.15);
    SceneObject sliding = dynamicBox(501, Vec3(0.0, 0.016, -0.12), Vec3(0.01), 0.1);
    sliding.body.velocity = Vec3(0.1, 0.0, 0.5);
    o.push_back(rolling);
    o.push_back(sliding);
    o.push_back(dynamicSphere(502, Vec3(0.03, 0.08, 0.03), 0.008, 0.03));
    return o;
}

TEST_CASE("a body's cached index query gives the steps a direct query gives",
          "[dynamics][threads]") {
    // The octree's bodies keep a cached query (a few dozen items near them, asked again after
    // moving 5 mm); brute force's one leaf holds all 401 items, more than a cache holds, so
    // its bodies ask the index directly every step. The candidates must be the same items in
    // the same order, and so the states the same bits.
    World cached(cubeFieldScene(), Vec3(0, -kG, 0), awake()),
        direct(cubeFieldScene(), Vec3(0, -kG, 0), awake(), 1000.0, "brute");
    const Vec3 start = cached.body(0).position;
    const std::size_t bytes = sizeof(BodyState) * cached.dynamics->bodyCount();
    for (int k = 0; k < 1000; ++k) {
        cached.dynamics->step();
        direct.dynamics->step();
        REQUIRE(std::memcmp(cached.dynamics->bodies().data(), direct.dynamics->bodies().data(),
                            bytes) == 0);
    }
    CHECK(glm::length(cached.body(0).position - start) > 0.05); // many caches made, not one
    CHECK(cached.dynamics->droppedContacts() == 0);
}

TEST_CASE("a box comes to rest on a closed triangle-mesh floor", "[dynamics]") {
    // The floor is the mesh of a 2 m x 10 cm x 2 m box: its top face is two triangles.
    SceneObject slab = makeBox(1, Vec3(0, -0.05, 0), Vec3(1.0, 0.05, 1.0));
    SceneObject mesh = meshOfBox(slab);
    World w({mesh, dynamicBox(2, Vec3(0.1, 0.03, 0.05), Vec3(0.02), 0.2, frictionOf(0.5, 0.4))},
            Vec3(0, -kG, 0), awake());
    w.run(1.0);
    // Dropped 1 cm: it lands, stays level and rests within the slop of the plane y = 0.
    CHECK(w.body(0).position.y == Approx(0.02).margin(1.1e-4));
    CHECK(std::abs(w.body(0).velocity.y) < 1e-6);
    CHECK(glm::dot(upAxis(w.body(0)), Vec3(0, 1, 0)) > 1.0 - 1e-6);
}

TEST_CASE("a body at rest falls asleep and wakes by an impulse or a touch", "[dynamics]") {
    World w({floorBox(1), dynamicBox(2, Vec3(0, 0.02, 0), Vec3(0.02), 0.2, frictionOf(0.5, 0.4)),
             dynamicSphere(3, Vec3(0.1, 0.2, 0), 0.01, 0.05)});
    w.run(0.3);
    CHECK_FALSE(w.body(0).sleeping); // sleepAfterS = 0.5 s has not passed
    w.run(0.5);
    CHECK(w.body(0).sleeping);
    const Vec3 rest = w.body(0).position;
    w.dynamics->applyImpulse(0, Vec3(0.02, 0, 0), Vec3(0.0));
    CHECK_FALSE(w.body(0).sleeping);
    w.dynamics->step();
    CHECK(w.body(0).position.x > rest.x);
    w.run(2.0); // it slides to rest and sleeps again; the ball sleeps on the floor
    CHECK(w.body(0).sleeping);
    CHECK(w.body(1).sleeping);
    // A ball thrown at the sleeping box wakes it.
    w.dynamics->applyImpulse(1, Vec3(-0.1, 0.0, 0.0), Vec3(0.0));
    bool woke = false;
    for (int k = 0; k < 500 && !woke; ++k) {
        w.dynamics->step();
        woke = !w.body(0).sleeping;
    }
    CHECK(woke);
}

TEST_CASE("a body woken on the floor by a light touch starts warm with no sideways jolt",
          "[dynamics]") {
    // A sleeping body keeps the manifolds it rests on (carrySleepingPatches), so waking it
    // warm-starts its supports and friction anchors. Solved cold, the first steps awake slid
    // this box 6.3 nm sideways (a hand resting on its side face found itself inside it); warm,
    // 3.5 pm. Bound: 0.1 nm.
    World w({floorBox(1), dynamicBox(2, Vec3(0, 0.02, 0), Vec3(0.02), 0.2, frictionOf(0.5, 0.4))});
    w.run(0.8);
    REQUIRE(w.body(0).sleeping);
    w.run(1.0); // asleep for a second
    // A hand's light touch straight down (1 mN for 1 ms) wakes it.
    w.dynamics->applyImpulse(0, Vec3(0.0, -1e-6, 0.0), Vec3(0.0));
    double sideways = 0.0; // the largest sideways move of one step (m)
    Vec3 before = w.body(0).position;
    for (int k = 0; k < 10; ++k) {
        w.dynamics->step();
        const Vec3 d = w.body(0).position - before;
        sideways = std::max(sideways, std::hypot(d.x, d.z));
        before = w.body(0).position;
    }
    CHECK_FALSE(w.body(0).sleeping);
    CHECK(sideways < 1e-10);
}

TEST_CASE("a zero impulse every step wakes nothing: a body left alone still falls asleep",
          "[dynamics]") {
    // The runtime's dynamics step hands every body its accumulated impulse each step, most
    // often zero (DynamicsLoop.cpp, takeImpulses).
    World w({floorBox(1), dynamicBox(2, Vec3(0, 0.02, 0), Vec3(0.02), 0.2, frictionOf(0.5, 0.4))});
    for (int k = 0; k < 800; ++k) {
        w.dynamics->applyImpulse(0, Vec3(0.0), Vec3(0.0));
        w.dynamics->applyHandTorsion(0, Mat3(0.0));
        w.dynamics->step();
    }
    CHECK(w.body(0).sleeping);
    w.dynamics->applyImpulse(0, Vec3(0.0), Vec3(0.0));
    CHECK(w.body(0).sleeping);
    w.dynamics->applyImpulse(0, Vec3(0.0, 1e-9, 0.0), Vec3(0.0)); // any impulse wakes it
    CHECK_FALSE(w.body(0).sleeping);
}
