// hapto_bench: per-query cost, build time and memory of hapto's indices against the broad
// phases people use instead (Bullet's btDbvt, FCL's dynamic AABB tree, Boost.Geometry's
// rtree), in one process, over the same boxes, driven by the same hand-speed walk.
//
// Benchmarks are named KIND/SCENE/N/STRUCTURE, KIND = query or build, SCENE = random or
// cluster, N = 1000 .. 1000000, so a filter picks a slice:
//
//   hapto_bench                                          # everything: about 4-6 minutes
//   hapto_bench --benchmark_min_time=0.1                 # everything, shorter: 2-3 minutes
//   hapto_bench --benchmark_filter='query/random/'       # random scenes, queries only
//   hapto_bench --benchmark_filter='/100000/' --benchmark_min_time=0.2
//   hapto_bench --benchmark_filter='query/random/1000/' --benchmark_min_time=0.01  # smoke
//
// Query benchmarks: one query per iteration, so the time is ns per query. Every structure
// returns the slots of the boxes holding the point into one reused, pre-reserved vector (the
// broad phase's job); hapto's do it as cursor locate + AABB filter of the leaf's candidates.
// The `*-leaf` variants time what hapto's servo path does instead: locate and read the
// candidate span, no filter. Counters (per query): candidates (hapto: the leaf's objects;
// trees: the boxes they return), hits (boxes holding the point), steps (hapto cursor links);
// and bytes_per_object (hapto: IndexStats bytes / objects; baselines: heap growth around the
// build, glibc mallinfo2), heap_bytes_per_object (heap growth for all), checked_points.
// Build benchmarks time one build per iteration (wall clock), each run started from a trimmed
// heap, as in a fresh process (buildLoop, HeapUsage.h); hapto builds with TBB on the number of
// threads in the name.
//
// Before timing, each structure is checked once at every check point of its scene: it must
// return every object whose solid holds the point and nothing whose AABB misses it (the
// baselines: exactly the AABB set). A disagreement fails that benchmark and the exit code.

#include "BenchScenes.h"
#include "BoostRtreeBroadPhase.h"
#include "BulletDbvtBroadPhase.h"
#include "FclBroadPhase.h"
#include "HaptoBroadPhase.h"
#include "HeapUsage.h"

#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/Generators.h"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace hapto::bench {

/// The mesh scenes' benchmarks (MeshBench.cpp): mesh-near, mesh-build, mesh-tick. [control]
void registerMeshBenchmarks();
/// Mesh baselines that returned a wrong set at a check point (MeshBench.cpp). [control]
std::size_t meshCheckFailures();
/// Mesh check points passed. [control]
std::size_t meshChecksPassed();

