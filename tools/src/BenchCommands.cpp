// `hapto bench query`: per-query cost of indices over one scene, along one hand-speed walk.

#include "Commands.h"
#include "Options.h"

#include "hapto/experiments/HandWalk.h"
#include "hapto/index/Cursor.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/InputError.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace hapto::cli {
namespace {

using Clock = std::chrono::steady_clock;

/// Steps of the walk each index runs before the next one takes its turn.
constexpr std::size_t kBlockSteps = 1024;

/// Keeps a value alive as far as the optimiser knows, so the work making it is not dropped.
template <class T> void keep(const T& value) {
    asm volatile("" : : "g"(value) : "memory");
}

/// One `--index` argument: a spec and the cursor strategy after '@'.
struct Target {
    std::string label; ///< As printed: the spec's canonical text, plus @strategy when given.
    IndexSpec spec;
    CursorStrategy strategy = CursorStrategy::NeighbourLinks;
};

Target parseTarget(const std::string& text) {
    const std::size_t at = text.find('@');
    Target t;
    try {
        t.spec = IndexSpec::parse(std::string_view(text).substr(0, at));
    } catch (const InputError& e) {
        throw InputError(std::string("--index: ") + e.what());
    }
    t.label = t.spec.toString();
    if (at != std::string::npos) {
        const std::string strategy = text.substr(at + 1);
        if (strategy == "root") {
            t.strategy = CursorStrategy::FromRoot;
        } else if (strategy == "climb") {
            t.strategy = CursorStrategy::Climb;
        } else if (strategy == "links") {
            t.strategy = CursorStrategy::NeighbourLinks;
        } else {
            throw InputError("--index '" + text + "': unknown cursor strategy '" + strategy +
                             "'; use @root, @climb or @links (the default), as in "
                             "octree:2:0.005@climb");
        }
        t.label += "@" + strategy;
    }
    return t;
}

/// One index being driven: its build, its cursor and what it measured.
struct Run {
    Target target;
    std::unique_ptr<SpatialIndex> index;
    Cursor cursor;
    std::vector<double> nsPerQuery; // one sample per timed batch
    std::uint64_t steps = 0;
    std::uint64_t locateSteps = 0;
    std::uint64_t candidates = 0;
    std::uint64_t touched = 0; // sum of every candidate slot read
    double totalNs = 0.0;      // all timed batches
};

/// The nearest-rank quantile of sorted samples.
double quantile(const std::vector<double>& sorted, double q) {
    if (sorted.empty()) {
        return 0.0;
    }
    const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
    return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

/// Median cost of one steady_clock reading (ns), to read --batch 1 figures against.
double clockOverheadNs() {
    std::vector<double> d(1001);
    for (double& x : d) {
        const auto t0 = Clock::now();
        const auto t1 = Clock::now();
        x = static_cast<double>(
            std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count());
    }
    std::nth_element(d.begin(), d.begin() + 500, d.end());
    return d[500];
}

struct QueryArgs {
    std::string scene;
    std::vector<std::string> indices;
    std::size_t steps = 100000;
    std::uint64_t seed = 1;
    std::size_t batch = 16;
    bool json = false;
    std::uint64_t maxIndexMb = IndexSpec::kDefaultMaxMegabytes;
};

void runQuery(const QueryArgs& args) {
    std::vector<std::string> texts = args.indices;
    if (texts.empty()) {
        texts = {"brute", "grid:5", "octree:2:0.005"};
    }
    std::vector<Target> targets;
    for (const std::string& t : texts) {
        targets.push_back(parseTarget(t));
    }
    const std::size_t steps = args.steps;
    const Scene scene = loadSceneOrDefault(args.scene);

    std::vector<std::unique_ptr<Run>> runs;
    for (const Target& t : targets) {
        auto run = std::make_unique<Run>();
        run->target = t;
        run->index = buildIndex(scene, t.spec.withMaxMegabytes(args.maxIndexMb));
        run->cursor = Cursor(*run->index, t.strategy);
        run->nsPerQuery.reserve(steps / args.batch + steps / kBlockSteps + 2);
        runs.push_back(std::move(run));
    }

    // The same walk for every index: generated a block at a time, each block run by every
    // index in turn (starting with a different one each block), each cursor going on from
    // where its previous block left it.
    experiments::HandWalk walk(scene.bounds(), args.seed);
    std::vector<Vec3> block(kBlockSteps);
    for (std::size_t done = 0, round = 0; done < steps; ++round) {
        const std::size_t length = std::min(kBlockSteps, steps - done);
        for (std::size_t k = 0; k < length; ++k) {
            block[k] = walk.next();
        }
        for (std::size_t r = 0; r < runs.size(); ++r) {
            Run& run = *runs[(r + round) % runs.size()];
            std::uint64_t locateSteps = 0, candidates = 0, touched = 0;
            for (std::size_t b = 0; b < length; b += args.batch) {
                const std::size_t end = std::min(length, b + args.batch);
                const auto t0 = Clock::now();
                for (std::size_t k = b; k < end; ++k) {
                    const LocateResult res = run.cursor.locate(block[k]);
                    for (const std::uint32_t slot : res.candidates) {
                        touched += slot;
                    }
                    locateSteps += res.steps;
                    candidates += res.candidates.size();
                }
                const auto t1 = Clock::now();
                keep(touched);
                const auto batchNs = static_cast<double>(
                    std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count());
                run.nsPerQuery.push_back(batchNs / static_cast<double>(end - b));
                run.totalNs += batchNs;
            }
            run.steps += length;
            run.locateSteps += locateSteps;
            run.candidates += candidates;
            run.touched += touched;
        }
        done += length;
    }

    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    if (!args.json) {
        std::printf("scene:   %s, %u objects\n",
                    args.scene.empty() ? "(embedded default scene)" : args.scene.c_str(),
                    scene.size());
        std::printf("walk:    %zu steps of 1 ms, seed %llu, <= 0.5 m/s (<= 0.5 mm per step), "
                    "mirrored at the bounds\n",
                    steps, static_cast<unsigned long long>(args.seed));
        std::printf("timing:  steady_clock around batches of %zu queries (per-query ns = batch "
                    "/ %zu); indices interleaved in blocks of %zu steps; one clock reading "
                    "costs ~%.0f ns\n\n",
                    args.batch, args.batch, kBlockSteps, clockOverheadNs());
        std::printf("%-24s %9s %10s %9s %9s %9s %12s %12s\n", "index", "build ms", "bytes/obj",
                    "p50 ns", "p99.9 ns", "mean ns", "steps/query", "cand./query");
    }
    for (const auto& run : runs) {
        std::vector<double>& ns = run->nsPerQuery;
        const double mean = run->totalNs / static_cast<double>(run->steps);
        std::sort(ns.begin(), ns.end());
        const double p50 = quantile(ns, 0.5), p999 = quantile(ns, 0.999);
        const double stepsMean =
            static_cast<double>(run->locateSteps) / static_cast<double>(run->steps);
        const double candMean =
            static_cast<double>(run->candidates) / static_cast<double>(run->steps);
        if (args.json) {
            out.push_back({{"index", run->target.label},
                           {"objects", scene.size()},
                           {"steps", run->steps},
                           {"ns_p50", p50},
                           {"ns_p999", p999},
                           {"ns_mean", mean},
                           {"locate_steps_mean", stepsMean},
                           {"candidates_mean", candMean}});
        } else {
            const IndexStats& st = run->index->stats();
            std::printf("%-24s %9.2f %10.1f %9.1f %9.1f %9.1f %12.3f %12.2f\n",
                        run->target.label.c_str(), 1e3 * st.buildSeconds, st.bytesPerObject, p50,
                        p999, mean, stepsMean, candMean);
        }
        keep(run->touched);
    }
    if (args.json) {
        std::cout << out.dump(2) << "\n";
    }
}

} // namespace

void addBenchCommands(CLI::App& app) {
    CLI::App* bench = app.add_subcommand("bench", "Measure the speed of the spatial indices");
    bench->require_subcommand(1);

    auto args = std::make_shared<QueryArgs>();
    auto* cmd = bench->add_subcommand(
        "query",
        "Per-query cost of one or more indices over the same scene, along the same seeded "
        "hand-speed walk (1 kHz positions, <= 0.5 m/s, so <= 0.5 mm per step, mirrored at the "
        "bounds). Every index is built, then all are driven in turn, interleaved in blocks of "
        "1024 steps, each through its own cursor. A query is cursor locate plus reading every "
        "candidate id (their sum is kept). Timing: std::chrono::steady_clock read around each "
        "batch of --batch consecutive queries of one index, divided by the batch size; median, "
        "p99.9 and mean are over those per-batch figures (so with the default 16, one slow "
        "query is averaged with 15 others; --batch 1 times every query alone, clock reading "
        "included, whose cost is printed). Also reports mean locate steps (links followed) and "
        "candidates per query.");
    cmd->add_option("--scene", args->scene, "Scene file (default: the embedded default scene)");
    cmd->add_option("--index", args->indices,
                    "Index to measure, repeatable: brute, grid:N, octree:M:MIN (MIN in m), each "
                    "optionally with :aabb, then optionally @root, @climb or @links to pick the "
                    "octree cursor's strategy (default links), e.g. octree:2:0.005@climb. "
                    "Default: brute, grid:5 and octree:2:0.005");
    addMaxIndexMbOption(cmd, args->maxIndexMb);
    cmd->add_option("--steps", args->steps, "Walk steps (queries) per index, e.g. 1e5")
        ->capture_default_str()
        ->transform(wholeNumber(1, 4e9));
    cmd->add_option("--seed", args->seed, "Walk seed; same seed, same walk")
        ->capture_default_str()
        ->check(finiteRange(0, kMaxSeed));
    cmd->add_option("--batch", args->batch, "Queries per clock reading (1 = time each query alone)")
        ->capture_default_str()
        ->check(finiteRange(1, kBlockSteps));
    cmd->add_flag("--json", args->json,
                  "Print only a JSON array of {index, objects, steps, ns_p50, ns_p999, ns_mean, "
                  "locate_steps_mean, candidates_mean}");
    cmd->callback([args] { runQuery(*args); });
}

} // namespace hapto::cli
