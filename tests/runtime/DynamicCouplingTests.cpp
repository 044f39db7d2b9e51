// The hands and the dynamic bodies, in step mode: a servo step renders a dynamic body from the
// BodyPoseTable and hands the reaction of its contact force back to it (Newton's third law, to
// the table's fixed-point quantum), a hand feels a body resting on the floor, a body squeezed
// between two clamped hands never gains energy, and a servo tick in contact allocates nothing.
//
// The rig drives ServoStep directly with its own BodyPoseTable and a stepper of its own, in
// the order the runtime's step mode runs them at each instant: the dynamics step takes the
// impulses the servo ticks handed back since the last one, steps, publishes every pose; then
// the servo ticks due at that instant run. The stepper (Stepper below) is the dynamics step
// with nothing but the hands' impulses and gravity: symplectic Euler of each centre of mass
// (v += J / m + g h, x += v h), the orientation held, as DESIGN's coupling analysis assumes;
// the solver's own contacts are the dynamics tests' business, not these.
//
// A second rig (RealRig) steps the real Dynamics instead, in the same order, taking each body's
// torsional-friction budget too (as the runtime's dynamics step does): the angular impulse a
// body gets from hands pressing off its centre, the hands' torsional friction (soft-finger
// patch: a held box does not spin under a torque below mu (F1 + F2) r, spins freely without the
// patch, slips at the Coulomb rate above it) and its passivity, and the device file's
// `renderer.torsion_radius_m`.

#include "CountingNew.h"

#include "hapto/dynamics/Dynamics.h"
#include "hapto/io/InputError.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/ServoStep.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/SceneObject.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

using namespace hapto;

namespace {

/// A hand that holds still at one point (world = device frame) and keeps the last force.
class HeldDevice : public Device {
public:
    explicit HeldDevice(Vec3 at) : mAt(at) {}
    std::string_view name() const override { return "held"; }
    DeviceKind kind() const override { return DeviceKind::Scripted; }
    DeviceCapabilities capabilities() const override {
        return {"held test hand", Aabb{Vec3(-1), Vec3(1)}, 100.0, 0.0, 1000.0, 0};
    }
    DeviceStatus open() override { return DeviceStatus::Ok; }
    void close() override {}
    DeviceStatus read(DeviceState& state) noexcept override {
        state = DeviceState{};
        state.position = mAt;
        state.hasVelocity = true; // clamped: it does not move
        return DeviceStatus::Ok;
    }
    DeviceStatus write(const Vec3& forceN) noexcept override {
        lastForce = forceN;
        return DeviceStatus::Ok;
    }
    std::string errorMessage() const override { return {}; }
    /// Holds still somewhere else from the next read on.
    void moveTo(Vec3 at) { mAt = at; }

    Vec3 lastForce{0.0}; ///< The last force written (N).

private:
    Vec3 mAt;
};

/// A dynamic box: mass (kg), its inertia, stiffness (N/m), friction mu_s = mu_d = `mu`.
SceneObject dynamicBox(ObjectId id, Vec3 center, Vec3 half, double massKg, double stiffness,
                       double mu, Vec3 velocity = Vec3(0.0)) {
    Material material;
    material.stiffness = stiffness;
    material.staticFriction = mu;
    material.dynamicFriction = mu;
    SceneObject o = makeBox(id, center, half, Quat(1, 0, 0, 0), material);
    o.body.dynamic = true;
    o.body.massKg = massKg;
    o.body.inertia = Mat3(0.0);
    o.body.inertia[0][0] = massKg / 3.0 * (half.y * half.y + half.z * half.z);
    o.body.inertia[1][1] = massKg / 3.0 * (half.x * half.x + half.z * half.z);
    o.body.inertia[2][2] = massKg / 3.0 * (half.x * half.x + half.y * half.y);
    o.body.velocity = velocity;
    return o;
}

/// The dynamics step reduced to what the coupling needs: each dynamic object's centre of mass
/// under gravity and the impulses handed to it (symplectic Euler), its orientation held.
struct Stepper {
    struct Body {
        std::uint32_t slot = 0;
        double massKg = 0.0;
        Vec3 position{0.0}; ///< Centre of mass (m).
        Vec3 velocity{0.0}; ///< (m/s).
        Vec3 pending{0.0};  ///< Impulse for the next step (N s).
    };
    std::vector<Body> bodies;
    Vec3 gravity{0.0};
    double dtS = 1e-3;
    std::uint64_t steps = 0;

