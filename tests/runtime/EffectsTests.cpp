// Force effects and the per-tick hook: each effect's force against its formula, and both
// through the runtime's step mode (the servo tick itself): picked up at the next tick, added
// before the safety filter, clamped and sanitised by it.

#include "CubeScene.h"
#include "ScriptedDevice.h"
#include "TestSupport.h"

#include "hapto/core/Finite.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/Effects.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

using namespace hapto;
using hapto::test::cubeScene;
using test::ScriptedDevice;

namespace {

using test::kMs;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool near(const Vec3& a, const Vec3& b, double eps = 1e-12) {
    return glm::length(a - b) <= eps;
}

/// A rig's device: its configuration (transform, max force) and what the runtime renders for it
/// (effects, renderer damping).
struct RigDevice {
    DeviceConfig config;
    DeviceRendering rendering;
};

/// One scripted device at 1 kHz in step mode over the cube scene; `setup` brings its effects,
/// transform and renderer damping, `hook` is registered before the start.
struct EffectsRig {
    ManualClock clock;
    World world;
    ScriptedDevice* device = nullptr;
    std::unique_ptr<Runtime> runtime;
    std::uint64_t t0 = 0;

    EffectsRig(ScriptedDevice::Path path, RigDevice setup = {}, TickHook hook = {})
        : world(cubeScene(), IndexSpec::parse(kDefaultIndexSpec)) {
        DeviceConfig& config = setup.config;
        world.useClock(clock);
        auto d = std::make_unique<ScriptedDevice>("d", std::move(path));
        d->useClock(&clock);
        device = d.get();
        config.name = std::string(d->name()); // "d"
        config.kind = DeviceKind::Scripted;
        config.rateHz = 1000.0;
        if (config.maxForceN == 0) {
            config.maxForceN = 5.0;
        }
        std::vector<RuntimeDevice> rds;
        rds.push_back({std::move(d), config, nullptr, setup.rendering});
        RuntimeOptions options;
        options.realtime = false;
        runtime = std::make_unique<Runtime>(world, std::move(rds), options);
        if (hook.fn) {
            runtime->setTickHook(0, hook);
        }
        t0 = clock.nowNs();
        REQUIRE(runtime->startStepped(clock) == 1);
    }
    /// Ticks up to and including t0 + ms.
    void runTo(std::uint64_t ms) { runtime->runUntil(t0 + ms * kMs); }
    std::uint64_t ticks() const { return runtime->metrics(0).ticks.load(); }
    /// The force of the last tick (N, world).
    Vec3 force() const {
        const DeviceMetrics& m = runtime->metrics(0);
        return {m.forceN[0].load(), m.forceN[1].load(), m.forceN[2].load()};
    }
};

/// A device held still at `p` (m, device frame).
ScriptedDevice::Path still(const Vec3& p) {
    return [p](std::uint64_t) { return p; };
}

/// A device moving from `from` at `velocity` (m/s), one tick per ms.
ScriptedDevice::Path moving(const Vec3& from, const Vec3& velocity) {
    return [from, velocity](std::uint64_t t) {
        return from + velocity * (1e-3 * static_cast<double>(t));
    };
}

RigDevice withEffects(std::vector<ForceEffect> effects) {
    RigDevice c;
    c.rendering.effects = std::move(effects);
    return c;
}

} // namespace