namespace {

constexpr std::size_t kCounts[] = {1000, 10000, 100000, 1000000};
constexpr SceneKind kKinds[] = {SceneKind::Random, SceneKind::Cluster};
constexpr std::size_t kReserve = 4096; // ids a query may return before `out` grows once

std::size_t gChecks = 0;            // check points passed, over all structures
std::size_t gCheckedStructures = 0; // structures checked
std::size_t gFailures = 0;          // structures that disagreed

/// The structure under test, kept between the calls Google Benchmark makes for one benchmark
/// (it calls the function several times while it sizes the iteration count), and handed from
/// a structure's build benchmark to its query benchmark, so 10^6 objects are built once. One
/// at a time.
struct Prepared {
    std::string key; // SCENE/N/STRUCTURE
    std::shared_ptr<void> structure;
    double bytesPerObject = 0.0;     // the counter bytes_per_object
    double heapBytesPerObject = 0.0; // heap growth around the build
    bool checked = false;            // the agreement check ran
    std::string error;               // "" when the agreement check passed
    std::size_t walkIndex = 0;       // where the walk goes on at the next call
};

Prepared& prepared() {
    static Prepared p;
    return p;
}

/// hapto's index for a case and spec, shared by every cursor strategy (one at a time).
struct SharedIndex {
    std::string key;
    std::shared_ptr<const SpatialIndex> index;
    double heapBytesPerObject = 0.0;
};

SharedIndex& haptoIndexCache() {
    static SharedIndex shared;
    return shared;
}

std::shared_ptr<const SpatialIndex> haptoIndex(const SceneCase& c, const IndexSpec& spec,
                                               double& heapBytesPerObject) {
    SharedIndex& shared = haptoIndexCache();
    const std::string key =
        std::string(sceneKindName(c.kind)) + "/" + std::to_string(c.count) + "/" + spec.toString();
    if (shared.key != key || !shared.index) {
        shared = {};
        std::size_t grown = 0;
        std::unique_ptr<SpatialIndex> built =
            measureHeap([&] { return buildIndex(c.scene, spec); }, grown);
        shared = {key, std::move(built), static_cast<double>(grown) / c.count};
    }
    heapBytesPerObject = shared.heapBytesPerObject;
    return shared.index;
}

/// Keeps an index a build benchmark made for the query benchmarks after it.
void keepHaptoIndex(const SceneCase& c, std::shared_ptr<const SpatialIndex> index,
                    double heapBytesPerObject) {
    haptoIndexCache() = {std::string(sceneKindName(c.kind)) + "/" + std::to_string(c.count) + "/" +
                             index->spec().toString(),
                         std::move(index), heapBytesPerObject};
}

/// Builds (unless its build benchmark left it) and checks (once) a structure; returns it, or
/// nullptr after SkipWithError.
template <class S, class Make>
S* prepare(benchmark::State& state, const std::string& key, const SceneCase& c, bool exactAabb,
           Make&& make) {
    Prepared& p = prepared();
    if (p.key != key || !p.structure) {
        p = {};
        double heapBytes = 0.0, statBytes = -1.0;
        p.structure = make(heapBytes, statBytes);
        p.key = key;
        p.heapBytesPerObject = heapBytes;
        p.bytesPerObject = statBytes >= 0.0 ? statBytes : heapBytes;
    }
    if (!p.checked) {
        p.error = checkAgreement(*static_cast<S*>(p.structure.get()), c, exactAabb);
        p.checked = true;
        ++gCheckedStructures;
        if (p.error.empty()) {
            gChecks += c.checks.size();
        } else {
            ++gFailures;
            std::fprintf(stderr, "hapto_bench: %s %s\n", key.c_str(), p.error.c_str());
        }
    }
    if (!p.error.empty()) {
        state.SkipWithError(("agreement check failed: " + p.error).c_str());
        return nullptr;
    }
    state.counters["bytes_per_object"] = p.bytesPerObject;
    state.counters["heap_bytes_per_object"] = p.heapBytesPerObject;
    state.counters["checked_points"] = static_cast<double>(c.checks.size());
    return static_cast<S*>(p.structure.get());
}

template <class S> void queryLoop(benchmark::State& state, S& s, const SceneCase& c) {
    std::vector<std::uint32_t> out;
    out.reserve(kReserve);
    const std::size_t mask = c.walk.size() - 1;
    std::size_t i = prepared().walkIndex;
    std::uint64_t candidates = 0, steps = 0, hits = 0;
    for (auto _ : state) {
        const QueryCounts q = s.query(c.walk[i & mask], out);
        ++i;
        candidates += q.candidates;
        steps += q.steps;
        hits += out.size();
        benchmark::DoNotOptimize(out.data());
    }
    prepared().walkIndex = i;
    using benchmark::Counter;
    state.counters["candidates"] =
        Counter(static_cast<double>(candidates), Counter::kAvgIterations);
    state.counters["hits"] = Counter(static_cast<double>(hits), Counter::kAvgIterations);
    state.counters["steps"] = Counter(static_cast<double>(steps), Counter::kAvgIterations);
}

void leafLoop(benchmark::State& state, HaptoBroadPhase& s, const SceneCase& c) {
    const std::size_t mask = c.walk.size() - 1;
    std::size_t i = prepared().walkIndex;
    std::uint64_t candidates = 0, steps = 0, sum = 0;
    for (auto _ : state) {
        const QueryCounts q = s.locateAndTouch(c.walk[i & mask], sum);
        ++i;
        candidates += q.candidates;
        steps += q.steps;
    }
    benchmark::DoNotOptimize(sum);
    prepared().walkIndex = i;
    using benchmark::Counter;
    state.counters["candidates"] =
        Counter(static_cast<double>(candidates), Counter::kAvgIterations);
    state.counters["steps"] = Counter(static_cast<double>(steps), Counter::kAvgIterations);
}

/// A hapto query benchmark: the index spec picked from the case, a cursor strategy.
void haptoQuery(benchmark::State& state, const std::string& name, SceneKind kind, std::size_t count,
                int which, CursorStrategy strategy, bool leafOnly) {
    const SceneCase& c = sceneCase(kind, count);
    const IndexSpec spec = which == 0 ? IndexSpec::brute() : which == 1 ? c.grid : c.octree;
    HaptoBroadPhase* s =
        prepare<HaptoBroadPhase>(state, name, c, false, [&](double& heap, double& stat) {
            auto index = haptoIndex(c, spec, heap);
            stat = index->stats().bytesPerObject;
            return std::make_shared<HaptoBroadPhase>(c.boxes, std::move(index), strategy);
        });
    if (!s) {
        return;
    }
    if (leafOnly) {
        leafLoop(state, *s, c);
    } else {
        queryLoop(state, *s, c);
    }
}

/// A baseline query benchmark.
template <class S>
void baselineQuery(benchmark::State& state, const std::string& name, SceneKind kind,
                   std::size_t count) {
    const SceneCase& c = sceneCase(kind, count);
    S* s = prepare<S>(state, name, c, true, [&](double& heap, double&) {
        std::size_t grown = 0;
        auto built = measureHeap([&] { return std::make_shared<S>(c.boxes); }, grown);
        heap = static_cast<double>(grown) / c.count;
        return built;
    });
    if (s) {
        queryLoop(state, *s, c);
    }
}

void haptoBuild(benchmark::State& state, SceneKind kind, std::size_t count, bool grid,
                int threads) {
    const SceneCase& c = sceneCase(kind, count);
    const IndexSpec spec = grid ? c.grid : c.octree;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    haptoIndexCache() = {}; // free the previous one before building
    double heap = 0.0;
    std::shared_ptr<const SpatialIndex> index = buildLoop(state, count, heap, [&] {
        return std::shared_ptr<const SpatialIndex>(buildIndex(c.scene, spec));
    });
    state.counters["heap_bytes_per_object"] = heap;
    if (index) {
        state.counters["bytes_per_object"] = index->stats().bytesPerObject;
        keepHaptoIndex(c, std::move(index), heap);
    }
}

template <class S>
void baselineBuild(benchmark::State& state, const std::string& key, SceneKind kind,
                   std::size_t count) {
    const SceneCase& c = sceneCase(kind, count);
    prepared() = {}; // free the previous structure before building
    double heap = 0.0;
    std::shared_ptr<S> last =
        buildLoop(state, count, heap, [&] { return std::make_shared<S>(c.boxes); });
    state.counters["heap_bytes_per_object"] = heap;
    if (last) {
        Prepared& p = prepared();
        p.key = key;
        p.structure = std::move(last);
        p.heapBytesPerObject = heap;
        p.bytesPerObject = heap;
    }
}

void registerAll() {
    using benchmark::RegisterBenchmark;
    for (const SceneKind kind : kKinds) {
        for (const std::size_t n : kCounts) {
            // Each structure's build benchmark runs just before its query benchmarks and hands
            // them its last build.
            const std::string sn = std::string(sceneKindName(kind)) + "/" + std::to_string(n) + "/";
            const auto hq = [&](const char* name, int which, CursorStrategy st, bool leaf) {
                const std::string full = "query/" + sn + name;
                RegisterBenchmark(full.c_str(), haptoQuery, full, kind, n, which, st, leaf);
            };
            const auto hb = [&](const char* name, bool grid, int threads) {
                RegisterBenchmark(("build/" + sn + name).c_str(), haptoBuild, kind, n, grid,
                                  threads)
                    ->UseRealTime();
            };
            hq("hapto-brute", 0, CursorStrategy::NeighbourLinks, false);
            hb("hapto-grid/threads:2", true, 2);
            hq("hapto-grid", 1, CursorStrategy::NeighbourLinks, false);
            hq("hapto-grid-leaf", 1, CursorStrategy::NeighbourLinks, true);
            hb("hapto-octree/threads:1", false, 1);
            hb("hapto-octree/threads:2", false, 2);
            hq("hapto-octree-root", 2, CursorStrategy::FromRoot, false);
            hq("hapto-octree-climb", 2, CursorStrategy::Climb, false);
            hq("hapto-octree-links", 2, CursorStrategy::NeighbourLinks, false);
            hq("hapto-octree-links-leaf", 2, CursorStrategy::NeighbourLinks, true);
            const auto baseline = [&](const char* name, auto build, auto query) {
                RegisterBenchmark(("build/" + sn + name).c_str(), build, sn + name, kind, n)
                    ->UseRealTime();
                RegisterBenchmark(("query/" + sn + name).c_str(), query, sn + name, kind, n);
            };
            baseline("bullet-dbvt", baselineBuild<BulletDbvtBroadPhase>,
                     baselineQuery<BulletDbvtBroadPhase>);
            baseline("fcl-dynamic-aabb-tree", baselineBuild<FclBroadPhase>,
                     baselineQuery<FclBroadPhase>);
            baseline("boost-rtree", baselineBuild<BoostRtreeBroadPhase>,
                     baselineQuery<BoostRtreeBroadPhase>);
        }
    }
}

} // namespace
} // namespace hapto::bench

