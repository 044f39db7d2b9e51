// `hapto bench query`: per-query cost of indices over one scene, along one hand-speed walk.
// `hapto bench tick`: the servo step's stages over one scene along the same walk, back to back,
// after a sleep, and after a sleep with the servo loop's warm-up (the harness:
// experiments/TickBench.h; this file parses and prints).

#include "Commands.h"
#include "Options.h"

#include "hapto/experiments/HandWalk.h"
#include "hapto/experiments/TickBench.h"
#include "hapto/experiments/TickMotion.h"
#include "hapto/index/Cursor.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/ServoLoop.h"
#include "hapto/runtime/ServoStep.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
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

/// Runs `block` through `run`'s cursor in batches of `batch` queries, each batch timed.
void queryBlock(Run& run, std::span<const Vec3> block, std::size_t batch) {
    std::uint64_t locateSteps = 0, candidates = 0, touched = 0;
    for (std::size_t b = 0; b < block.size(); b += batch) {
        const std::size_t end = std::min(block.size(), b + batch);
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
    run.steps += block.size();
    run.locateSteps += locateSteps;
    run.candidates += candidates;
    run.touched += touched;
}

/// Prints (or as JSON) each run's build, per-query time and work.
void printQueries(const QueryArgs& args, const Scene& scene,
                  const std::vector<std::unique_ptr<Run>>& runs) {
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    if (!args.json) {
        std::printf("scene:   %s, %u objects\n",
                    args.scene.empty() ? "(embedded default scene)" : args.scene.c_str(),
                    scene.size());
        std::printf("walk:    %zu steps of 1 ms, seed %llu, <= 0.5 m/s (<= 0.5 mm per step), "
                    "mirrored at the bounds\n",
                    args.steps, static_cast<unsigned long long>(args.seed));
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
        const double p50 = experiments::quantileOfSorted(ns, 0.5),
                     p999 = experiments::quantileOfSorted(ns, 0.999);
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

void runQuery(const QueryArgs& args) {
    std::vector<std::string> texts = args.indices;
    if (texts.empty()) {
        texts = {"brute", "grid:5", std::string(kDefaultIndexSpec)};
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
            queryBlock(*runs[(r + round) % runs.size()], {block.data(), length}, args.batch);
        }
        done += length;
    }
    printQueries(args, scene, runs);
}

// ---- `hapto bench tick` ----------------------------------------------------------------------
// The harness (the walk, the runs, the servo's own step with its stage stamps) is
// experiments::runTickBench (TickBench.h); this part checks the options and prints.

using experiments::Quantiles;
using experiments::quantilesOf;
using experiments::TickMode;
using experiments::TickRun;
using experiments::TickTarget;
constexpr std::size_t kStageCount = ServoStepProbe::kStages;

struct TickArgs {
    std::string scene;
    std::vector<std::string> indices;
    std::string device = "walk";
    experiments::TickBenchSettings settings; // indices and walkIn are filled in from the above
    double walkEdgeM = 0.0;                  ///< 0: the walk roams the scene's bounds
    std::string json;
    std::uint64_t maxIndexMb = IndexSpec::kDefaultMaxMegabytes;
    std::vector<std::string> motions;      ///< --motion: names, or "all"
    experiments::MotionOptions motionSize; ///< --objects (ticks and seed from settings)
    std::vector<std::string> modes;        ///< --mode: hot, sleep, sleep+warm
    bool pushMmGiven = false;              ///< --push-mm was given (refused with --motion)
    bool cpuTime = false;                  ///< --cpu-time (with --motion)
};

nlohmann::ordered_json toJson(const Quantiles& q) {
    return {{"ns_p50", q.p50},
            {"ns_p99", q.p99},
            {"ns_p999", q.p999},
            {"ns_max", q.max},
            {"ns_mean", q.mean}};
}

/// The device point's distance from the proxy over a run's ticks (m).
nlohmann::ordered_json gapJson(const std::vector<double>& gapM) {
    const Quantiles q = quantilesOf(gapM);
    return {{"p50", q.p50}, {"p99", q.p99}, {"p999", q.p999}, {"mean", q.mean}};
}

/// The settings the options give, checked (InputError names the option).
experiments::TickBenchSettings tickSettings(const TickArgs& args) {
    experiments::TickBenchSettings s = args.settings;
    std::vector<std::string> texts = args.indices;
    if (texts.empty()) {
        texts = {std::string(kDefaultIndexSpec)};
    }
    for (const std::string& t : texts) {
        try {
            s.indices.push_back(IndexSpec::parse(t).withMaxMegabytes(args.maxIndexMb));
        } catch (const InputError& e) {
            throw InputError(std::string("--index: ") + e.what());
        }
    }
    if (s.warmUs >= s.sleepUs) {
        char message[160];
        std::snprintf(message, sizeof message,
                      "--warm-us %g: not shorter than --sleep-us %g; the warm-up happens inside "
                      "the sleep",
                      s.warmUs, s.sleepUs);
        throw InputError(message);
    }
    if (!args.json.empty()) {
        checkOutputFile(args.json, "--json");
        refuseSameFile(args.json, "--json", args.scene, "--scene");
    }
    s.simDevice = args.device == "sim";
    for (const std::string& m : args.modes) {
        s.modes.push_back(m == "hot"     ? TickMode::Hot
                          : m == "sleep" ? TickMode::Sleep
                                         : TickMode::Warm); // the option checked the names
    }
    return s;
}

void printTickHeader(const TickArgs& args, const experiments::TickBenchSettings& s,
                     const Scene& scene) {
    const Aabb& walkIn = s.walkIn;
    std::printf("scene:   %s, %u objects\n",
                args.scene.empty() ? "(embedded default scene)" : args.scene.c_str(), scene.size());
    std::printf("walk:    %zu ticks per mode of 1 ms, seed %llu, device %s, <= 0.5 m/s, "
                "mirrored at the faces of [%g %g %g]..[%g %g %g] m\n",
                s.ticks, static_cast<unsigned long long>(s.seed), args.device.c_str(), walkIn.min.x,
                walkIn.min.y, walkIn.min.z, walkIn.max.x, walkIn.max.y, walkIn.max.z);
    std::printf("modes:   hot = back to back; sleep = after a %.0f us sleep; sleep+warm = the "
                "same with the servo loop's warm-up %.1f us before the deadline\n",
                s.sleepUs, s.warmUs);
    if (s.wakeLatencyUs >= 0) {
        std::printf("         +lat = the same while /dev/cpu_dma_latency holds %d us\n",
                    static_cast<int>(s.wakeLatencyUs));
    }
    std::printf("timing:  steady clock at each stage boundary (%zu readings per tick, one costs "
                "~%.0f ns); nearest-rank quantiles over every tick; runs interleaved in blocks "
                "of %zu ticks\n",
                kStageCount + 1, clockOverheadNs(), experiments::kTickBlock);
}

/// One index's table: a row per stage, the tick and the start lateness, a column per run, then
/// each run's per-tick figures.
void printTickTable(const TickTarget& target,
                    const std::vector<std::array<Quantiles, kStageCount + 1>>& q) {
    std::printf("\nindex %s\n%-12s", target.spec.toString().c_str(), "stage");
    for (const auto& run : target.runs) {
        std::printf(" | %-10s %7s %7s %8s", modeName(*run), "p50 ns", "p99 ns", "p99.9 ns");
    }
    std::printf("\n");
    for (std::size_t s = 0; s <= kStageCount; ++s) {
        std::printf("%-12s", s < kStageCount ? ServoStepProbe::kStageNames[s] : "tick");
        for (std::size_t r = 0; r < target.runs.size(); ++r) {
            std::printf(" | %-10s %7.0f %7.0f %8.0f", "", q[r][s].p50, q[r][s].p99, q[r][s].p999);
        }
        std::printf("\n");
    }
    std::printf("%-12s", "start late");
    for (const auto& run : target.runs) {
        const Quantiles late = quantilesOf(run->startLateNs);
        std::printf(" | %-10s %7.0f %7.0f %8.0f", "", late.p50, late.p99, late.p999);
    }
    std::printf("\n");
    for (const auto& run : target.runs) {
        const double n = static_cast<double>(run->ticks);
        const Quantiles gap = quantilesOf(run->gapM);
        std::printf("%-14s per tick: %.2f solves, %.2f extra leaves, %.3f pull-backs, %.1f "
                    "candidates; device to proxy p50 %.2f mm, p99 %.2f mm\n",
                    modeName(*run), static_cast<double>(run->solves) / n,
                    static_cast<double>(run->extraLeaves) / n,
                    static_cast<double>(run->pullBacks) / n,
                    static_cast<double>(run->candidates) / n, gap.p50 * 1e3, gap.p99 * 1e3);
    }
    for (const auto& run : target.runs) {
        if (run->mode == TickMode::Warm) {
            std::printf("%-12s warm-ups still running at their deadline: %llu of %llu\n",
                        modeName(*run), static_cast<unsigned long long>(run->warmOverruns),
                        static_cast<unsigned long long>(run->ticks));
        }
    }
}

/// One run's JSON entry.
nlohmann::ordered_json tickJson(const TickArgs& args, const experiments::TickBenchSettings& s,
                                const Scene& scene, const TickTarget& target, const TickRun& run,
                                const std::array<Quantiles, kStageCount + 1>& q) {
    const double n = static_cast<double>(run.ticks);
    const Aabb& walkIn = s.walkIn;
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    for (std::size_t st = 0; st < kStageCount; ++st) {
        stages[ServoStepProbe::kStageNames[st]] = toJson(q[st]);
    }
    return {{"index", target.spec.toString()},
            {"mode", modeName(run)},
            {"objects", scene.size()},
            {"ticks", run.ticks},
            {"sleep_us", run.mode == TickMode::Hot ? 0.0 : s.sleepUs},
            {"warm_us", run.mode == TickMode::Warm ? s.warmUs : 0.0},
            {"wake_latency_us", run.holdLatency ? s.wakeLatencyUs : -1},
            {"device", args.device},
            {"walk_min", {walkIn.min.x, walkIn.min.y, walkIn.min.z}},
            {"walk_max", {walkIn.max.x, walkIn.max.y, walkIn.max.z}},
            {"stages", stages},
            {"tick", toJson(q[kStageCount])},
            {"locate_steps_mean", static_cast<double>(run.locateSteps) / n},
            {"candidates_mean", static_cast<double>(run.candidates) / n},
            {"contact_fraction", static_cast<double>(run.contactTicks) / n},
            {"solves_mean", static_cast<double>(run.solves) / n},
            {"extra_leaves_mean", static_cast<double>(run.extraLeaves) / n},
            {"pull_backs_mean", static_cast<double>(run.pullBacks) / n},
            {"gap_m", gapJson(run.gapM)},
            {"warm_overruns", run.warmOverruns},
            {"start_late", toJson(quantilesOf(run.startLateNs))}};
}

// ---- `hapto bench tick --motion` -------------------------------------------------------------
// Each motion (experiments/TickMotion.h) over its own generated scene, one after another, every
// mode asked for (hot alone by default) through the same harness; a row per motion, index and
// mode with the tick's quantiles and the work counts that explain them.

/// The motions --motion names, in the suite's order ("all": every one).
std::vector<experiments::TickMotion> parseMotions(const std::vector<std::string>& names) {
    std::vector<experiments::TickMotion> out;
    for (const std::string& n : names) {
        if (n == "all") {
            out.assign(experiments::kTickMotions.begin(), experiments::kTickMotions.end());
            continue;
        }
        const auto m = experiments::parseTickMotion(n);
        if (!m) {
            throw InputError("--motion '" + n + "': unknown motion; use " +
                             experiments::tickMotionNames() + " or all");
        }
        if (std::find(out.begin(), out.end(), *m) == out.end()) {
            out.push_back(*m);
        }
    }
    std::sort(out.begin(), out.end()); // the suite's order: rest, the baseline, first
    return out;
}

/// What a run's ticks did: means, the largest counts, and the slowest tick's counts.
struct MotionWork {
    double solves = 0, candidates = 0, passes = 0, extraLeaves = 0, pullBacks = 0,
           facetsEntered = 0, contact = 0, multiContact = 0;
    std::uint32_t maxSolves = 0, maxCandidates = 0;
    /// The slowest tick's: by its own time with --repeats, else by CPU time when it was read,
    /// else on the wall.
    experiments::TickCounts worst;
    /// The ticks at or above the p99.9 of the same times: what they did, on average.
    experiments::TailWork tail;
};

MotionWork workOf(const TickRun& run) {
    MotionWork w;
    const double n = static_cast<double>(run.ticks);
    w.solves = static_cast<double>(run.solves) / n;
    w.candidates = static_cast<double>(run.candidates) / n;
    w.passes = static_cast<double>(run.passes) / n;
    w.extraLeaves = static_cast<double>(run.extraLeaves) / n;
    w.pullBacks = static_cast<double>(run.pullBacks) / n;
    w.facetsEntered = static_cast<double>(run.facetsEntered) / n;
    w.contact = static_cast<double>(run.contactTicks) / n;
    w.multiContact = static_cast<double>(run.multiContactTicks) / n;
    for (const experiments::TickCounts& c : run.counts) {
        w.maxSolves = std::max<std::uint32_t>(w.maxSolves, c.solves);
        w.maxCandidates = std::max(w.maxCandidates, c.candidates);
    }
    const std::vector<double>& ns = !run.ownNs.empty()   ? run.ownNs
                                    : !run.cpuNs.empty() ? run.cpuNs
                                                         : run.tickNs;
    const auto slowest = std::max_element(ns.begin(), ns.end());
    w.worst = run.counts[static_cast<std::size_t>(slowest - ns.begin())];
    w.tail = experiments::tailWork(run.counts, ns, 0.999);
    return w;
}

nlohmann::ordered_json countsJson(const experiments::TickCounts& c) {
    return {
        {"candidates", c.candidates},       {"solves", c.solves},        {"passes", c.passes},
        {"extra_leaves", c.extraLeaves},    {"pull_backs", c.pullBacks}, {"contacts", c.contacts},
        {"facets_entered", c.facetsEntered}};
}

/// One motion run's tick times: on the wall (wake-up to the end of the metrics) and on the
/// thread's CPU clock, and each p99.9 over rest's (0: no rest run to compare with).
struct MotionTimes {
    Quantiles wall, cpu, own; ///< own: each tick's least wall time over --repeats (TickRun::ownNs)
    double wallOverRest = 0, cpuOverRest = 0, ownOverRest = 0;
};

/// One motion run's JSON entry.
nlohmann::ordered_json motionJson(const experiments::MotionCase& c, const TickTarget& target,
                                  const TickRun& run, const MotionTimes& t, std::size_t repeats) {
    const MotionWork w = workOf(run);
    nlohmann::ordered_json stages = nlohmann::ordered_json::object();
    for (std::size_t st = 0; st < kStageCount; ++st) {
        stages[ServoStepProbe::kStageNames[st]] = toJson(quantilesOf(run.stageNs[st]));
    }
    return {{"motion", experiments::tickMotionName(c.motion)},
            {"scene", c.sceneText},
            {"path", c.pathText},
            {"objects", c.scene.size()},
            {"index", target.spec.toString()},
            {"mode", modeName(run)},
            {"ticks", run.ticks},
            {"tick", toJson(t.wall)},
            {"tick_cpu", run.cpuNs.empty() ? nlohmann::ordered_json() : toJson(t.cpu)},
            {"tick_own", run.ownNs.empty() ? nlohmann::ordered_json() : toJson(t.own)},
            {"repeats", repeats},
            {"work_differed", run.workDiffered},
            {"p999_over_rest", t.wallOverRest},
            {"cpu_p999_over_rest", t.cpuOverRest},
            {"own_p999_over_rest", t.ownOverRest},
            {"stages", stages},
            {"contact_fraction", w.contact},
            {"multi_contact_fraction", w.multiContact},
            {"solves_mean", w.solves},
            {"candidates_mean", w.candidates},
            {"passes_mean", w.passes},
            {"extra_leaves_mean", w.extraLeaves},
            {"pull_backs_mean", w.pullBacks},
            {"facets_entered_mean", w.facetsEntered},
            {"solves_max", w.maxSolves},
            {"candidates_max", w.maxCandidates},
            {"slowest_tick", countsJson(w.worst)},
            {"p999_ticks",
             {{"ticks", w.tail.ticks},
              {"solved_again_fraction", w.tail.solvedAgain},
              {"solves_mean", w.tail.solves},
              {"passes_mean", w.tail.passes},
              {"candidates_mean", w.tail.candidates},
              {"extra_leaves_mean", w.tail.extraLeaves}}},
            {"gap_m", gapJson(run.gapM)}};
}

std::string ratioText(double r) {
    char text[32];
    std::snprintf(text, sizeof text, r > 0 ? "%.2fx" : "-", r);
    return text;
}

std::string motionTimesRow(const experiments::MotionCase& c, const TickTarget& target,
                           const TickRun& run, const MotionTimes& t) {
    const auto columns = [](const std::vector<double>& samples, const Quantiles& q) {
        char text[64] = "      -       -        -        -";
        if (!samples.empty()) {
            std::snprintf(text, sizeof text, "%7.0f %7.0f %8.0f %8.0f", q.p50, q.p99, q.p999,
                          q.max);
        }
        return std::string(text);
    };
    char row[320];
    std::snprintf(row, sizeof row,
                  "%-8s %-15s %-10s | %7.0f %7.0f %8.0f %9.0f | %s | %s | %8s %8s %8s\n",
                  std::string(experiments::tickMotionName(c.motion)).c_str(),
                  target.spec.toString().c_str(), modeName(run), t.wall.p50, t.wall.p99,
                  t.wall.p999, t.wall.max, columns(run.cpuNs, t.cpu).c_str(),
                  columns(run.ownNs, t.own).c_str(), ratioText(t.wallOverRest).c_str(),
                  ratioText(t.cpuOverRest).c_str(), ratioText(t.ownOverRest).c_str());
    return row;
}

std::string motionWorkRow(const experiments::MotionCase& c, const TickTarget& target,
                          const TickRun& run) {
    const MotionWork w = workOf(run);
    char row[320];
    std::snprintf(
        row, sizeof row,
        "%-8s %-15s %-10s | %5.0f%% %5.0f%% %6.2f %6.2f %7.1f %6.2f %5.2f %6.2f | %3u "
        "%6u | %2u %5u %3u %2u %2u | %4zu %4.0f%% %4.2f %5.2f %6.1f %5.2f\n",
        std::string(experiments::tickMotionName(c.motion)).c_str(), target.spec.toString().c_str(),
        modeName(run), 100.0 * w.contact, 100.0 * w.multiContact, w.solves, w.passes, w.candidates,
        w.extraLeaves, w.pullBacks, w.facetsEntered, w.maxSolves, w.maxCandidates,
        static_cast<unsigned>(w.worst.solves), w.worst.candidates,
        static_cast<unsigned>(w.worst.passes), static_cast<unsigned>(w.worst.extraLeaves),
        static_cast<unsigned>(w.worst.pullBacks), w.tail.ticks, 100.0 * w.tail.solvedAgain,
        w.tail.solves, w.tail.passes, w.tail.candidates, w.tail.extraLeaves);
    return row;
}

void printMotionHeader(const experiments::TickBenchSettings& common,
                       const experiments::MotionOptions& size, const std::string& device) {
    std::printf("motions: %zu ticks of 1 ms each, seed %llu, device %s, about %zu objects or "
                "triangles; one after another, each over its own scene\n",
                common.ticks, static_cast<unsigned long long>(common.seed), device.c_str(),
                size.objects);
    std::printf("timing:  wall: steady clock from the wake-up to the end of the metrics stage; "
                "cpu (--cpu-time; - without): this thread's CPU clock around the step (without "
                "the time other processes held the core; a system call per tick, which slows "
                "the ticks after it); nearest-rank quantiles over every tick (ns); "
                "own (--repeats > 1; - without): each tick's least wall time over the repeats of "
                "the same ticks, the host's interruptions taken out; /rest: p99.9 over rest's\n");
    std::printf("counts:  per tick, means: solves, passes (solver passes of the last solve), "
                "candidates, extra leaves, pull-backs, facets entered; max: the largest solves "
                "and candidates of any tick; slowest (by own time, else cpu, else wall): that "
                "tick's solves, candidates, passes, extra leaves, pull-backs; tail (by the same "
                "time): the ticks at or above its p99.9, how many, the share solved more than "
                "once, and their mean solves, passes, candidates, extra leaves\n");
}

/// The motions' two tables (times, work), the motions whose work differed between repeats,
/// and what each motion is.
void printMotionTables(const std::vector<std::string>& timeRows,
                       const std::vector<std::string>& workRows,
                       const std::vector<std::string>& differed,
                       const std::vector<std::string>& described) {
    std::printf("\n%-8s %-15s %-10s | %7s %7s %8s %9s | %7s %7s %8s %8s | %7s %7s %8s %8s | "
                "%8s %8s %8s\n",
                "motion", "index", "mode", "p50", "p99", "p99.9", "max", "cpu p50", "p99", "p99.9",
                "max", "own p50", "p99", "p99.9", "max", "/rest", "cpu/rest", "own/rest");
    for (const std::string& row : timeRows) {
        std::printf("%s", row.c_str());
    }
    std::printf("\n%-8s %-15s %-10s | %6s %6s %6s %6s %7s %6s %5s %6s | %10s | %s | %4s %5s %4s "
                "%5s %6s %5s\n",
                "motion", "index", "mode", "contact", "2+", "solves", "passes", "cand.", "extra",
                "pull", "facets", "max s/cand", "slowest s cand pa ex pb", "tail", "2+", "s", "pa",
                "cand.", "ex");
    for (const std::string& row : workRows) {
        std::printf("%s", row.c_str());
    }
    if (!differed.empty()) {
        // A deterministic step does the same work on every repeat; say so when it did not.
        std::printf("\nticks whose work differed between repeats (their own times mix "
                    "different work):");
        for (const std::string& d : differed) {
            std::printf(" %s", d.c_str());
        }
        std::printf("\n");
    }
    std::printf("\n");
    for (const std::string& d : described) {
        std::printf("%s\n", d.c_str());
    }
}

void runMotions(const TickArgs& args) {
    if (!args.scene.empty() || args.walkEdgeM > 0.0 || args.pushMmGiven) {
        throw InputError(std::string(!args.scene.empty()  ? "--scene"
                                     : args.walkEdgeM > 0 ? "--walk-edge"
                                                          : "--push-mm") +
                         ": not with --motion; each motion generates its own scene and path");
    }
    const std::vector<experiments::TickMotion> motions = parseMotions(args.motions);
    TickArgs base = args;
    if (base.modes.empty()) {
        base.modes = {"hot"};
    }
    const experiments::TickBenchSettings common = tickSettings(base);
    experiments::MotionOptions size = args.motionSize;
    size.ticks = common.ticks;
    size.seed = common.seed;
    printMotionHeader(common, size, args.device);

    // Each motion's scene (10^6 objects) and index go before the next is built; only the
    // rows and the JSON are kept.
    std::vector<std::string> timeRows, workRows, described, differed;
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    std::map<std::string, MotionTimes> rest; // rest's times by index and mode
    for (const experiments::TickMotion m : motions) {
        const experiments::MotionCase c = experiments::makeMotionCase(m, size);
        experiments::TickBenchSettings s = common;
        if (args.indices.empty()) {
            s.indices = {c.index.withMaxMegabytes(args.maxIndexMb)};
        }
        s.path = c.path;
        s.walkIn = c.path.empty() ? c.walkIn : c.scene.bounds();
        s.pushMm = c.pushMm;
        s.bodyPoses = c.bodyPoses;
        s.cpuTime = args.cpuTime;
        const std::vector<TickTarget> targets = experiments::runTickBench(c.scene, s);
        for (const TickTarget& target : targets) {
            for (const auto& run : target.runs) {
                MotionTimes t{quantilesOf(run->tickNs), quantilesOf(run->cpuNs),
                              quantilesOf(run->ownNs)};
                const std::string key = target.spec.toString() + " " + modeName(*run);
                if (m == experiments::TickMotion::Rest) {
                    rest[key] = t;
                } else if (rest.count(key) != 0) {
                    const MotionTimes& r = rest[key];
                    t.wallOverRest = t.wall.p999 / r.wall.p999;
                    t.cpuOverRest = args.cpuTime ? t.cpu.p999 / r.cpu.p999 : 0.0;
                    t.ownOverRest = run->ownNs.empty() ? 0.0 : t.own.p999 / r.own.p999;
                }
                timeRows.push_back(motionTimesRow(c, target, *run, t));
                workRows.push_back(motionWorkRow(c, target, *run));
                out.push_back(motionJson(c, target, *run, t, s.repeats));
                if (run->workDiffered > 0) {
                    differed.push_back(std::string(experiments::tickMotionName(m)) + ": " +
                                       std::to_string(run->workDiffered));
                }
                keep(run->kept);
            }
        }
        described.push_back(std::string(experiments::tickMotionName(m)) + ": " + c.sceneText +
                            "; " + c.pathText);
    }
    printMotionTables(timeRows, workRows, differed, described);
    if (!args.json.empty()) {
        writeFileAtomically(args.json, out.dump(2) + "\n");
        std::printf("\nwrote %s\n", args.json.c_str());
    }
}

void runTick(const TickArgs& args) {
    if (!args.motions.empty()) {
        runMotions(args);
        return;
    }
    if (args.settings.repeats > 1) {
        throw InputError("--repeats: only with --motion (each motion's own times)");
    }
    experiments::TickBenchSettings s = tickSettings(args);
    const Scene scene = loadSceneOrDefault(args.scene);
    s.walkIn = experiments::walkBox(scene.bounds(), args.walkEdgeM);
    const std::vector<TickTarget> targets = experiments::runTickBench(scene, s);

    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    printTickHeader(args, s, scene);
    for (const TickTarget& target : targets) {
        std::vector<std::array<Quantiles, kStageCount + 1>> q(target.runs.size());
        for (std::size_t r = 0; r < target.runs.size(); ++r) {
            for (std::size_t st = 0; st < kStageCount; ++st) {
                q[r][st] = quantilesOf(target.runs[r]->stageNs[st]);
            }
            q[r][kStageCount] = quantilesOf(target.runs[r]->tickNs);
        }
        printTickTable(target, q);
        for (std::size_t r = 0; r < target.runs.size(); ++r) {
            out.push_back(tickJson(args, s, scene, target, *target.runs[r], q[r]));
            keep(target.runs[r]->kept);
        }
    }
    if (!args.json.empty()) {
        writeFileAtomically(args.json, out.dump(2) + "\n");
        std::printf("\nwrote %s\n", args.json.c_str());
    }
}

/// `hapto bench query`.
void addQueryCommand(CLI::App* bench) {
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
                    "Default: brute, grid:5 and " +
                        std::string(kDefaultIndexSpec));
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
    setExamples(cmd, {"hapto bench query --steps 1e5",
                      "hapto bench query --scene million.hsb --index octree:2:0.005@climb "
                      "--index grid:20 --json"});
    cmd->callback([args] { runQuery(*args); });
}

/// `hapto bench tick --motion` and the options that go with it.
void addMotionOptions(CLI::App* tick, TickArgs& targs) {
    tick->add_option(
        "--motion", targs.motions,
        "Instead of one scene's walk, adversarial hand motions, each over its own "
        "generated scene, repeatable: rest (the baseline: resting 0.5 mm inside a "
        "cube's face), walk (the walk held at 2 mm), trapped (the walk deep in "
        "dense cubes, never held back), sweep (straight lines at 1 m/s through the "
        "cubes), graze (along cube edges and across vertices), sphere (sliding over "
        "a fine-faceted sphere), slabs (through 20 thin slabs at 1 m/s), body (resting "
        "on a dynamic box that swings under the hand), or all. "
        "Reports per motion the tick's p50, p99, p99.9 and max, p99.9 over rest's, "
        "and the work that explains them: solves, solver passes, candidates, extra "
        "leaves, pull-backs, facets entered, the slowest tick's counts. Hot mode "
        "only unless --mode says otherwise; not with --scene, --walk-edge or "
        "--push-mm");
    tick->add_flag("--cpu-time", targs.cpuTime,
                   "With --motion: also read the thread's CPU clock around each tick and report "
                   "its quantiles, which leave out the time other processes held the core. A "
                   "system call per tick: on a VM it makes the ticks after it slower (here the "
                   "resting tick's p50 0.8 -> 2.5 us), so compare such runs only with each "
                   "other");
    tick->add_option("--repeats", targs.settings.repeats,
                     "With --motion: run each motion this many times over the same ticks (the "
                     "same work) and also report each tick's least wall time over the repeats "
                     "(own): its cost with the host's interruptions taken out, since one that "
                     "lands on a tick in one repeat rarely lands on it in every one")
        ->capture_default_str()
        ->transform(wholeNumber(1, 100));
    tick->add_option("--objects", targs.motionSize.objects,
                     "With --motion: cubes in the cube scenes (the lattice rounds to K^3) and "
                     "triangles in the sphere, e.g. 1e6")
        ->capture_default_str()
        ->transform(wholeNumber(8, 1e7));
}

/// `hapto bench tick`.
void addTickCommand(CLI::App* bench) {
    auto targs = std::make_shared<TickArgs>();
    auto* tick = bench->add_subcommand(
        "tick",
        "The servo tick's cost stage by stage (device read, snapshot acquire, locate, "
        "candidates, render, effects, safety, write, metrics) over one scene, along the same "
        "seeded hand walk as bench query, each tick started three ways, side by side in one "
        "run: back to back (hot), after a --sleep-us sleep (a real 1 kHz servo), and after the "
        "same sleep with the servo loop's warm-up --warm-us before the deadline (hapto run "
        "--warm-us); with --wake-latency-us, both sleep modes again while a CPU wake-latency "
        "request is held. Each tick is the servo's own step (ServoStep::run: fault rules, miss "
        "rules, metrics and contacts included), with a steady clock reading at each stage "
        "boundary; locate to safety are timed inside its HapticTick::tick (render includes its "
        "walk over the proxy's path and any re-solve). Reports each "
        "stage's and the whole tick's median, p99 and p99.9 (ns).");
    tick->add_option("--scene", targs->scene, "Scene file (default: the embedded default scene)");
    tick->add_option("--index", targs->indices,
                     "Index to tick over, repeatable: brute, grid:N, octree:M:MIN (MIN in m), "
                     "each optionally with :aabb. Default: " +
                         std::string(kDefaultIndexSpec));
    addMaxIndexMbOption(tick, targs->maxIndexMb);
    tick->add_option("--device", targs->device,
                     "walk: a device that plays the walk (read and write cost nothing but a "
                     "call); sim: a simulated hand (its read and write are timed; the walk still "
                     "drives the tick)")
        ->capture_default_str()
        ->check(CLI::IsMember({"walk", "sim"}));
    tick->add_option("--ticks", targs->settings.ticks, "Ticks per mode and index, e.g. 5000")
        ->capture_default_str()
        ->transform(wholeNumber(1, 1e7));
    tick->add_option("--sleep-us", targs->settings.sleepUs,
                     "Sleep before each tick of the sleep modes (us; 1000 = a 1 kHz servo)")
        ->capture_default_str()
        ->check(finiteRange(1, 1e6));
    tick->add_option("--warm-us", targs->settings.warmUs,
                     "Warm-up before the deadline in the sleep+warm mode (us), shorter than "
                     "--sleep-us")
        ->capture_default_str()
        ->check(finiteRange(0.001, static_cast<double>(kMaxWarmUpNs) / 1000.0));
    tick->add_option("--seed", targs->settings.seed, "Walk seed; same seed, same walk")
        ->capture_default_str()
        ->check(finiteRange(0, kMaxSeed));
    tick->add_option("--walk-edge", targs->walkEdgeM,
                     "Keep the walk in the cube of this edge (m) centred on the scene's centre "
                     "(within the bounds), e.g. to walk the same neighbourhood of a small and a "
                     "large scene of equal density; default: the whole bounds")
        ->check(finiteRange(1e-6, 1e4));
    tick->add_option("--push-mm", targs->settings.pushMm,
                     "After each tick the walking hand is held back to at most this far from "
                     "the proxy (mm; 2 mm is 1.6 N at 800 N/m), as a hand that feels the force; "
                     "0: it walks through everything, leaving the proxy behind (trapped in a "
                     "dense scene, many cm away)")
        ->capture_default_str()
        ->check(finiteRange(0.0, 1e3));
    addWakeLatencyOption(tick, targs->settings.wakeLatencyUs,
                         "the two sleep modes run again, as sleep+lat and sleep+warm+lat, "
                         "interleaved with the others (hapto run --wake-latency-us)");
    tick->add_option("--json", targs->json,
                     "Also write a JSON array of {index, mode, objects, ticks, sleep_us, warm_us, "
                     "wake_latency_us (-1: none), "
                     "device, walk_min, walk_max, stages: {read, ...: {ns_p50, ns_p99, ns_p999, "
                     "ns_mean}}, tick: "
                     "{...}, locate_steps_mean, candidates_mean, contact_fraction} to this file");
    addMotionOptions(tick, *targs);
    tick->add_option("--mode", targs->modes,
                     "Modes to run, repeatable: hot, sleep, sleep+warm (default: all three; "
                     "with --motion: hot)")
        ->check(CLI::IsMember({"hot", "sleep", "sleep+warm"}));
    setExamples(tick, {"hapto bench tick --ticks 5000",
                       "hapto bench tick --motion all --ticks 5000 --json motions.json",
                       "hapto bench tick --scene mesh.json --device sim --json tick.json"});
    tick->callback([targs, tick] {
        targs->pushMmGiven = tick->count("--push-mm") > 0;
        runTick(*targs);
    });
}

} // namespace

void addBenchCommands(CLI::App& app) {
    CLI::App* bench =
        app.add_subcommand("bench", "Measure the speed of the spatial indices and the servo tick");
    bench->require_subcommand(1);
    setExamples(bench, {"hapto bench query --steps 1e5", "hapto bench tick --ticks 5000"});
    addQueryCommand(bench);
    addTickCommand(bench);
}

} // namespace hapto::cli
