// HapticTick, the one haptic tick: locate, candidates, render, effects, safety.

#include "OneThreadBuilds.h"
#include "TestMeshes.h"
#include "hapto/experiments/HandWalk.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/HapticTick.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/RendererSettings.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

using namespace hapto;

namespace {

Scene boxScene(double stiffness) {
    Material m;
    m.stiffness = stiffness;
    return Scene(Aabb{Vec3(-0.125), Vec3(0.125)},
                 {makeBox(7, Vec3(0), Vec3(0.025), Quat(1, 0, 0, 0), m)});
}

/// Moves the device from 1 cm above the top face straight down to `depth` below it in 50
/// ticks of 1 ms, then holds it there for 50 more; returns the last tick's output.
TickOutput pressTo(HapticTick& tick, const WorldSnapshot& s, double depth, double x = 0.0) {
    TickOutput out;
    for (int i = 0; i <= 100; ++i) {
        const double u = std::min(1.0, i / 50.0);
        const Vec3 p(x, 0.025 + 0.01 - u * (0.01 + depth), 0.0);
        out = tick.tick(s, p, Vec3(0.0), 1e-3, Vec3(0.0));
    }
    return out;
}

} // namespace

TEST_CASE("pressing d into a box face of stiffness k gives k d along the face normal, before the "
          "safety filter") {
    const double k = GENERATE(200.0, 800.0, 2000.0);
    const double d = GENERATE(0.0005, 0.002);
    INFO("k " << k << " d " << d);
    World world(boxScene(k), IndexSpec::parse(kDefaultIndexSpec));
    HapticTick tick;
    const TickOutput out = pressTo(tick, world.current(), d);
    const double expected = k * (d + GodObjectRenderer::kSkinM);
    CHECK(out.render.contactCount == 1);
    CHECK(out.render.contacts[0].id == 7);
    CHECK(out.render.contacts[0].normal == Vec3(0, 1, 0));
    CHECK(out.render.force.x == Approx(0.0).margin(1e-12));
    CHECK(out.render.force.y == Approx(expected).epsilon(1e-9));
    CHECK(out.render.force.z == Approx(0.0).margin(1e-12));
    CHECK(out.render.proxy.y == Approx(0.025 + GodObjectRenderer::kSkinM).epsilon(1e-12));
    // Below the 8.5 N default clamp the safety filter passes it as it is.
    CHECK(out.forceN == out.render.force);
    CHECK_FALSE(out.outside);
}

TEST_CASE("a force above the device's limit is clamped by the safety filter, not in the render "
          "output") {
    World world(boxScene(5000.0), IndexSpec::parse(kDefaultIndexSpec));
    SafetyConfig safety;
    safety.maxForceN = 3.0;
    HapticTick tick({}, safety);
    const TickOutput out = pressTo(tick, world.current(), 0.002);
    CHECK(out.render.force.y == Approx(5000.0 * (0.002 + GodObjectRenderer::kSkinM)));
    CHECK(out.forceN.y == Approx(3.0).epsilon(1e-12));
    CHECK(tick.safety().counters().clamped > 0);
}

TEST_CASE("in free space the force is zero and the proxy is the device point", "[threads]") {
    World world(boxScene(800.0), IndexSpec::parse("grid:4"));
    HapticTick tick;
    for (const Vec3& p : {Vec3(0.05, 0.05, 0.05), Vec3(-0.1, 0.0, 0.02), Vec3(0.0, 0.03, 0.0)}) {
        const TickOutput out = tick.tick(world.current(), p, Vec3(0.0), 1e-3, Vec3(0.0));
        CHECK(out.render.force == Vec3(0.0));
        CHECK(out.forceN == Vec3(0.0));
        CHECK(out.render.proxy == p);
        CHECK(out.render.contactCount == 0);
    }
    // Outside the index's bounds: still rendered (nothing reaches out there), and said.
    const TickOutput out = tick.tick(world.current(), Vec3(0.3, 0, 0), Vec3(0.0), 1e-3, Vec3(0.0));
    CHECK(out.outside);
    CHECK(out.forceN == Vec3(0.0));
}