TEST_CASE("each effect's force is its formula") {
    const Vec3 anchor(0.01, -0.02, 0.03);
    const Vec3 p(0.05, 0.04, -0.01);
    const Vec3 v(0.2, -0.1, 0.3);
    const Vec3 r = p - anchor;

    SECTION("a spring to a point pulls by -k (x - anchor)") {
        CHECK(near(effectForceN(ForceEffect::springToPoint(anchor, 200.0), p, v), -200.0 * r));
    }
    SECTION("a spring to a line pulls only across the line") {
        const ForceEffect e = ForceEffect::springToLine(anchor, Vec3(0, 0, 2), 200.0);
        CHECK(e.axis == Vec3(0, 0, 1)); // normalised
        CHECK(near(effectForceN(e, p, v), -200.0 * Vec3(r.x, r.y, 0.0)));
        // Sliding along the line changes nothing.
        CHECK(near(effectForceN(e, p + Vec3(0, 0, 0.5), v), effectForceN(e, p, v)));
    }
    SECTION("a spring to a plane pulls only along the normal, from both sides") {
        const ForceEffect e = ForceEffect::springToPlane(anchor, Vec3(0, -3, 0), 200.0);
        CHECK(near(effectForceN(e, p, v), Vec3(0, -200.0 * r.y, 0)));
        const Vec3 below(0.3, anchor.y - 0.01, 0.7);
        CHECK(near(effectForceN(e, below, v), Vec3(0, 200.0 * 0.01, 0), 1e-12));
    }
    SECTION("a damper resists velocity, -b v, and ignores position") {
        const ForceEffect e = ForceEffect::damper(4.0);
        CHECK(near(effectForceN(e, p, v), -4.0 * v));
        CHECK(near(effectForceN(e, Vec3(100.0), v), -4.0 * v));
    }
    SECTION("a damper in a box acts inside it only, the boundary included") {
        const ForceEffect e =
            ForceEffect::damper(4.0, EffectRegion::box(Vec3(0.1, 0, 0), Vec3(0.01, 0.02, 0.03)));
        CHECK(near(effectForceN(e, Vec3(0.105, 0.019, -0.029), v), -4.0 * v));
        CHECK(near(effectForceN(e, Vec3(0.11, 0.0, 0.0), v), -4.0 * v)); // on the face
        CHECK(effectForceN(e, Vec3(0.111, 0.0, 0.0), v) == Vec3(0.0));
        CHECK(effectForceN(e, Vec3(0.1, 0.021, 0.0), v) == Vec3(0.0));
        CHECK(effectForceN(e, Vec3(0.1, 0.0, -0.031), v) == Vec3(0.0));
    }
    SECTION("a damper in a sphere acts inside it only") {
        const ForceEffect e = ForceEffect::damper(4.0, EffectRegion::sphere(anchor, 0.05));
        CHECK(near(effectForceN(e, anchor + Vec3(0.03, 0.0, 0.039), v), -4.0 * v));
        CHECK(effectForceN(e, anchor + Vec3(0.03, 0.0, 0.041), v) == Vec3(0.0));
    }
    SECTION("a constant force is itself, anywhere") {
        const ForceEffect e = ForceEffect::constant(Vec3(0.5, -1.0, 0.25));
        CHECK(effectForceN(e, p, v) == Vec3(0.5, -1.0, 0.25));
        CHECK(effectForceN(e, -p, -v) == Vec3(0.5, -1.0, 0.25));
    }
    SECTION("an effect that is off gives nothing") {
        ForceEffect e = ForceEffect::springToPoint(anchor, 200.0);
        e.enabled = false;
        CHECK(effectForceN(e, p, v) == Vec3(0.0));
        e = ForceEffect::constant(Vec3(1.0));
        e.enabled = false;
        CHECK(effectForceN(e, p, v) == Vec3(0.0));
    }
    SECTION("a set sums its effects; on and off by index") {
        const std::vector<ForceEffect> list = {ForceEffect::springToPoint(anchor, 200.0),
                                               ForceEffect::damper(4.0),
                                               ForceEffect::constant(Vec3(0, 1, 0))};
        EffectSet set(list);
        REQUIRE(set.size() == 3);
        CHECK(near(set.forceN(p, v), -200.0 * r - 4.0 * v + Vec3(0, 1, 0), 1e-12));
        CHECK(set.setEnabled(1, false));
        CHECK(near(set.forceN(p, v), -200.0 * r + Vec3(0, 1, 0), 1e-12));
        CHECK_FALSE(set.setEnabled(3, false));
    }
}