    Stepper(const Scene& scene, double stepS) : gravity(scene.physics().gravity), dtS(stepS) {
        for (std::uint32_t slot = 0; slot < scene.size(); ++slot) {
            const SceneObject& o = scene.object(slot);
            if (o.body.dynamic) {
                bodies.push_back({slot, o.body.massKg, o.center, o.body.velocity, Vec3(0.0)});
            }
        }
    }
    void step() {
        for (Body& b : bodies) {
            b.velocity += b.pending / b.massKg + gravity * dtS;
            b.pending = Vec3(0.0);
            b.position += b.velocity * dtS;
        }
        ++steps;
    }
};

/// One servo (a held hand) and what it shares.
struct Hand {
    HeldDevice device;
    ServoStepShared shared;
    ServoStep step;
    Hand(Vec3 at, const SafetyConfig& safety, const RendererConfig& renderer = {})
        : device(at), step(renderer, safety) {}
    /// A hand at `at` whose servo step is started on `world`'s clock, every `periodNs`, with
    /// the bodies of `table`.
    static std::unique_ptr<Hand> started(Vec3 at, const SafetyConfig& safety,
                                         const RendererConfig& renderer, World& world,
                                         ManualClock& clock, BodyPoseTable& table,
                                         std::uint64_t periodNs) {
        auto hand = std::make_unique<Hand>(at, safety, renderer);
        ServoStep& s = hand->step;
        s.setTiming(periodNs, 3, 0.5, 100'000'000);
        s.device = &hand->device;
        s.reader = world.registerReader();
        s.ports = hand->shared.portsFor(world, &clock);
        s.ports.bodies = &table;
        s.start(clock.nowNs());
        return hand;
    }
};

/// The scene, its world and dynamics, the pose table and the hands, on one manual clock.
struct CouplingRig {
    static constexpr std::uint64_t kPeriodNs = 1'000'000; // servo and dynamics: 1 kHz

    ManualClock clock;
    std::shared_ptr<const Scene> scene;
    World world;
    Stepper dynamics;
    BodyPoseTable table;
    std::vector<std::unique_ptr<Hand>> hands;
    Vec3 impulseTaken{0.0};     ///< Every linear impulse taken from the table (N s).
    Vec3 handForceTimesDt{0.0}; ///< Sum of every force written x dt (N s).

    CouplingRig(std::vector<SceneObject> objects, Vec3 gravity, std::vector<Vec3> handPoints,
                SafetyConfig safety = unlimitedSafety())
        : scene(makeScene(std::move(objects), gravity)), world(scene, IndexSpec::parse("brute")),
          dynamics(*scene, static_cast<double>(kPeriodNs) * 1e-9), table(dynamics.bodies.size()) {
        world.useClock(clock);
        publish();
        for (const Vec3& at : handPoints) {
            hands.push_back(
                Hand::started(at, safety, RendererConfig{}, world, clock, table, kPeriodNs));
        }
    }

    /// The safety filter out of the way: no rate limit (a lag in the force is not passive),
    /// a clamp far above the forces here.
    static SafetyConfig unlimitedSafety() {
        SafetyConfig s;
        s.maxForceN = 1000.0;
        s.maxForceStepN = std::numeric_limits<double>::infinity();
        return s;
    }
    static std::shared_ptr<const Scene> makeScene(std::vector<SceneObject> objects, Vec3 g) {
        auto s = std::make_shared<Scene>(Aabb{Vec3(-0.2), Vec3(0.2)}, std::move(objects));
        ScenePhysics physics;
        physics.gravity = g;
        physics.rateHz = 1e9 / static_cast<double>(kPeriodNs);
        s->setPhysics(physics);
        return s;
    }

    /// Every body's state into the table, at the clock's time.
    void publish() {
        for (std::size_t i = 0; i < dynamics.bodies.size(); ++i) {
            const Stepper::Body& b = dynamics.bodies[i];
            BodyPose pose;
            pose.center = b.position; // the boxes' centre of mass is their centre
            pose.centerOfMass = b.position;
            pose.velocity = b.velocity;
            pose.timeNs = clock.nowNs();
            pose.step = dynamics.steps;
            table.publish(i, pose);
        }
    }

    /// One instant, one period on: the dynamics step (with the impulses handed back), its
    /// poses published, then every hand's servo tick.
    void advance() {
        clock.set(clock.nowNs() + kPeriodNs);
        for (std::size_t i = 0; i < dynamics.bodies.size(); ++i) {
            Vec3 angular;
            Vec3& linear = dynamics.bodies[i].pending;
            table.takeImpulse(i, linear, angular);
            impulseTaken += linear;
        }
        dynamics.step();
        publish();
        tickHands();
    }
    /// Every hand's servo tick at the current instant.
    void tickHands() {
        for (auto& h : hands) {
            REQUIRE(h->step.deadlineNs == clock.nowNs());
            REQUIRE(h->step.run(h->step.deadlineNs));
            handForceTimesDt += h->device.lastForce * h->step.dtS;
        }
    }
    /// The body's kinetic energy plus the contact springs' energy, 1/2 k |proxy - device|^2
    /// per hand (J), at the current instant.
    double energy(double stiffness) const {
        const Stepper::Body& b = dynamics.bodies[0];
        double e = 0.5 * b.massKg * glm::dot(b.velocity, b.velocity);
        for (const auto& h : hands) {
            const Vec3 d = h->step.haptic.proxy() - h->step.lastPosition;
            e += 0.5 * stiffness * glm::dot(d, d);
        }
        return e;
    }
};

/// The same instants as CouplingRig, with the real Dynamics: each step takes every body's
/// impulse and torsional budget from the table (applyImpulse, then applyHandTorsion, as the
/// runtime's dynamics step does), steps, publishes; then the hands tick. `disturbanceNms` is
/// added to body 0 each step as an angular impulse through the table, as an application would.
struct RealRig {
    static constexpr std::uint64_t kPeriodNs = CouplingRig::kPeriodNs;
    static constexpr double kDtS = 1e-3;