int main(int argc, char** argv) {
    // Our own flag, removed before Google Benchmark sees the arguments: fail unless at least
    // one agreement check ran (the smoke test uses it, so a filter typo cannot pass).
    bool expectChecks = false;
    bool minTimeGiven = false;
    std::vector<char*> args{argv[0]};
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--hapto_expect_checks") == 0) {
            expectChecks = true;
        } else {
            minTimeGiven = minTimeGiven || std::strncmp(argv[i], "--benchmark_min_time", 20) == 0;
            args.push_back(argv[i]);
        }
    }
    // A shorter default than Google Benchmark's 0.5 s, so the whole run takes minutes.
    char defaultMinTime[] = "--benchmark_min_time=0.2";
    if (!minTimeGiven) {
        args.push_back(defaultMinTime);
    }
    args.push_back(nullptr);
    argc = static_cast<int>(args.size()) - 1;
    argv = args.data();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) {
        return 2;
    }
    hapto::bench::registerAll();
    hapto::bench::registerMeshBenchmarks();
    // Start TBB's workers once, so no measured build or heap growth pays for their set-up.
    (void)hapto::buildIndex(hapto::makeLatticeScene({}), hapto::IndexSpec::octree(2, 0.005));
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    using namespace hapto::bench;
    std::fprintf(stderr,
                 "hapto_bench: agreement checked on %zu structures, %zu points passed, "
                 "%zu structures disagreed\n",
                 gCheckedStructures, gChecks, gFailures);
    std::fprintf(stderr, "hapto_bench: mesh baselines: %zu points passed, %zu disagreed\n",
                 meshChecksPassed(), meshCheckFailures());
    if (gFailures > 0 || meshCheckFailures() > 0) {
        return 1;
    }
    if (expectChecks && gChecks == 0 && meshChecksPassed() == 0) {
        std::fprintf(stderr, "hapto_bench: --hapto_expect_checks: no agreement check ran\n");
        return 1;
    }
    return 0;
}