TEST_CASE("the external force is added before the safety filter: clamped and rate-limited") {
    World world(boxScene(800.0), IndexSpec::parse(kDefaultIndexSpec));
    HapticTick tick; // 8.5 N at most, 1 N per tick at most
    const Vec3 p(0.05, 0.05, 0.05);
    for (int i = 1; i <= 12; ++i) {
        const TickOutput out = tick.tick(world.current(), p, Vec3(0.0), 1e-3, Vec3(0, -20.0, 0));
        CHECK(out.render.force == Vec3(0.0));
        CHECK(out.forceN.y == Approx(-std::min(8.5, 1.0 * i)).epsilon(1e-12));
    }
}

TEST_CASE("reset() starts afresh and zeroForce() makes the force grow from zero again") {
    World world(boxScene(800.0), IndexSpec::parse(kDefaultIndexSpec));
    HapticTick tick;
    TickOutput out = pressTo(tick, world.current(), 0.002);
    const double held = 800.0 * (0.002 + GodObjectRenderer::kSkinM);
    REQUIRE(out.forceN.y == Approx(held));

    SECTION("zeroForce: the next force is at most one rate-limit step") {
        tick.zeroForce();
        out = tick.tick(world.current(), Vec3(0, 0.023, 0), Vec3(0.0), 1e-3, Vec3(0.0));
        CHECK(out.render.force.y == Approx(held)); // the proxy stayed
        CHECK(out.forceN.y == Approx(1.0).epsilon(1e-12));
    }
    SECTION("reset: the proxy starts on the device point, which is inside the box, so the box "
            "is ignored until the proxy has left it") {
        tick.reset();
        out = tick.tick(world.current(), Vec3(0, 0.023, 0), Vec3(0.0), 1e-3, Vec3(0.0));
        CHECK(out.render.proxy == Vec3(0, 0.023, 0));
        CHECK(out.forceN == Vec3(0.0));
        CHECK_FALSE(out.newSnapshot); // a fresh start is not a new snapshot
    }
}

TEST_CASE("a new snapshot re-binds the cursors and is reported once, moving objects are "
          "candidates") {
    World world(boxScene(800.0), IndexSpec::parse(kDefaultIndexSpec));
    HapticTick tick;
    const Vec3 p(0.06, 0.023, 0.0);
    TickOutput out = tick.tick(world.current(), p, Vec3(0.0), 1e-3, Vec3(0.0));
    CHECK_FALSE(out.newSnapshot); // the first tick binds
    out = tick.tick(world.current(), p, Vec3(0.0), 1e-3, Vec3(0.0));
    CHECK_FALSE(out.newSnapshot);

    // An object added around the proxy's path is not in the index yet: only the snapshot's
    // moving list names it, and the tick tests it.
    Material m;
    m.stiffness = 800.0;
    world.addObject(makeBox(8, Vec3(0.06, 0, 0), Vec3(0.02), Quat(1, 0, 0, 0), m));
    REQUIRE(world.current().moving.size() == 1);
    out = tick.tick(world.current(), Vec3(0.06, 0.03, 0.0), Vec3(0.0), 1e-3, Vec3(0.0));
    CHECK(out.newSnapshot);
    CHECK(out.render.contactCount == 0);
    out = tick.tick(world.current(), Vec3(0.06, 0.019, 0.0), Vec3(0.0), 1e-3, Vec3(0.0));
    CHECK_FALSE(out.newSnapshot);
    CHECK(out.render.contactCount == 1);
    CHECK(out.render.contacts[0].id == 8);
    CHECK(out.render.force.y == Approx(800.0 * (0.001 + GodObjectRenderer::kSkinM)));
}

namespace {

/// Counts its calls, checks it got no device reading, and returns `force`.
struct NoSampleHook {
    Vec3 force{0.0};
    int calls = 0;
    bool sawDefaultSample = true;
};

Vec3 noSampleHook(void* context, const TickHookArgs& a) noexcept {
    auto& h = *static_cast<NoSampleHook*>(context);
    ++h.calls;
    h.sawDefaultSample = h.sawDefaultSample && a.sample.position == Vec3(0.0) &&
                         a.sample.sequence == 0 && a.sample.buttons == 0;
    return h.force;
}

} // namespace