TEST_CASE("an effect set refuses bad effects by index and field, and more than its capacity") {
    const auto errorOf = [](std::vector<ForceEffect> list) -> std::string {
        try {
            EffectSet set(list);
        } catch (const std::invalid_argument& e) {
            return e.what();
        }
        return "(no error)";
    };
    const ForceEffect ok = ForceEffect::constant(Vec3(1, 0, 0));
    CHECK(errorOf({ok, ForceEffect::springToPoint(Vec3(0), 2e4)}) ==
          "effects[1].stiffness_n_per_m: the stiffness (N/m) must be in 0..10000 (got 20000); a "
          "stiffer spring only oscillates");
    CHECK_THAT(errorOf({ForceEffect::springToPoint(Vec3(0), -1)}),
               Catch::StartsWith("effects[0].stiffness_n_per_m:"));
    CHECK_THAT(errorOf({ForceEffect::springToPoint(Vec3(kNaN, 0, 0), 10)}),
               Catch::StartsWith("effects[0].anchor:"));
    ForceEffect line = ForceEffect::springToLine(Vec3(0), Vec3(1, 0, 0), 10);
    line.axis = Vec3(2, 0, 0);
    CHECK_THAT(errorOf({line}), Catch::StartsWith("effects[0].direction: must be a unit vector"));
    CHECK_THAT(errorOf({ForceEffect::damper(101)}),
               Catch::StartsWith("effects[0].damping_n_s_per_m: the damping (N·s/m) must be in "
                                 "0..100 (got 101)"));
    CHECK_THAT(errorOf({ForceEffect::damper(1, EffectRegion::sphere(Vec3(0), 0))}),
               Catch::StartsWith("effects[0].region.sphere.radius_m:"));
    CHECK_THAT(errorOf({ForceEffect::damper(1, EffectRegion::box(Vec3(0), Vec3(1, -1, 1)))}),
               Catch::StartsWith("effects[0].region.box.half_extents:"));
    CHECK_THAT(errorOf({ok, ok, ForceEffect::constant(Vec3(0, 0, 101))}),
               Catch::StartsWith("effects[2].force_n: the force's magnitude (N) must be in "
                                 "0..100 (got 101)"));
    CHECK_THAT(errorOf(std::vector<ForceEffect>(EffectSet::kCapacity + 1, ok)),
               Catch::Contains("at most 8"));
    CHECK(errorOf(std::vector<ForceEffect>(EffectSet::kCapacity, ok)) == "(no error)");
}

TEST_CASE("runtime: a device's configured effects act from the first tick, each as its formula") {
    // Free space (the cube is 5 cm away): the force is the effects' alone, below the 1 N per
    // tick growth limit, so the first tick already sends all of it.
    const Vec3 p(0.08, 0.06, -0.04);
    const Vec3 anchor(0.07, 0.08, -0.04);
    SECTION("a spring to a point") {
        EffectsRig rig(still(p), withEffects({ForceEffect::springToPoint(anchor, 20.0)}));
        rig.runTo(1);
        REQUIRE(rig.ticks() == 1);
        CHECK(near(rig.force(), -20.0 * (p - anchor)));
    }
    SECTION("a spring to a plane, through the device transform") {
        // The device frame is the world moved by +0.01 m in x: the effect sees world points.
        RigDevice c = withEffects({ForceEffect::springToPlane(anchor, Vec3(1, 0, 0), 20.0)});
        c.config.transform.translation = Vec3(0.01, 0, 0);
        EffectsRig rig(still(p - Vec3(0.01, 0, 0)), c);
        rig.runTo(1);
        CHECK(near(rig.force(), Vec3(-20.0 * (p.x - anchor.x), 0, 0)));
    }
    SECTION("a damper inside a sphere, not outside") {
        // Moving at 0.1 m/s in +x from x = 0.06: inside the 1 cm ball around x = 0.08 only
        // between x = 0.07 and 0.09 (ticks 100 to 300).
        const Vec3 v(0.1, 0, 0);
        EffectsRig rig(moving(Vec3(0.06, 0.06, 0.0), v),
                       withEffects({ForceEffect::damper(
                           5.0, EffectRegion::sphere(Vec3(0.08, 0.06, 0), 0.01))}));
        rig.runTo(50);
        CHECK(rig.force() == Vec3(0.0));
        rig.runTo(200);
        // The velocity is estimated from the last two points: exactly 0.1 mm per ms.
        CHECK(rig.force().x == Approx(-5.0 * 0.1).epsilon(1e-9));
        CHECK(rig.force().y == 0.0);
        rig.runTo(350);
        CHECK(rig.force() == Vec3(0.0));
    }
    SECTION("a constant force, off and on") {
        ForceEffect off = ForceEffect::constant(Vec3(0, 0, 0.5));
        off.enabled = false;
        EffectsRig rig(still(p), withEffects({ForceEffect::constant(Vec3(0.25, 0, 0)), off}));
        rig.runTo(3);
        CHECK(rig.force() == Vec3(0.25, 0, 0));
        rig.runtime->setEffectEnabled(0, 1, true);
        rig.runTo(4);
        CHECK(rig.force() == Vec3(0.25, 0, 0.5));
        rig.runtime->setEffectEnabled(0, 0, false);
        rig.runTo(5);
        CHECK(rig.force() == Vec3(0, 0, 0.5));
        CHECK_THROWS_AS(rig.runtime->setEffectEnabled(0, 2, true), std::out_of_range);
    }
}

