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

#include "CountingNew.h"

#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/ServoStep.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/SceneObject.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <memory>
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
    Hand(Vec3 at, const SafetyConfig& safety) : device(at), step(RendererConfig{}, safety) {}
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
            auto hand = std::make_unique<Hand>(at, safety);
            ServoStep& s = hand->step;
            s.setTiming(kPeriodNs, 3, 0.5, 100'000'000);
            s.device = &hand->device;
            s.reader = world.registerReader();
            s.ports = hand->shared.portsFor(world, &clock);
            s.ports.bodies = &table;
            s.start(clock.nowNs());
            hands.push_back(std::move(hand));
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

TEST_CASE("a servo tick in contact with a dynamic body allocates nothing") {
    const double k = 2000.0;
    const Vec3 half(0.02, 0.02, 0.02);
    CouplingRig rig({dynamicBox(1, Vec3(0.0), half, 0.05, k, 0.5, Vec3(0.05, 0.01, 0.0))},
                    Vec3(0.0), {Vec3(0.0205, 0.0, 0.0), Vec3(-0.0205, 0.0, 0.0)});
    for (int i = 0; i < 20; ++i) {
        rig.advance(); // into contact
    }
    std::uint64_t contact = 0;
    std::uint64_t allocations = 0;
    for (int i = 0; i < 300; ++i) {
        rig.clock.set(rig.clock.nowNs() + CouplingRig::kPeriodNs);
        for (std::size_t b = 0; b < rig.dynamics.bodies.size(); ++b) {
            Vec3 angular;
            rig.table.takeImpulse(b, rig.dynamics.bodies[b].pending, angular);
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
    CHECK(allocations == 0);
}