TEST_CASE("the tick adds its effects and its hook to the render force, each reported apart, "
          "before the safety filter") {
    World world(boxScene(500.0), IndexSpec::parse(kDefaultIndexSpec));
    HapticTick tick;
    const std::vector<ForceEffect> effects = {ForceEffect::constant(Vec3(0.2, 0, 0)),
                                              ForceEffect::damper(3.0)};
    tick.setEffects(EffectSet(effects));
    NoSampleHook hook;
    hook.force = Vec3(0, 0, -0.1);
    tick.setHook({&noSampleHook, &hook});
    const TickOutput out = pressTo(tick, world.current(), 0.002); // held still: damper adds 0
    CHECK(hook.calls == 101);
    CHECK(hook.sawDefaultSample); // the tick without a device reading hands over a default one
    CHECK(out.effectsN == Vec3(0.2, 0, 0));
    CHECK(out.hookN == Vec3(0, 0, -0.1));
    CHECK_FALSE(out.hookNonFinite);
    CHECK(out.forceN.x == Approx(out.render.force.x + 0.2).epsilon(1e-12));
    CHECK(out.forceN.y == Approx(out.render.force.y).epsilon(1e-12));
    CHECK(out.forceN.z == Approx(out.render.force.z - 0.1).epsilon(1e-12));
    CHECK(tick.effects().size() == 2);

    // In free space, a moving point feels the damper: -b v, with the velocity given.
    HapticTick free;
    free.setEffects(EffectSet(effects));
    free.setHook({&noSampleHook, &hook});
    const TickOutput moving =
        free.tick(world.current(), Vec3(0.08, 0, 0), Vec3(0.1, 0, 0), 1e-3, Vec3(0.0));
    CHECK(moving.render.force == Vec3(0.0));
    CHECK(moving.effectsN.x == Approx(0.2 - 0.3).epsilon(1e-12));
    CHECK(moving.forceN.x == Approx(0.2 - 0.3).epsilon(1e-12));
    CHECK(moving.forceN.z == Approx(-0.1).epsilon(1e-12));

    // A NaN from the hook adds nothing and is flagged; the effects still apply.
    hook.force = Vec3(std::numeric_limits<double>::quiet_NaN());
    const TickOutput bad = free.tick(world.current(), Vec3(0.08, 0, 0), Vec3(0.0), 1e-3, Vec3(0.0));
    CHECK(bad.hookNonFinite);
    CHECK(bad.hookN == Vec3(0.0));
    CHECK(bad.forceN == Vec3(0.2, 0, 0));
}

namespace {

/// The smallest distance from the centre to a facet plane of a mesh centred on the origin,
/// at most r (m): how deep below a sphere of radius r its facets reach.
double nearestFacetPlane(const TriangleMesh& mesh, double r) {
    double nearest = r;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const auto [v0, v1, v2] = mesh.corners(t);
        nearest = std::min(nearest, glm::dot(glm::normalize(glm::cross(v1 - v0, v2 - v0)), v0));
    }
    return nearest;
}

} // namespace