TEST_CASE("runtime: effects set from the control thread are picked up at the next tick") {
    const Vec3 p(0.08, 0.06, -0.04);
    EffectsRig rig(still(p));
    rig.runTo(10);
    CHECK(rig.force() == Vec3(0.0));
    CHECK(rig.runtime->effects(0).size() == 0);

    // setEffects() returns at once, between two ticks: no tick ran for it and none waited.
    const std::vector<ForceEffect> spring = {
        ForceEffect::springToPoint(Vec3(0.08, 0.05, -0.04), 30.0)};
    rig.runtime->setEffects(0, spring);
    CHECK(rig.ticks() == 10);
    CHECK(rig.force() == Vec3(0.0));
    CHECK(rig.runtime->effects(0).size() == 1);
    rig.runTo(11);
    CHECK(near(rig.force(), Vec3(0, -30.0 * 0.01, 0)));

    // Replaced by another set, then by none.
    const std::vector<ForceEffect> push = {ForceEffect::constant(Vec3(0.1, 0, 0)),
                                           ForceEffect::constant(Vec3(0.2, 0, 0))};
    rig.runtime->setEffects(0, push);
    rig.runTo(12);
    CHECK(near(rig.force(), Vec3(0.3, 0, 0)));
    rig.runtime->setEffects(0, {});
    rig.runTo(13);
    CHECK(rig.force() == Vec3(0.0));

    // A bad set is refused whole and changes nothing.
    rig.runtime->setEffects(0, push);
    const std::vector<ForceEffect> bad = {ForceEffect::constant(Vec3(0, 0, 0.1)),
                                          ForceEffect::damper(kNaN)};
    CHECK_THROWS_WITH(rig.runtime->setEffects(0, bad),
                      Catch::StartsWith("Runtime::setEffects: device 'd': "
                                        "effects[1].damping_n_s_per_m:"));
    rig.runTo(14);
    CHECK(near(rig.force(), Vec3(0.3, 0, 0)));
    CHECK(rig.runtime->effects(0).size() == 2);
}

TEST_CASE("runtime: effects are set from a list, and lastTick gives the force sent, zero after "
          "the stop") {
    EffectsRig rig(still(Vec3(0.08, 0.06, -0.04)));
    rig.runtime->setEffects(0, {ForceEffect::damper(2.0), ForceEffect::constant(Vec3(0, 0, 0.4))});
    CHECK(rig.runtime->effects(0).size() == 2);
    rig.runTo(3);
    ContactReport last;
    REQUIRE(rig.runtime->lastTick(0, last));
    CHECK(last.tick == rig.ticks() - 1);
    CHECK(last.force == rig.force());
    CHECK(near(last.force, Vec3(0, 0, 0.4))); // held still in free space: the damper adds nothing
    CHECK(last.contactCount == 0);
    rig.runtime->setEffects(0, {});
    rig.runTo(4);
    REQUIRE(rig.runtime->lastTick(0, last));
    CHECK(last.force == Vec3(0.0));

    rig.runtime->setEffects(0, {ForceEffect::constant(Vec3(0.2, 0, 0))});
    rig.runTo(5);
    REQUIRE(rig.runtime->lastTick(0, last));
    CHECK(near(last.force, Vec3(0.2, 0, 0)));
    rig.runtime->stop(); // the force the device feels at the end of the session: none
    REQUIRE(rig.runtime->lastTick(0, last));
    CHECK(last.force == Vec3(0.0));
    CHECK(last.contactCount == 0);
    CHECK(rig.device->forces().back().force == Vec3(0.0));
}

TEST_CASE("runtime: a device's renderer damping comes from its configuration") {
    // Two runs pressing into the cube's top at 0.1 m/s: the damped one pushes back harder by
    // b v along the normal while the tool moves in (b = 20 N·s/m: 2 N more).
    const auto path = [](std::uint64_t t) {
        return Vec3(0.0, 0.03 - 1e-4 * static_cast<double>(t), 0.0); // 0.1 m/s down
    };
    RigDevice damped;
    damped.rendering.renderer.contactDampingNsPerM = 20.0;
    damped.config.maxForceN = 50.0;
    RigDevice plain;
    plain.config.maxForceN = 50.0;
    EffectsRig a(path, damped);
    EffectsRig b(path, plain);
    a.runTo(80); // 8 mm down: 3 mm into the cube, 1.5 N from the spring alone
    b.runTo(80);
    // The 80th reading is 7.9 mm down, 2.9 mm into the top face at y = 0.025.
    CHECK(b.force().y == Approx(500.0 * (0.025 - (0.03 - 79e-4) + 1e-8)).epsilon(1e-6));
    CHECK(a.force().y - b.force().y == Approx(20.0 * 0.1).epsilon(1e-6));
}