    ManualClock clock;
    std::shared_ptr<const Scene> scene;
    World world;
    Dynamics dynamics;
    BodyPoseTable table;
    std::vector<std::unique_ptr<Hand>> hands;
    Vec3 disturbanceNms{0.0};  ///< Angular impulse added to body 0 each step (N m s).
    double torsionTaken = 0.0; ///< Sum of the budgets' traces taken (N m s).

    /// The hands start at `startPoints` (outside the bodies: a proxy starts on its device
    /// point), tick once there, and are then held at `heldPoints`.
    RealRig(std::vector<SceneObject> objects, std::vector<Vec3> startPoints,
            std::vector<Vec3> heldPoints, const RendererConfig& renderer)
        : scene(CouplingRig::makeScene(std::move(objects), Vec3(0.0))),
          world(scene, IndexSpec::parse("brute")), dynamics(scene, world.current().index),
          table(dynamics.bodyCount()) {
        world.useClock(clock);
        publish();
        for (const Vec3& at : startPoints) {
            hands.push_back(Hand::started(at, CouplingRig::unlimitedSafety(), renderer, world,
                                          clock, table, kPeriodNs));
        }
        advance();
        for (std::size_t h = 0; h < hands.size(); ++h) {
            hands[h]->device.moveTo(heldPoints[h]);
        }
    }
    void publish() {
        for (std::size_t i = 0; i < dynamics.bodyCount(); ++i) {
            table.publish(i, bodyPoseOf(dynamics, i, clock.nowNs())); // as the dynamics thread
        }
    }
    /// The dynamics step due one period on, then every hand's tick at that instant.
    void advance() {
        clock.set(clock.nowNs() + kPeriodNs);
        if (disturbanceNms != Vec3(0.0)) {
            REQUIRE(table.addImpulse(0, Vec3(0.0), disturbanceNms));
        }
        for (std::size_t i = 0; i < dynamics.bodyCount(); ++i) {
            Vec3 linear(0.0), angular(0.0);
            table.takeImpulse(i, linear, angular);
            const Mat3 torsion = table.takeTorsion(i);
            torsionTaken += torsion[0][0] + torsion[1][1] + torsion[2][2];
            dynamics.applyImpulse(i, linear, angular);
            dynamics.applyHandTorsion(i, torsion);
        }
        dynamics.step();
        publish();
        for (auto& h : hands) {
            REQUIRE(h->step.deadlineNs == clock.nowNs());
            REQUIRE(h->step.run(h->step.deadlineNs));
        }
    }
    /// Body 0's rotational kinetic energy (J), 1/2 w.I w, for a body whose inertia is
    /// isotropic (a cube): I = the scene's Ixx.
    double cubeSpinEnergyJ() const {
        const Vec3 w = dynamics.bodies()[0].angularVelocity;
        return 0.5 * scene->object(dynamics.bodies()[0].slot).body.inertia[0][0] * glm::dot(w, w);
    }
};

/// A renderer whose hand has the effective torsional radius `radiusM` (m).
RendererConfig withTorsion(double radiusM) {
    RendererConfig c;
    c.torsionRadiusM = radiusM;
    return c;
}

} // namespace

TEST_CASE("the impulses a dynamic body receives sum to minus the hand's force times dt") {
    // A 50 g box drifts into a hand held still on its +x side, a little off its centre line
    // (so the contact turns it too) and rebounds; the hand touches nothing else.
    const double k = 2000.0;
    const Vec3 half(0.02, 0.02, 0.02);
    CouplingRig rig({dynamicBox(1, Vec3(0.0), half, 0.05, k, 0.3, Vec3(0.05, 0.0, 0.0))}, Vec3(0.0),
                    {Vec3(0.0205, 0.005, 0.0)});
    std::uint64_t contactTicks = 0;
    for (int i = 0; i < 200; ++i) {
        rig.advance();
        contactTicks += rig.hands[0]->device.lastForce != Vec3(0.0) ? 1 : 0;
    }
    rig.advance(); // the last ticks' impulses taken too
    // The hand was pushed (+x) and the box pushed back (-x): contact happened.
    CHECK(contactTicks > 5);
    CHECK(rig.handForceTimesDt.x > 1e-4);
    CHECK(rig.dynamics.bodies[0].velocity.x < 0.0);
    // Newton's third law: equal to the quantum of each tick's rounding (<= 1/2 quantum each
    // component) and the double sums' rounding.
    const double tolerance =
        static_cast<double>(contactTicks + 1) * BodyPoseTable::kImpulseQuantumNs + 1e-15;
    for (int c = 0; c < 3; ++c) {
        INFO("component " << c);
        CHECK(std::abs(rig.impulseTaken[c] + rig.handForceTimesDt[c]) <= tolerance);
    }
}