TEST_CASE("a hand sliding over a fine mesh whose leaves are smaller than one tick's motion stays "
          "on the surface - the leaves the proxy slides over are rendered too") {
    hapto::test::buildOnOneThread();
    // An icosphere of 327 680 triangles (edges about 0.45 mm) in an octree of 0.5 mm leaves,
    // and a device 1 mm inside it sliding 0.5 mm per tick over its top: every few ticks the
    // proxy slides into a leaf that neither the device's nor its own old leaf lists.
    const double r = 0.05;
    const int subdiv = GENERATE(3, 7);
    INFO("subdivisions " << subdiv);
    const Scene scene(Aabb{Vec3(-0.06), Vec3(0.06)},
                      {makeMesh(1, Vec3(0.0), test::makeIcosphere(subdiv, r))});
    const char* spec = GENERATE("grid:64", "octree:8:0.0005");
    INFO(spec);
    World world(scene, IndexSpec::parse(spec));
    HapticTick tick;
    int touching = 0;
    int ticks = 0;
    double deepest = 0.0;
    const double polar = 0.3; // rad from the pole: a circle of about 1.5 cm radius
    const auto along = [&](double a) {
        return Vec3(std::sin(polar) * std::cos(a), std::cos(polar), std::sin(polar) * std::sin(a));
    };
    for (int i = 0; i <= 700; ++i) {
        // In along a radius for 100 ticks to 1 mm inside the surface, then round the circle at
        // 0.5 mm per tick, 1 mm inside.
        const double u = std::min(1.0, i / 100.0);
        const double depth = r + 0.01 - u * 0.011;
        const double a = i > 100 ? (i - 100) * 0.0005 / ((r - 0.001) * std::sin(polar)) : 0.0;
        const Vec3 p = depth * along(a);
        const TickOutput out = tick.tick(world.current(), p, Vec3(NAN), 1e-3, Vec3(0.0));
        if (i > 110) {
            ++ticks;
            touching += out.render.contactCount > 0 ? 1 : 0;
            deepest = std::max(deepest, r - glm::length(out.render.proxy));
        }
    }
    // The facets lie inside the sphere: the deepest the proxy may rest is the nearest facet
    // plane's distance below r.
    const double nearestPlane = nearestFacetPlane(*scene.object(0).mesh, r);
    INFO("ticks in contact " << touching << " of " << ticks << ", deepest proxy " << deepest
                             << ", facet sag " << r - nearestPlane);
    CHECK(touching == ticks);                 // the device 1 mm inside is always held
    CHECK(deepest < r - nearestPlane + 1e-6); // the proxy never sinks below the facets
}

namespace {

/// A device pressing up to 7 mm into a 5 cm icosphere of 327 680 triangles (edges about
/// 0.45 mm), moving up to 2 x `stepM` per tick on a wavy loop after coming straight down; what
/// the proxy did from the first tick the device is inside for good.
struct DeepPress {
    int ticks = 0, touching = 0, extraLeaves = 0, pullBacks = 0;
    double deepest = 0.0;  ///< The proxy's deepest point below the sphere (m).
    double facetSag = 0.0; ///< The nearest facet plane's depth below the sphere (m).
};

DeepPress pressDeepAndFast(double stepM, const char* spec) {
    const double r = 0.05, press = 0.004;
    const Scene scene(Aabb{Vec3(-0.06), Vec3(0.06)},
                      {makeMesh(1, Vec3(0.0), test::makeIcosphere(7, r))});
    std::vector<Vec3> path;
    for (double z = r + 0.005; z > r - press; z -= stepM) {
        path.emplace_back(0.0, 0.0, z);
    }
    const std::size_t approach = path.size();
    double a = 0.0, b = 0.0, da = stepM / (r - press);
    for (int i = 0; i < 1500; ++i) {
        const Vec3 d =
            glm::normalize(Vec3(std::sin(a), 0.8 * std::sin(2 * a) + std::sin(b), std::cos(a)));
        path.push_back((r - press + press * 0.8 * std::sin(i * 0.013)) * d);
        a += da * (1 + 0.5 * std::sin(i * 0.07));
        b += 0.3 * da * std::cos(i * 0.011);
        if (std::abs(a) > 0.6) {
            da = -da;
        }
    }
    DeepPress got;
    got.facetSag = r - nearestFacetPlane(*scene.object(0).mesh, r);
    World world(scene, IndexSpec::parse(spec));
    HapticTick tick;
    for (std::size_t i = 0; i < path.size(); ++i) {
        const TickOutput out = tick.tick(world.current(), path[i], Vec3(NAN), 1e-3, Vec3(0.0));
        if (i > approach) { // the device is at least 0.8 mm inside from here on
            ++got.ticks;
            got.touching += out.render.contactCount > 0 ? 1 : 0;
            got.deepest = std::max(got.deepest, r - glm::length(out.render.proxy));
            got.extraLeaves += out.extraLeaves;
            got.pullBacks += out.pullBacks;
        }
    }
    return got;
}

} // namespace