namespace {

/// What a hook saw, and what it returns.
struct HookProbe {
    Vec3 returns{0.0};
    std::uint64_t calls = 0;
    DeviceState sample;
    Vec3 point{0.0}, velocity{0.0}, proxy{0.0}, renderForce{0.0}, normal{0.0};
    std::size_t contacts = 0;
    double dtS = 0;
};

Vec3 probeHook(void* context, const TickHookArgs& a) noexcept {
    auto& probe = *static_cast<HookProbe*>(context);
    ++probe.calls;
    probe.sample = a.sample;
    probe.point = a.devicePointM;
    probe.velocity = a.velocityMPerS;
    probe.proxy = a.proxyM;
    probe.renderForce = a.renderForceN;
    probe.contacts = a.contacts.size();
    probe.normal = a.contacts.empty() ? Vec3(0.0) : a.contacts[0].normal;
    probe.dtS = a.dtS;
    return probe.returns;
}

} // namespace

TEST_CASE("runtime: the hook is called every tick with the sample, proxy, contacts and dt, and "
          "its force is added") {
    HookProbe probe;
    probe.returns = Vec3(0.0, 0.0, 0.4);
    RigDevice c;
    c.config.transform.translation = Vec3(0.002, 0, 0); // device frame != world frame
    EffectsRig rig(test::pressIntoCube(0.0), c, TickHook{&probeHook, &probe});
    rig.runTo(100);
    CHECK(probe.calls == 100);
    CHECK(probe.dtS == Approx(1e-3));
    // The sample is the device's own reading (its frame); the point is in the world.
    CHECK(probe.sample.position == Vec3(0.0, 0.025 - 0.002, 0.0));
    CHECK(probe.sample.sequence == 99);
    CHECK(probe.point == Vec3(0.002, 0.025 - 0.002, 0.0));
    CHECK(probe.velocity == Vec3(0.0)); // held still since tick 50
    // Pressed 2 mm into the top face: the proxy rides on it, one contact, normal +y.
    CHECK(probe.proxy.y == Approx(0.025).margin(1e-7));
    CHECK(probe.proxy.x == Approx(0.002));
    REQUIRE(probe.contacts == 1);
    CHECK(near(probe.normal, Vec3(0, 1, 0)));
    CHECK(probe.renderForce.y == Approx(500.0 * (0.002 + 1e-8)).epsilon(1e-6));
    // The force sent: the renderer's plus the hook's.
    CHECK(near(rig.force(), probe.renderForce + probe.returns, 1e-12));
    CHECK(rig.runtime->report().devices[0].hookNonFinite == 0);
}

TEST_CASE("runtime: a hook may be a lambda that captures nothing, declared noexcept, with its "
          "data through the context pointer") {
    HookProbe probe;
    probe.returns = Vec3(0.0, 0.0, 0.25);
    const TickHook hook{[](void* context, const TickHookArgs&) noexcept {
                            auto& p = *static_cast<HookProbe*>(context);
                            ++p.calls;
                            return p.returns;
                        },
                        &probe};
    EffectsRig rig(still(Vec3(0.08, 0.06, 0)), {}, hook);
    rig.runTo(10);
    CHECK(probe.calls == 10);
    CHECK(near(rig.force(), probe.returns));
    CHECK(TickHook{}.fn == nullptr);
}

TEST_CASE("runtime: a hook registers only before the start") {
    HookProbe probe;
    EffectsRig rig(still(Vec3(0.08, 0, 0)));
    CHECK_THROWS_AS(rig.runtime->setTickHook(0, TickHook{&probeHook, &probe}), std::logic_error);
    rig.runTo(5);
    CHECK(probe.calls == 0);
}

