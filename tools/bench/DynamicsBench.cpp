// hapto_bench, dynamics: the cost of one hapto::Dynamics step with bodies resting on a box in a
// scene of N static objects (issue 37's targets: 1 body <= 100 us p99.9, 16 bodies <= 300 us,
// and the same from 10^3 to 10^6 static objects within 10 %).
//
// Benchmarks, named dynamics-step/N/B (N = 10^3 or 10^6 static cubes, B = 1 or 16 bodies):
// the scene is makeRandomScene's 1 cm cubes at one density (N in a cube of 0.5 m * cbrt(N /
// 10^3)), clear within 16 cm of the origin, plus a static 20 x 2 x 20 cm platform there whose
// top is y = 0, and B dynamic 2 cm, 20 g cubes standing on it (a 4 x 4 grid, 5 cm apart; one at
// the origin for B = 1). The bodies' neighbourhood is the same at every N, so what N changes is
// the index the broad phase asks (the scene's default index) and the memory it spans.
// The bodies never sleep (DynamicsOptions::sleepAfterS = 0: an awake resting body is the
// case that costs; a sleeping one is skipped) and are settled for 0.5 s before timing.
//
// One step per iteration, manual time; counters p50_us, p99_us, p999_us, max_us (wall clock,
// over the iterations of that run), cpu_p50_us and cpu_p999_us (the thread's CPU time per
// step: the step's own cost, without the time other processes held the core) and sink_mm: how far
// the lowest body's bottom got below the platform top at the end (a check that the bodies were
// resting while timed, not falling).
//
//   hapto_bench --benchmark_filter='^dynamics-step/' --benchmark_min_time=2
//               --benchmark_repetitions=5   (one line)
//
// Registered from this file's static initialiser (Google Benchmark's registry), so the
// benchmark main needs no line for it.

#include "hapto/core/Clock.h"
#include "hapto/dynamics/Dynamics.h"
#include "hapto/experiments/TickBench.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/MassProperties.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hapto::bench {
namespace {

constexpr double kBodyEdgeM = 0.02;  // the bodies' edge (m)
constexpr double kBodyMassKg = 0.02; // 2.5 g/cm^3 (glass)
constexpr double kSettleS = 0.5;     // simulated time before timing (s)

/// A scene and its index, built once per N (10^6 cubes take seconds to make and index).
struct Prepared {
    std::shared_ptr<const Scene> scene;
    std::shared_ptr<const SpatialIndex> index;
};

SceneObject restingBody(ObjectId id, double x, double z) {
    const double h = kBodyEdgeM / 2;
    SceneObject body = makeBox(id, Vec3(x, h, z), Vec3(h), Quat(1, 0, 0, 0), generatedMaterial());
    body.body.dynamic = true;
    fillMassProperties(body, kBodyMassKg, std::nullopt, std::nullopt);
    return body;
}

/// N random cubes, the platform and `bodies` (1 or 16) resting bodies.
Scene sceneWith(std::size_t n, int bodies) {
    RandomOptions random;
    random.count = n;
    random.seed = 37;
    random.cubeSize = 0.01;
    random.workspace = 0.5 * std::cbrt(static_cast<double>(n) / 1000.0);
    random.keepClear = 0.15 + random.cubeSize;
    const Scene statics = makeRandomScene(random);
    std::vector<SceneObject> objects(statics.objects().begin(), statics.objects().end());
    const auto nextId = static_cast<ObjectId>(n);
    objects.push_back(makeBox(nextId, Vec3(0.0, -0.01, 0.0), Vec3(0.1, 0.01, 0.1), Quat(1, 0, 0, 0),
                              generatedMaterial()));
    for (int k = 0; k < bodies; ++k) {
        const double x = bodies == 1 ? 0.0 : 0.05 * (k % 4 - 1.5);
        const double z = bodies == 1 ? 0.0 : 0.05 * (k / 4 - 1.5);
        objects.push_back(restingBody(nextId + 1 + static_cast<ObjectId>(k), x, z));
    }
    Scene scene(statics.bounds(), std::move(objects));
    scene.setPhysics(ScenePhysics{});
    return scene;
}

const Prepared& prepared(std::size_t n, int bodies) {
    static std::map<std::pair<std::size_t, int>, Prepared> cache;
    const auto key = std::make_pair(n, bodies);
    if (auto it = cache.find(key); it != cache.end()) {
        return it->second;
    }
    cache.clear(); // one scene at a time: 10^6 objects are a few hundred MB with their index
    Prepared p;
    p.scene = std::make_shared<const Scene>(sceneWith(n, bodies));
    p.index = buildIndex(*p.scene, IndexSpec::parse(defaultIndexSpec(*p.scene)));
    return cache.emplace(key, std::move(p)).first->second;
}

/// How far the lowest body's bottom is below the platform top (mm; negative: above it).
double sinkMm(const Dynamics& dynamics) {
    double lowest = INFINITY;
    for (const BodyState& b : dynamics.bodies()) {
        lowest = std::min(lowest, b.position.y - kBodyEdgeM / 2);
    }
    return -1e3 * lowest;
}

void stepDynamics(benchmark::State& state, std::size_t n, int bodies) {
    const Prepared& p = prepared(n, bodies);
    DynamicsOptions options;
    options.sleepAfterS = 0.0;
    Dynamics dynamics(p.scene, p.index, options);
    for (int s = 0; s < static_cast<int>(kSettleS / dynamics.dtS()); ++s) {
        dynamics.step();
    }
    std::vector<double> us, cpuUs;
    us.reserve(1 << 22);
    cpuUs.reserve(1 << 22);
    for (auto _ : state) {
        const std::uint64_t c0 = threadCpuNs();
        const auto t0 = std::chrono::steady_clock::now();
        dynamics.step();
        const auto t1 = std::chrono::steady_clock::now();
        const std::uint64_t c1 = threadCpuNs();
        const double s = std::chrono::duration<double>(t1 - t0).count();
        state.SetIterationTime(s);
        if (us.size() < us.capacity()) {
            us.push_back(1e6 * s);
            cpuUs.push_back(1e-3 * static_cast<double>(c1 - c0));
        }
    }
    const double maxUs = us.empty() ? 0.0 : *std::max_element(us.begin(), us.end());
    const experiments::Quantiles wall = experiments::quantilesOf(std::move(us));
    const experiments::Quantiles cpu = experiments::quantilesOf(std::move(cpuUs));
    state.counters["p50_us"] = wall.p50;
    state.counters["p99_us"] = wall.p99;
    state.counters["p999_us"] = wall.p999;
    state.counters["max_us"] = maxUs;
    state.counters["cpu_p50_us"] = cpu.p50;
    state.counters["cpu_p999_us"] = cpu.p999;
    state.counters["sink_mm"] = sinkMm(dynamics);
    state.counters["objects"] = static_cast<double>(p.scene->size());
}

bool registerDynamicsBenchmarks() {
    for (const std::size_t n : {1000, 1000000}) {
        for (const int bodies : {1, 16}) {
            const std::string name =
                "dynamics-step/" + std::to_string(n) + "/" + std::to_string(bodies);
            benchmark::RegisterBenchmark(name.c_str(), stepDynamics, n, bodies)
                ->UseManualTime()
                ->Unit(benchmark::kMicrosecond);
        }
    }
    return true;
}

const bool gRegistered = registerDynamicsBenchmarks();

} // namespace
} // namespace hapto::bench