TEST_CASE("a hand pressing deep and fast over a fine mesh is held on every tick under every "
          "index - the leaves of the proxy's whole path are rendered") {
    hapto::test::buildOnOneThread();
    // Up to 2 mm per tick: the solver's passes slide the proxy sideways over several small
    // leaves before it settles, so walking only the straight ways from its start missed some,
    // and a proxy that slid over an unlisted leaf fell through the surface. Every index must
    // give the same hold.
    const char* spec = GENERATE("grid:64", "octree:8:0.0005", "octree:2:0.005");
    const DeepPress got = pressDeepAndFast(0.001, spec);
    INFO(spec << ": " << got.touching << " of " << got.ticks << " held, deepest " << got.deepest
              << " (facet sag " << got.facetSag << "), extra leaves " << got.extraLeaves);
    CHECK(got.touching == got.ticks);
    CHECK(got.deepest < got.facetSag + 1e-6);
    CHECK(got.pullBacks == 0);
}

TEST_CASE("a hand faster than its leaves can be listed has its goal pulled back - the proxy moves "
          "less, never through the surface, and the hand is held") {
    hapto::test::buildOnOneThread();
    // Up to 6 mm per tick over 0.2 mm leaves: more leaves than a tick can list
    // (HapticTick::kExtraLeaves). The goal is pulled back toward the proxy instead: the proxy
    // moves less on those ticks but never sinks into the mesh, and the contacts and force are
    // still the device point's.
    const DeepPress got = pressDeepAndFast(0.003, "octree:8:0.0002");
    INFO(got.touching << " of " << got.ticks << " held, deepest " << got.deepest << ", pull-backs "
                      << got.pullBacks);
    REQUIRE(got.pullBacks > 0); // the case reaches the fail-safe
    CHECK(got.deepest < got.facetSag + 1e-6);
    CHECK(got.touching == got.ticks);
}

TEST_CASE("timing a tick's stages changes none of its results, and the stamps are in stage order "
          "within the tick, re-solves included") {
    hapto::test::buildOnOneThread();
    // The fine-mesh slide of the test above, with its re-solves over leaves the proxy slides
    // into (`hapto bench tick` times the servo's own tick this way), ticked by a timed and an
    // untimed HapticTick side by side.
    const double r = 0.05;
    const Scene scene(Aabb{Vec3(-0.06), Vec3(0.06)},
                      {makeMesh(1, Vec3(0.0), test::makeIcosphere(7, r))});
    World world(scene, IndexSpec::parse("octree:8:0.0005"));
    HapticTick plain, timed;
    HapticTick::StageStamps stamps{};
    timed.timeStages(&stamps);
    int solvedAgain = 0;
    for (int i = 0; i <= 300; ++i) {
        const double u = std::min(1.0, i / 100.0);
        const double a = i > 100 ? (i - 100) * 0.0005 / (r - 0.001) : 0.0;
        const Vec3 p = (r + 0.01 - u * 0.011) * Vec3(std::sin(a), std::cos(a), 0.0);
        const TickOutput want = plain.tick(world.current(), p, Vec3(NAN), 1e-3, Vec3(0.0));
        stamps.fill(0);
        const std::uint64_t before = rt::nowNs();
        const TickOutput got = timed.tick(world.current(), p, Vec3(NAN), 1e-3, Vec3(0.0));
        const std::uint64_t after = rt::nowNs();
        INFO("tick " << i);
        REQUIRE(got.forceN == want.forceN);
        REQUIRE(got.render.proxy == want.render.proxy);
        REQUIRE(got.render.objectsTested == want.render.objectsTested);
        REQUIRE(got.solves == want.solves);
        CHECK(before <= stamps[0]);
        for (std::size_t s = 1; s < stamps.size(); ++s) {
            CHECK(stamps[s - 1] <= stamps[s]);
        }
        CHECK(stamps.back() <= after);
        solvedAgain += got.solves > 1 ? 1 : 0;
    }
    CHECK(solvedAgain > 0); // the path did make the tick solve again
}