TEST_CASE("runtime: effects and the hook pass through the safety filter") {
    HookProbe probe;
    SECTION("a non-finite hook force is replaced by zero and counted; contact still renders") {
        probe.returns = Vec3(kNaN, 0.0, 0.0);
        EffectsRig rig(test::pressIntoCube(0.0), {}, TickHook{&probeHook, &probe});
        rig.runTo(100);
        CHECK(finite(rig.force()));
        CHECK(near(rig.force(), probe.renderForce, 1e-12));
        const DeviceReport r = rig.runtime->report().devices[0];
        CHECK(r.hookNonFinite == 100);
        CHECK(r.safety.nonFinite == 0); // never reached the filter
        CHECK(r.fault.empty());
    }
    SECTION("an infinite hook force in free space sends zero") {
        probe.returns = Vec3(0.0, std::numeric_limits<double>::infinity(), 0.0);
        EffectsRig rig(still(Vec3(0.08, 0.06, 0)), {}, TickHook{&probeHook, &probe});
        rig.runTo(10);
        CHECK(rig.force() == Vec3(0.0));
        for (const ScriptedDevice::Written& w : rig.device->forces()) {
            CHECK(w.force == Vec3(0.0));
        }
        CHECK(rig.runtime->report().devices[0].hookNonFinite == 10);
    }
    SECTION("a huge hook force is rate-limited, then clamped to the device's maximum") {
        probe.returns = Vec3(1e9, 0.0, 0.0);
        EffectsRig rig(still(Vec3(0.08, 0.06, 0)), {}, TickHook{&probeHook, &probe});
        rig.runTo(1);
        CHECK(glm::length(rig.force()) == Approx(1.0)); // 1 N per tick from zero
        rig.runTo(20);
        CHECK(rig.force().x == Approx(5.0));
        CHECK(rig.runtime->report().devices[0].safety.clamped > 0);
    }
    SECTION("a stiff spring far from its anchor is clamped to the device's maximum") {
        // 10^4 N/m at 10 cm asks for 1000 N.
        EffectsRig rig(still(Vec3(0.08, 0.06, 0)),
                       withEffects({ForceEffect::springToPoint(Vec3(0.08, -0.04, 0), 1e4)}));
        double largest = 0;
        for (std::uint64_t ms = 1; ms <= 20; ++ms) {
            rig.runTo(ms);
            largest = std::max(largest, glm::length(rig.force()));
        }
        CHECK(largest == Approx(5.0));
        CHECK(rig.force().y == Approx(-5.0));
        CHECK(rig.runtime->report().devices[0].safety.clamped > 0);
    }
    SECTION("effects and the hook add up with contact before the filter") {
        probe.returns = Vec3(0.0, 0.0, -0.2);
        EffectsRig rig(
            test::pressIntoCube(0.0),
            withEffects({ForceEffect::constant(Vec3(0.3, 0, 0)), ForceEffect::damper(2.0)}),
            TickHook{&probeHook, &probe});
        rig.runTo(100); // held still: the damper adds nothing
        CHECK(near(rig.force(), probe.renderForce + Vec3(0.3, 0, -0.2), 1e-12));
    }
}

TEST_CASE("servo threads: effects set while they run reach them, and the control thread never "
          "waits for a tick",
          "[realtime]") {
    World world(cubeScene(), IndexSpec::parse(kDefaultIndexSpec));
    std::vector<RuntimeDevice> rds;
    auto d = std::make_unique<ScriptedDevice>("d", still(Vec3(0.08, 0.06, 0.0))); // free space
    DeviceConfig c;
    c.name = std::string(d->name());
    c.kind = DeviceKind::Scripted;
    c.maxForceN = 5.0;
    rds.push_back({std::move(d), c, nullptr});
    RuntimeOptions options;
    options.realtime = false;               // tests share a noisy machine
    options.stallTimeoutNs = 5'000'000'000; // a sanitizer build may stall a thread a while
    Runtime runtime(world, std::move(rds), options);
    REQUIRE(runtime.start() == 1);
    const auto force = [&runtime] {
        const DeviceMetrics& m = runtime.metrics(0);
        return Vec3(m.forceN[0].load(), m.forceN[1].load(), m.forceN[2].load());
    };
    for (int i = 1; i <= 20; ++i) {
        const Vec3 f(0.01 * i, 0.0, -0.02 * (i % 3));
        const std::vector<ForceEffect> effects = {ForceEffect::constant(f)};
        runtime.setEffects(0, effects);
        INFO("set " << i);
        CHECK(test::eventually([&] { return force() == f; }));
    }
    runtime.setEffectEnabled(0, 0, false);
    CHECK(test::eventually([&] { return force() == Vec3(0.0); }));
    runtime.stop();
    CHECK(runtime.report().devices[0].fault.empty());
}