TEST_CASE("a dynamic body is rendered where the table says and not where the scene put it") {
    // The scene holds the box at the origin; the table says it is 3 cm along +x, moving. A
    // hand held 1 mm inside the published box's +x face feels it; one at the scene's stale
    // face feels nothing.
    const double k = 1000.0;
    const Vec3 half(0.01, 0.01, 0.01);
    CouplingRig rig({dynamicBox(1, Vec3(0.0), half, 0.1, k, 0.0)}, Vec3(0.0),
                    {Vec3(0.0405, 0.0, 0.0), Vec3(0.0105, 0.0, 0.0)});
    BodyPose moved = rig.table.read(0);
    moved.center = moved.centerOfMass = Vec3(0.03, 0.0, 0.0);
    // It moves +x at 1 m/s: by the next tick (1 ms on) its face is 1 mm further out.
    moved.velocity = Vec3(1.0, 0.0, 0.0);
    moved.timeNs = rig.clock.nowNs();
    rig.table.publish(0, moved);
    rig.clock.set(rig.clock.nowNs() + CouplingRig::kPeriodNs);
    rig.tickHands();
    // Extrapolated 1 ms: the face is at 0.041, the first hand 0.5 mm inside it.
    CHECK(rig.hands[0]->device.lastForce.x ==
          Approx(k * (0.041 + GodObjectRenderer::kSkinM - 0.0405) +
                 GodObjectRenderer::dynamicCouplingDamping(k, 1e-3) * 1.0)
              .epsilon(1e-6));
    CHECK(rig.hands[1]->device.lastForce == Vec3(0.0));
    CHECK(rig.hands[0]->step.haptic.dynamicBodies().count == 1);
    CHECK(rig.hands[1]->step.haptic.dynamicBodies().count == 0);
}

TEST_CASE("a hand pressing on a dynamic box feels it and pushes it away") {
    // A 100 g box at rest beside a static floor slab, no gravity (the stepper here has no
    // contacts: a box resting on the floor under gravity needs the dynamics solver). The hand
    // starts 0.5 mm above its top face, then is held 0.5 mm below it: the first tick feels
    // k x 0.5 mm up, every tick feels the box push up (never pull), and the box is pushed down.
    const double k = 1000.0;
    const Vec3 half(0.02, 0.01, 0.02);
    Material floorMaterial;
    std::vector<SceneObject> objects{
        dynamicBox(1, Vec3(0.0, 0.01, 0.0), half, 0.1, k, 0.5),
        makeBox(2, Vec3(0.0, -0.01, 0.0), Vec3(0.1, 0.01, 0.1), Quat(1, 0, 0, 0), floorMaterial)};
    CouplingRig rig(std::move(objects), Vec3(0.0), {Vec3(0.0, 0.0205, 0.0)});
    rig.advance(); // the proxy starts above the face
    rig.hands[0]->device.moveTo(Vec3(0.0, 0.0195, 0.0));
    const Vec3 before = rig.impulseTaken;
    for (int i = 0; i < 10; ++i) {
        rig.advance();
        const Vec3 f = rig.hands[0]->device.lastForce;
        const double faceY = rig.dynamics.bodies[0].position.y + half.y;
        INFO("tick " << i << ", face at " << faceY << " m, force " << f.y << " N");
        if (i == 0) {
            CHECK(f.y == Approx(k * (0.0005 + GodObjectRenderer::kSkinM)).epsilon(1e-6));
        }
        CHECK(f.y > 0.0);
        // The spring on the face where the box is, less the coupling damping as it recedes.
        CHECK(f.y <= k * (faceY + GodObjectRenderer::kSkinM - 0.0195) + 1e-9);
        CHECK(f.x == 0.0);
        CHECK(f.z == 0.0);
    }
    rig.advance();
    CHECK(rig.impulseTaken.y - before.y < -0.5 * 1e-3);
    CHECK(rig.dynamics.bodies[0].velocity.y < 0.0);
}