TEST_CASE("a proxy left behind its hand moves at most maxProxyStepM a tick toward it, pushing "
          "k (proxy - device point) all the while, and one at its hand follows a jump") {
    World world(boxScene(800.0), IndexSpec::parse(kDefaultIndexSpec));
    for (const double stepM : {RendererConfig{}.maxProxyStepM, 0.002}) {
        INFO("step " << stepM << " m");
        RendererConfig config;
        config.maxProxyStepM = stepM;
        HapticTick tick(config);
        // 2 cm into the box's top face (y = 0.025), then the hand jumps 3 cm along it at once.
        TickOutput out = pressTo(tick, world.current(), 0.02, -0.015);
        REQUIRE(out.render.contactCount == 1);
        const Vec3 p(0.015, 0.005, 0.0);
        Vec3 last = out.render.proxy;
        double firstStep = 0.0;
        for (int i = 0; i < 200; ++i) {
            out = tick.tick(world.current(), p, Vec3(0.0), 1e-3, Vec3(0.0));
            const RenderOutput& r = out.render;
            INFO("tick " << i << " proxy x " << r.proxy.x);
            const double step = glm::length(r.proxy - last);
            CHECK(step <= stepM * (1.0 + 1e-12));
            CHECK(r.proxy.x >= last.x); // toward the hand's projection, never back
            REQUIRE(r.contactCount == 1);
            CHECK(r.contacts[0].normal == Vec3(0, 1, 0));
            CHECK(r.proxy.y == Approx(last.y).margin(1e-12)); // on the face
            CHECK(glm::length(r.force - 800.0 * (r.proxy - p)) <= 1e-9);
            firstStep = i == 0 ? step : firstStep;
            last = r.proxy;
        }
        // The first step: stepM toward the hand, on the face (3 cm along, 2 cm below it).
        CHECK(firstStep == Approx(stepM * 0.03 / std::sqrt(0.03 * 0.03 + 0.02 * 0.02)));
        // Then ever shorter steps, ending over the hand.
        CHECK(last.x == Approx(0.015).margin(1e-9));
        // Back out above the face: the proxy steps up to it, then follows any jump in free
        // space at once.
        const Vec3 above(0.015, 0.04, 0.0);
        for (int i = 0; i < 10; ++i) {
            out = tick.tick(world.current(), above, Vec3(0.0), 1e-3, Vec3(0.0));
        }
        CHECK(out.render.proxy == above);
        for (const Vec3& q : {Vec3(-0.09, 0.1, 0.05), Vec3(0.09, 0.1, -0.05)}) {
            out = tick.tick(world.current(), q, Vec3(0.0), 1e-3, Vec3(0.0));
            CHECK(out.render.proxy == q);
        }
    }
}

TEST_CASE("the proxy's step is checked, and a device scaled into the world steps as far in its "
          "own motion") {
    for (const double bad : {0.0, -0.001, std::nan(""), HUGE_VAL}) {
        RendererConfig config;
        config.maxProxyStepM = bad;
        CHECK_THROWS_WITH(HapticTick(config),
                          Catch::Contains("maxProxyStepM must be a finite value > 0 m"));
    }
    CHECK(withDeviceSettings(RendererConfig{}, RendererSettings{}).maxProxyStepM ==
          RendererConfig{}.maxProxyStepM);
    CHECK(withDeviceSettings(RendererConfig{}, RendererSettings{}, 10.0).maxProxyStepM ==
          Approx(10.0 * RendererConfig{}.maxProxyStepM));
}

TEST_CASE("a proxy trapped far behind a hand that pushed through keeps its contacts and the "
          "device point's force when its goal is pulled back, and stays out of every cube") {
    hapto::test::buildOnOneThread();
    // 10^3 cubes of 0.5 mm filling half of a 6.25 mm cube, and the benchmarks' hand walk (up
    // to 0.5 mm per tick) through them, ignoring the force: the proxy is caught in the pockets
    // between cubes, millimetres behind, and its way toward the hand (at most
    // RendererConfig::maxProxyStepM a tick) can cross more 0.25 mm leaves than one tick can list
    // (HapticTick::kExtraLeaves), so its goal is pulled back.
    RandomOptions options;
    options.count = 1000;
    options.workspace = 0.00625;
    options.cubeSize = 0.0005;
    const Scene scene = makeRandomScene(options);
    const World world(scene, IndexSpec::parse("octree:8:0.00025"));
    const std::vector<Vec3> path = experiments::makeHandWalk(scene.bounds(), 1, 3000);
    HapticTick tick;
    int pulled = 0, pulledInContact = 0, pulledHeld = 0, stays = 0, nudged = 0;
    bool wasInContact = false;
    for (const Vec3& p : path) {
        const TickOutput out = tick.tick(world.current(), p, Vec3(0.0), 1e-3, Vec3(0.0));
        const RenderOutput& r = out.render;
        // The proxy is never inside a cube (1 nm of rounding allowed).
        for (const SceneObject& o : scene.objects()) {
            const Vec3 d = glm::abs(r.proxy - o.center) - o.halfExtents;
            REQUIRE(std::max({d.x, d.y, d.z}) > -1e-9);
        }
        // In contact the force is the device point's: k (proxy - device), pulled back or not
        // (no damping, no velocity).
        if (r.contactCount > 0) {
            const Vec3 expected = 800.0 * (r.proxy - p);
            REQUIRE(glm::length(r.force - expected) <= 1e-9 * (1.0 + glm::length(expected)));
        }
        if (out.pullBacks > 0) {
            ++pulled;
            if (wasInContact) {
                ++pulledInContact;
                pulledHeld += r.contactCount > 0 ? 1 : 0;
            }
            stays += out.pullBacks == HapticTick::kPullBacks ? 1 : 0;
            nudged += out.pullBacks == HapticTick::kPullBacks - 1 ? 1 : 0;
        }
        wasInContact = r.contactCount > 0;
    }
    INFO(pulled << " ticks pulled back, " << pulledInContact << " of them from contact, "
                << pulledHeld << " of those still in contact, " << nudged
                << " moved the proxy only by the nudge, " << stays
                << " kept the proxy where it was, of " << path.size());
    REQUIRE(pulled > 20); // the case reaches the pull-backs
    REQUIRE(pulledInContact > 20);
    // Before the pull-backs took the force at the device point, the last one (the proxy stays,
    // no force) ended most of them: a hand pushing into the cubes felt nothing one tick in three.
    // Here 88 % of those that started in contact end in contact; the rest slid off their cube
    // toward a goal between the cubes.
    CHECK(pulledHeld >= pulledInContact * 4 / 5);
    CHECK(stays <= pulled / 10);
    // Before the first pull-back started at the edge of the listed leaves (halfway to the
    // device point instead, centimetres away), 139 of 164 pulled-back ticks here took every
    // halving and moved the proxy only by the 1 um nudge: a trapped proxy crawled.
    CHECK(nudged <= pulled / 10);
}

namespace {

/// Every member the tick asks of a force algorithm but restore(): a tick over it could not
/// solve a tick again with more leaves.
struct NoRestore {
    struct State {
        Vec3 proxy{0.0};
    };
    explicit NoRestore(const RendererConfig&) {}
    void reset(const Vec3&) noexcept {}
    RenderOutput update(const Scene&, const CandidateSet&, const Vec3&, const Vec3&,
                        double) noexcept {
        return {};
    }
    RenderOutput update(const Scene&, const CandidateSet&, const Vec3&, const Vec3&, const Vec3&,
                        double) noexcept {
        return {};
    }
    Vec3 proxy() const noexcept { return mState.proxy; }
    bool inContact() const noexcept { return false; }
    const State& state() const noexcept { return mState; }
    std::span<const Vec3> visitedPath(int) const noexcept { return {}; }
    State mState;
};

/// The same with restore(): the smallest force algorithm.
struct Minimal : NoRestore {
    using NoRestore::NoRestore;
    void restore(const State& state) noexcept { mState = state; }
};

} // namespace

TEST_CASE("the force-algorithm seam: the god-object renderer is one, and the tick runs over it") {
    STATIC_REQUIRE(ForceAlgorithm<GodObjectRenderer>);
    STATIC_REQUIRE(ForceAlgorithm<Minimal>);
    STATIC_REQUIRE_FALSE(ForceAlgorithm<NoRestore>);
    STATIC_REQUIRE(std::is_same_v<HapticTick, BasicHapticTick<GodObjectRenderer>>);
    STATIC_REQUIRE(std::is_same_v<decltype(std::declval<const HapticTick&>().renderer()),
                                  const GodObjectRenderer&>);
}