TEST_CASE("a body squeezed between two clamped hands never gains energy over 5 s") {
    // The hands hold still (no device damping) on either side of the box, 0.5 mm clear of it;
    // the box drifts into one at 5 cm/s with a sideways 1 cm/s (the contacts' friction takes
    // part), bounces between them and settles. Two cases: a light box (a = sum k h^2 / m =
    // 0.16) and the limit the coupling is made for (a = 1: 20 g between two 10^4 N/m hands).
    struct Case {
        double massKg, stiffness;
    };
    const Case c = GENERATE(Case{0.01, 800.0}, Case{0.02, 10'000.0});
    INFO("m = " << c.massKg << " kg, k = " << c.stiffness << " N/m per hand");
    const Vec3 half(0.02, 0.02, 0.02);
    CouplingRig rig(
        {dynamicBox(1, Vec3(0.0), half, c.massKg, c.stiffness, 0.5, Vec3(0.05, 0.01, 0.0))},
        Vec3(0.0), {Vec3(0.0205, 0.0, 0.0), Vec3(-0.0205, 0.0, 0.0)});
    double last = rig.energy(c.stiffness);
    const double start = last;
    double largestStepRise = 0.0; // over one step
    double highest = last;
    std::uint64_t contactTicks = 0;
    for (int i = 0; i < 5000; ++i) {
        rig.advance();
        const double e = rig.energy(c.stiffness);
        largestStepRise = std::max(largestStepRise, e - last);
        highest = std::max(highest, e);
        last = e;
        contactTicks += rig.hands[0]->device.lastForce != Vec3(0.0) ||
                                rig.hands[1]->device.lastForce != Vec3(0.0)
                            ? 1
                            : 0;
    }
    INFO("start " << start << " J, end " << last << " J, " << contactTicks << " contact ticks");
    CHECK(contactTicks > 10);
    INFO("largest rise over one step " << largestStepRise << " J");
    // Never above where it started, and falling away: beyond the 10 nm skin the proxy rides
    // on (its k x skin force over one step's travel).
    const double v0 = glm::length(Vec3(0.05, 0.01, 0.0));
    CHECK(highest <= start + 2.0 * c.stiffness * GodObjectRenderer::kSkinM * v0 * 1e-3);
    // A step may rise only at a contact's first instant: the body met the held point during
    // the step and the spring's 1/2 k d^2 (d <= v h, the step's travel) was not paid for by
    // the integrator; the coupling damping (c = k h) takes more than that over the next step.
    CHECK(largestStepRise <= 0.5 * c.stiffness * (v0 * 1e-3) * (v0 * 1e-3));
    CHECK(last < 0.5 * start);
}

TEST_CASE("a servo tick in contact with a dynamic body allocates nothing, its torsional patch "
          "on") {
    const double k = 2000.0;
    const Vec3 half(0.02, 0.02, 0.02);
    CouplingRig rig({dynamicBox(1, Vec3(0.0), half, 0.05, k, 0.5, Vec3(0.05, 0.01, 0.0))},
                    Vec3(0.0), {Vec3(0.0205, 0.0, 0.0), Vec3(-0.0205, 0.0, 0.0)});
    for (int i = 0; i < 20; ++i) {
        rig.advance(); // into contact
    }
    REQUIRE(rig.hands[0]->step.haptic.dynamicBodies().count == 1);
    std::uint64_t contact = 0;
    std::uint64_t allocations = 0;
    double torsion = 0.0; // the budgets' traces taken (N m s): the patch was at work
    for (int i = 0; i < 300; ++i) {
        rig.clock.set(rig.clock.nowNs() + CouplingRig::kPeriodNs);
        for (std::size_t b = 0; b < rig.dynamics.bodies.size(); ++b) {
            Vec3 angular;
            rig.table.takeImpulse(b, rig.dynamics.bodies[b].pending, angular);
            const Mat3 t = rig.table.takeTorsion(b);
            torsion += t[0][0] + t[1][1] + t[2][2];
        }
        rig.dynamics.step();
        rig.publish();
        for (auto& h : rig.hands) {
            const std::uint64_t before = hapto::test::gAllocations.load();
            const bool ok = h->step.run(h->step.deadlineNs);
            allocations += hapto::test::gAllocations.load() - before;
            REQUIRE(ok);
            contact += h->step.haptic.renderer().inContact() ? 1 : 0;
        }
    }
    CHECK(contact > 30);
    CHECK(torsion > 0.0);
    CHECK(allocations == 0);
}

TEST_CASE("two hands pressing a body off its centre of mass turn it by r x F, their patches off") {
    // A 50 g, 4 cm cube (isotropic inertia, so its angular momentum is I w whatever its pose),
    // no gravity, between two hands held 0.5 mm inside its +-x faces, 2 mm above and below its
    // centre: a couple about z. The test sums what each hand was sent, as impulse -F dt at the
    // proxy about the centre of mass the tick saw, and compares it with the body's momentum.
    const double k = 1000.0, m = 0.05;
    const Vec3 half(0.02, 0.02, 0.02);
    RealRig rig({dynamicBox(1, Vec3(0.0), half, m, k, 0.3)},
                {Vec3(0.0205, 0.002, 0.0), Vec3(-0.0205, -0.002, 0.0)},
                {Vec3(0.0195, 0.002, 0.0), Vec3(-0.0195, -0.002, 0.0)}, withTorsion(0.0));
    const double inertia = rig.scene->object(0).body.inertia[0][0];
    Vec3 sentLinear(0.0), sentAngular(0.0);
    std::uint64_t ticks = 0;
    double firstAngularZ = 0.0; // sent about z over the first 5 steps (N m s)
    for (int i = 0; i < 100; ++i) {
        if (i == 5) {
            firstAngularZ = sentAngular.z;
        }
        rig.advance();
        const Vec3 com = rig.dynamics.bodies()[0].position; // published now: no extrapolation
        for (const auto& h : rig.hands) {
            const Vec3 impulse = -h->device.lastForce * RealRig::kDtS;
            sentLinear += impulse;
            sentAngular += glm::cross(h->step.haptic.proxy() - com, impulse);
            ticks += h->device.lastForce != Vec3(0.0) ? 1 : 0;
        }
    }
    // The last ticks' impulses into the body, no more ticks.
    for (auto& h : rig.hands) {
        h->device.moveTo(Vec3(0.5, 0.5, 0.5)); // far away: the hands tick no more here
    }
    Vec3 linear(0.0), angular(0.0);
    rig.table.takeImpulse(0, linear, angular);
    rig.dynamics.applyImpulse(0, linear, angular);
    rig.dynamics.step();
    const BodyState& b = rig.dynamics.bodies()[0];
    INFO("sent angular " << sentAngular.z << " N m s, body L_z " << inertia * b.angularVelocity.z);
    REQUIRE(ticks > 150);
    CHECK(firstAngularZ > 0.0);            // the first presses: a couple about +z, as the arms say
    CHECK(std::abs(sentAngular.z) > 1e-6); // it turned the body
    const double tolerance = static_cast<double>(ticks + 2) * BodyPoseTable::kImpulseQuantumNs;
    for (int c = 0; c < 3; ++c) {
        INFO("component " << c);
        CHECK(std::abs(m * b.velocity[c] - sentLinear[c]) <= tolerance + 1e-12 * m);
        CHECK(std::abs(inertia * b.angularVelocity[c] - sentAngular[c]) <=
              tolerance + 1e-9 * std::abs(sentAngular.z));
    }
}

namespace {

/// A 50 g, 4 cm cube with mu_s = mu_d = 0.5 between two hands held 1 mm inside its +-x faces,
/// no gravity, the hands' effective torsional radius `radiusM`; 20 ms to settle.
RealRig squeezedCube(double radiusM, Vec3 spin = Vec3(0.0)) {
    SceneObject box = dynamicBox(1, Vec3(0.0), Vec3(0.02), 0.05, 2000.0, 0.5);
    box.body.angularVelocity = spin;
    return RealRig({box}, {Vec3(0.0205, 0.0, 0.0), Vec3(-0.0205, 0.0, 0.0)},
                   {Vec3(0.019, 0.0, 0.0), Vec3(-0.019, 0.0, 0.0)}, withTorsion(radiusM));
}

/// mu (|F1| + |F2|) r: the hands' torsional limit from the forces they were last sent (N m).
double torsionLimitNm(const RealRig& rig, double mu, double radiusM) {
    double normal = 0.0;
    for (const auto& h : rig.hands) {
        normal += std::abs(h->device.lastForce.x);
    }
    return mu * normal * radiusM;
}

} // namespace

TEST_CASE("a box pressed between two hands spins under a torque without their patches and "
          "holds with them") {
    // A torque about the line between the hands (x), 1e-3 N m, a sixth of the patches' limit
    // mu (F1 + F2) r = 0.5 x 4 N x 3 mm = 6e-3 N m, for 2 s after 20 ms of settling.
    const double tau = 1e-3, radius = 0.003;
    const double inertia = 0.05 / 3.0 * 2.0 * 0.02 * 0.02;
    SECTION("point contacts: it spins up freely, w = tau t / I") {
        RealRig rig = squeezedCube(0.0);
        for (int i = 0; i < 20; ++i) {
            rig.advance();
        }
        rig.disturbanceNms = Vec3(tau * RealRig::kDtS, 0.0, 0.0);
        for (int i = 0; i < 2000; ++i) {
            rig.advance();
        }
        const double w = rig.dynamics.bodies()[0].angularVelocity.x;
        INFO("w_x " << w << " rad/s, free " << tau * 2.0 / inertia);
        CHECK(rig.torsionTaken == 0.0);
        CHECK(w == Approx(tau * 2.0 / inertia).epsilon(0.01));
    }
    SECTION("3 mm patches: it turns less than 1 mrad in 2 s") {
        RealRig rig = squeezedCube(radius);
        for (int i = 0; i < 20; ++i) {
            rig.advance();
        }
        const double limit = torsionLimitNm(rig, 0.5, radius);
        CHECK(limit == Approx(6e-3).epsilon(0.01));
        rig.disturbanceNms = Vec3(tau * RealRig::kDtS, 0.0, 0.0);
        double angle = 0.0; // about x (rad): the integral of w_x
        const std::uint64_t before = hapto::test::gAllocations.load();
        for (int i = 0; i < 2000; ++i) {
            rig.advance();
            angle += rig.dynamics.bodies()[0].angularVelocity.x * RealRig::kDtS;
        }
        const std::uint64_t allocations = hapto::test::gAllocations.load() - before;
        INFO("turned " << angle << " rad, w_x " << rig.dynamics.bodies()[0].angularVelocity.x);
        CHECK(std::abs(angle) < 1e-3);
        CHECK(std::abs(rig.dynamics.bodies()[0].angularVelocity.x) < 1e-6);
        CHECK(allocations == 0); // dynamics steps with hand torsion and servo ticks in contact
    }
    SECTION("above the limit it slips at the Coulomb rate (tau - limit) / I") {
        RealRig rig = squeezedCube(radius);
        for (int i = 0; i < 20; ++i) {
            rig.advance();
        }
        const double limit = torsionLimitNm(rig, 0.5, radius);
        const double big = 1.5 * limit;
        rig.disturbanceNms = Vec3(big * RealRig::kDtS, 0.0, 0.0);
        for (int i = 0; i < 500; ++i) {
            rig.advance();
        }
        const double w = rig.dynamics.bodies()[0].angularVelocity.x;
        INFO("w_x " << w << " rad/s, limit " << limit << " N m");
        CHECK(w == Approx((big - limit) * 0.5 / inertia).epsilon(0.02));
    }
}

TEST_CASE("the hands' torsional friction only takes a held body's spin energy away") {
    // The cube spins at 30 rad/s about the line between the hands, no other torque: its spin
    // energy never rises from one step to the next, and the patches stop it by Coulomb's
    // deceleration (F1 + F2) mu r / I, in I w0 / limit.
    const double radius = 0.003, w0 = 30.0;
    RealRig rig = squeezedCube(radius, Vec3(w0, 0.0, 0.0));
    const double inertia = rig.scene->object(0).body.inertia[0][0];
    double last = rig.cubeSpinEnergyJ();
    const double start = last;
    double largestRise = 0.0;
    int stoppedAt = -1;
    double limit = 0.0;
    for (int i = 0; i < 200; ++i) {
        rig.advance();
        const double e = rig.cubeSpinEnergyJ();
        largestRise = std::max(largestRise, e - last);
        last = e;
        if (i == 10) {
            limit = torsionLimitNm(rig, 0.5, radius);
        }
        if (stoppedAt < 0 && std::abs(rig.dynamics.bodies()[0].angularVelocity.x) < 1e-9) {
            stoppedAt = i;
        }
    }
    INFO("start " << start << " J, largest one-step rise " << largestRise << " J, stopped at step "
                  << stoppedAt << ", limit " << limit << " N m");
    CHECK(largestRise <= 1e-15 * start);
    CHECK(last <= 1e-20);
    REQUIRE(stoppedAt > 0);
    // The first tick's budget comes one step late and the force settles over the first steps.
    CHECK(stoppedAt == Approx(inertia * w0 / limit / RealRig::kDtS).margin(3.0));
}

TEST_CASE("Dynamics::applyHandTorsion never adds energy and stops the spin about a single axis "
          "exactly") {
    // A 1:2:3 box turned arbitrarily (a full inverse inertia in world axes), alone in an empty
    // scene: random spins and random budgets (one axis, two opposed hands, two and three
    // arbitrary normals). The impulse lands in the next step; the step changes nothing else
    // (no gravity, no contact), so the spin after it is the spin the budget left.
    SceneObject box = dynamicBox(1, Vec3(0.0), Vec3(0.01, 0.02, 0.03), 0.1, 1000.0, 0.5);
    box.rotation = glm::normalize(Quat(0.9, 0.3, -0.2, 0.25));
    auto scene = CouplingRig::makeScene({box}, Vec3(0.0));
    World world(scene, IndexSpec::parse("brute"));
    std::mt19937_64 random(37);
    std::normal_distribution<double> gauss(0.0, 1.0);
    std::uniform_real_distribution<double> budget(0.0, 2e-5);
    for (int trial = 0; trial < 200; ++trial) {
        Dynamics d(scene, world.current().index);
        const Vec3 w(5.0 * gauss(random), 5.0 * gauss(random), 5.0 * gauss(random));
        const Mat3 r = glm::mat3_cast(box.rotation);
        const Mat3 inertiaWorld = r * box.body.inertia * glm::transpose(r);
        d.applyImpulse(0, Vec3(0.0), inertiaWorld * w); // from rest to w
        const int hands = 1 + trial % 4;
        Mat3 b(0.0);
        Vec3 first(0.0);
        for (int h = 0; h < hands; ++h) {
            Vec3 n = glm::normalize(Vec3(gauss(random), gauss(random), gauss(random)));
            if (h == 0) {
                first = n;
            } else if (hands == 2) {
                n = -first; // two opposed hands
            }
            const double beta = budget(random);
            b += beta * glm::outerProduct(n, n);
        }
        d.applyHandTorsion(0, b);
        d.step();
        const Vec3 after = d.bodies()[0].angularVelocity;
        const double before = 0.5 * glm::dot(w, inertiaWorld * w);
        const double now = 0.5 * glm::dot(after, inertiaWorld * after);
        INFO("trial " << trial << ", " << hands << " hands: " << before << " J -> " << now);
        CHECK(now <= before * (1.0 + 1e-12));
        if (hands <= 2) {
            // One axis n: w.n is stopped, or reduced by exactly the budget's worth,
            // beta (n.I^-1 n), keeping its sign.
            const double beta = b[0][0] + b[1][1] + b[2][2];
            const double reach = beta * glm::dot(first, glm::inverse(inertiaWorld) * first);
            const double spin = glm::dot(w, first);
            const double expected =
                std::abs(spin) <= reach ? 0.0 : spin - std::copysign(reach, spin);
            CHECK(glm::dot(after, first) == Approx(expected).margin(1e-9 * (1.0 + std::abs(spin))));
        }
    }
}

TEST_CASE("a device file's renderer.torsion_radius_m sets the hand's patch, and a bad one is "
          "refused with its JSON path") {
    const std::string head =
        R"({"format": "hapto-devices", "version": 1, "devices": [{"name": "a", "kind": "sim"}, )";
    const DeviceFile file = parseDeviceFile(
        head + R"({"name": "b", "kind": "sim", "renderer": {"torsion_radius_m": 0.004}}]})",
        "ok.json");
    CHECK_FALSE(file.renderingOf(0).renderer.torsionRadiusM.has_value());
    REQUIRE(file.renderingOf(1).renderer.torsionRadiusM.has_value());
    CHECK(*file.renderingOf(1).renderer.torsionRadiusM == 0.004);
    CHECK_FALSE(file.renderingOf(1).renderer.contactDampingNsPerM.has_value());
    CHECK(withDeviceSettings(RendererConfig{}, file.renderingOf(1).renderer).torsionRadiusM ==
          0.004);
    CHECK(withDeviceSettings(RendererConfig{}, file.renderingOf(0).renderer).torsionRadiusM ==
          RendererConfig{}.torsionRadiusM);
    struct Case {
        std::string renderer, message;
    };
    const std::vector<Case> cases = {
        {R"({"torsion_radius_m": -0.001})",
         "bad.json: devices[1].renderer.torsion_radius_m: the torsional radius (m) "
         "must be >= 0 (got -0.001)"},
        {R"({"torsion_radius_m": 0.2})",
         "bad.json: devices[1].renderer.torsion_radius_m: the torsional radius (m) "
         "must be <= 0.05 (got 0.2)"},
        {R"({"torsion_radius_m": "3 mm"})",
         "bad.json: devices[1].renderer.torsion_radius_m: expected a number, got a string"},
        {R"({})", "bad.json: devices[1].renderer: expected 'damping_n_s_per_m' or "
                  "'torsion_radius_m' (or both)"},
    };
    for (const Case& c : cases) {
        std::string error = "(no error)";
        try {
            parseDeviceFile(head + R"({"name": "b", "kind": "sim", "renderer": )" + c.renderer +
                                "}]}",
                            "bad.json");
        } catch (const InputError& e) {
            error = e.what();
        }
        INFO(c.renderer);
        CHECK(error == c.message);
    }
    CHECK_THROWS_AS(BodyCoupling(0.06), std::invalid_argument);
    CHECK_THROWS_AS(BodyCoupling(std::nan("")), std::invalid_argument);
}

TEST_CASE("the pose table sums torsional budgets sign-free and exactly, and refuses bad ones") {
    BodyPoseTable table(2);
    const Vec3 n = glm::normalize(Vec3(1.0, 2.0, -2.0));
    REQUIRE(table.addTorsion(1, n, 3e-6));
    REQUIRE(table.addTorsion(1, -n, 1e-6)); // the opposed hand: the same axis, budgets add
    CHECK_FALSE(table.addTorsion(1, n, -1e-6));
    CHECK_FALSE(table.addTorsion(1, n, std::nan("")));
    CHECK_FALSE(table.addTorsion(1, Vec3(std::numeric_limits<double>::infinity(), 0, 0), 1e-6));
    CHECK(table.takeTorsion(0) == Mat3(0.0));
    const Mat3 b = table.takeTorsion(1);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            INFO("row " << r << ", column " << c);
            CHECK(b[c][r] == b[r][c]);
            CHECK(std::abs(b[c][r] - 4e-6 * n[r] * n[c]) <= BodyPoseTable::kImpulseQuantumNs);
        }
    }
    CHECK(table.takeTorsion(1) == Mat3(0.0)); // taken once
}
