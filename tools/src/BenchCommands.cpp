// `hapto bench query`: per-query cost of indices over one scene, along one hand-speed walk.
// `hapto bench tick`: the servo tick's stages over one scene along the same walk, back to back,
// after a sleep, and after a sleep with the servo loop's warm-up.

#include "Commands.h"
#include "Options.h"

#include "hapto/core/Mailbox.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/experiments/HandWalk.h"
#include "hapto/index/Cursor.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/CandidateSet.h"
#include "hapto/runtime/DeviceMetrics.h"
#include "hapto/runtime/Effects.h"
#include "hapto/runtime/ForceSafety.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/HapticTick.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/ServoLoop.h"
#include "hapto/runtime/World.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
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

// ---- `hapto bench tick` ----------------------------------------------------------------------

/// The stages of one servo tick, in the order Runtime::servoTick and HapticTick::tick run them.
constexpr std::array<const char*, 9> kStages{
    "read", "snapshot", "locate", "candidates", "render", "effects", "safety", "write", "metrics"};
constexpr std::size_t kStageCount = kStages.size();

/// How a tick is started: back to back, after a sleep, or after a sleep with the servo loop's
/// warm-up before the deadline.
enum class TickMode : std::uint8_t { Hot, Sleep, Warm };
constexpr std::array<const char*, 3> kModeNames{"hot", "sleep", "sleep+warm"};
/// The same sleep modes with a CPU wake-latency request held (--wake-latency-us).
constexpr std::array<const char*, 3> kHeldModeNames{"", "sleep+lat", "sleep+warm+lat"};

/// A device that plays the hand walk: read() hands over the walk's next point (device frame =
/// world frame), write() keeps the force. Kind "scripted": made by this program, never by a
/// device file.
class WalkDevice final : public Device {
public:
    WalkDevice(const Aabb& bounds, std::uint64_t seed) : mWalk(bounds, seed) {}
    std::string_view name() const override { return "walk"; }
    DeviceKind kind() const override { return DeviceKind::Scripted; }
    DeviceCapabilities capabilities() const override { return {}; }
    DeviceStatus open() override { return DeviceStatus::Ok; }
    void close() override {}
    DeviceStatus read(DeviceState& state) noexcept override {
        state.position = mWalk.next();
        state.hasVelocity = false;
        return DeviceStatus::Ok;
    }
    DeviceStatus write(const Vec3& forceN) noexcept override {
        mForceN = forceN;
        return DeviceStatus::Ok;
    }
    std::string errorMessage() const override { return {}; }
    experiments::HandWalk& walk() { return mWalk; }

private:
    experiments::HandWalk mWalk;
    Vec3 mForceN{0.0};
};

/// What one tick reads and writes, laid out like the servo's hot state: the servo's own
/// HapticTick (timing its stages), the device sample, and the walk's last point and step (the
/// velocity, and the warm-up's predicted point). One per (index, mode).
struct alignas(64) TickPieces {
    HapticTick haptic;
    HapticTick::StageStamps stamps{};
    DeviceState sample;
    Vec3 lastPoint{0.0};
    Vec3 lastStep{0.0};
    bool fresh = true;

    TickPieces() { haptic.timeStages(&stamps); }
    TickPieces(const TickPieces&) = delete;
    TickPieces& operator=(const TickPieces&) = delete;
};

/// One (index, mode) being driven: its device, its tick state, its per-stage samples (ns).
struct TickRun {
    TickMode mode = TickMode::Hot;
    bool holdLatency = false; // hold --wake-latency-us while it ticks
    std::unique_ptr<Device> device;
    std::unique_ptr<experiments::HandWalk> walk; // the point, when the device is a sim hand
    experiments::HandWalk* hand = nullptr;       // the walk either way (held back near the proxy)
    std::unique_ptr<TickPieces> pieces;
    std::unique_ptr<DeviceMetrics> metrics;
    std::unique_ptr<Mailbox<ContactReport>> contacts;
    SnapshotReader* reader = nullptr;
    std::array<std::vector<double>, kStageCount> stageNs;
    std::vector<double> tickNs;
    std::uint64_t ticks = 0, locateSteps = 0, candidates = 0, contactTicks = 0;
    std::uint64_t solves = 0, extraLeaves = 0, pullBacks = 0; // HapticTick's, summed
    std::vector<double> gapM; ///< Per tick: the device point's distance from the proxy (m).
    std::uint64_t kept = 0;   // what the warm-up read, kept
    /// Warm-ups still running at their deadline: those ticks started late by the overrun,
    /// which the tick's time (from the wake-up) does not show.
    std::uint64_t warmOverruns = 0;
    /// Per tick after a sleep: how long after its deadline it started (ns; 0 if on time): the
    /// wake-up's lateness, plus a warm-up's overrun. A servo reads its device this late.
    std::vector<double> startLateNs;
};

/// One `--index`: its world (scene copy, index, snapshots) and its three runs.
struct TickTarget {
    IndexSpec spec;
    std::unique_ptr<World> world;
    std::vector<std::unique_ptr<TickRun>> runs;
};

struct TickArgs {
    std::string scene;
    std::vector<std::string> indices;
    std::string device = "walk";
    std::size_t ticks = 5000;
    double sleepUs = 1000;
    double warmUs = static_cast<double>(kDefaultWarmUpNs) / 1000.0;
    std::uint64_t seed = 1;
    double walkEdgeM = 0.0; ///< 0: the walk roams the scene's bounds
    /// After each tick the hand is held back to at most this far from the proxy (mm); 0: it
    /// ignores the force and walks through everything, leaving the proxy behind.
    double pushMm = 2.0;
    std::int32_t wakeLatencyUs = -1; ///< >= 0: also the sleep modes with this request held
    std::string json;
    std::uint64_t maxIndexMb = IndexSpec::kDefaultMaxMegabytes;
};

/// The box the walk roams: the scene's bounds, or with `edgeM` > 0 their part within the cube
/// of that edge (m) centred on their centre.
Aabb walkBox(const Aabb& bounds, double edgeM) {
    if (edgeM <= 0.0) {
        return bounds;
    }
    const Vec3 half(0.5 * edgeM);
    return {glm::max(bounds.min, bounds.center() - half),
            glm::min(bounds.max, bounds.center() + half)};
}

/// One tick, stage by stage, as Runtime::servoTick runs it: read, snapshot, HapticTick::tick
/// (its own five stages: locate, candidates, render with the walk and re-solves, effects,
/// safety), write, metrics. The stage boundaries are steady clock readings (`wake` is the
/// first).
void timedTick(TickRun& run, World& world, std::size_t at, std::uint64_t wakeNs, double dtS,
               double pushM) {
    TickPieces& t = *run.pieces;
    std::array<std::uint64_t, kStageCount + 1> stamp{};
    stamp[0] = wakeNs;
    // read
    (void)run.device->read(t.sample);
    if (run.walk) {
        t.sample.position = run.walk->next(); // the sim hand was read; the walk drives the tick
        t.sample.hasVelocity = false;
    }
    stamp[1] = rt::nowNs();
    // snapshot: claim it, the device point in the world (identity frame), its velocity
    const WorldSnapshot& snap = world.acquire(*run.reader);
    const Vec3 p = t.sample.position;
    if (t.fresh) {
        t.lastPoint = p;
        t.fresh = false;
    }
    const Vec3 v = t.sample.hasVelocity ? t.sample.velocity : (p - t.lastPoint) / dtS;
    t.lastStep = p - t.lastPoint;
    t.lastPoint = p;
    stamp[2] = rt::nowNs();
    // locate, candidates, render, effects, safety
    const TickOutput tick = t.haptic.tick(snap, p, v, dtS, Vec3(0.0), t.sample);
    std::copy(t.stamps.begin(), t.stamps.end(), stamp.begin() + 3);
    const RenderOutput& out = tick.render;
    const Vec3 force = tick.forceN;
    // write
    (void)run.device->write(force);
    stamp[8] = rt::nowNs();
    // metrics: what servoTick records and publishes
    DeviceMetrics& m = *run.metrics;
    m.tickNs.record(stamp[8] - wakeNs);
    m.latenessNs.record(0);
    m.ioNs.record((stamp[1] - wakeNs) + (stamp[8] - stamp[7]));
    DeviceMetrics::bump(m.locateStepsSum, tick.locateSteps);
    DeviceMetrics::bump(m.candidatesSum, out.objectsTested);
    if (out.contactCount > 0) {
        DeviceMetrics::bump(m.contactTicks);
    }
    for (int i = 0; i < 3; ++i) {
        m.forceN[i].store(force[i], std::memory_order_relaxed);
        m.positionM[i].store(p[i], std::memory_order_relaxed);
    }
    m.leafAtVersion.store((snap.version & 0xFFFFFFFFu) << 32 | tick.deviceLeaf,
                          std::memory_order_relaxed);
    ContactReport report;
    report.tick = run.ticks;
    report.devicePoint = p;
    report.proxy = out.proxy;
    report.force = force;
    report.contactCount = out.contactCount;
    for (std::uint32_t c = 0; c < out.contactCount && c < report.objects.size(); ++c) {
        report.objects[c] = out.contacts[c].id;
        report.normals[c] = out.contacts[c].normal;
    }
    run.contacts->publish(report);
    DeviceMetrics::bump(m.ticks);
    m.heartbeatNs.store(stamp[8], std::memory_order_relaxed);
    stamp[9] = rt::nowNs();

    for (std::size_t s = 0; s < kStageCount; ++s) {
        run.stageNs[s][at] = static_cast<double>(stamp[s + 1] - stamp[s]);
    }
    run.tickNs[at] = static_cast<double>(stamp[kStageCount] - stamp[0]);
    ++run.ticks;
    run.locateSteps += tick.locateSteps;
    run.candidates += out.objectsTested;
    run.contactTicks += out.contactCount > 0 ? 1 : 0;
    run.solves += tick.solves;
    run.extraLeaves += tick.extraLeaves;
    run.pullBacks += tick.pullBacks;
    const double gap = glm::length(p - out.proxy);
    run.gapM[at] = gap;
    // A hand that feels the force: it is never more than --push-mm from the proxy (beyond the
    // proxy only where a surface holds it back).
    if (pushM > 0.0 && gap > pushM) {
        run.hand->holdBack(out.proxy + (pushM / gap) * (p - out.proxy));
    }
}

/// "hot", "sleep", "sleep+warm", "sleep+lat", "sleep+warm+lat".
const char* modeName(const TickRun& run) {
    const auto m = static_cast<std::size_t>(run.mode);
    return run.holdLatency ? kHeldModeNames[m] : kModeNames[m];
}

/// Runs `count` ticks of `run` from sample `at` on, started as its mode says.
void driveTicks(TickRun& run, World& world, std::size_t at, std::size_t count,
                const TickArgs& args) {
    const auto sleepNs = static_cast<std::uint64_t>(args.sleepUs * 1000.0);
    const auto warmNs = static_cast<std::uint64_t>(args.warmUs * 1000.0);
    const double dtS = 1e-3;
    // Held for this block only (the request takes effect at the CPUs' next idle entry), so
    // the runs with and without it take turns like every other pair of runs.
    rt::WakeLatencyHold hold;
    if (run.holdLatency) {
        hold = rt::WakeLatencyHold(args.wakeLatencyUs);
        if (!hold.held()) {
            throw std::runtime_error("bench tick: --wake-latency-us: " + hold.note());
        }
    }
    for (std::size_t k = at; k < at + count; ++k) {
        std::uint64_t wake = rt::nowNs();
        if (run.mode != TickMode::Hot) {
            const std::uint64_t deadline = wake + sleepNs;
            if (run.mode == TickMode::Warm) {
                // As the servo loop does with a warm-up: wake early, touch, spin to the deadline.
                rt::sleepUntilNs(deadline - warmNs, 0);
                const WorldSnapshot& snap = world.acquire(*run.reader);
                run.kept += warmUpTick(snap, run.pieces->haptic.renderer(),
                                       std::as_bytes(std::span(run.pieces.get(), 1)),
                                       run.pieces->lastPoint, run.pieces->lastStep, dtS);
                run.warmOverruns += rt::nowNs() > deadline ? 1 : 0;
                spinUntilNs(deadline);
            } else {
                rt::sleepUntilNs(deadline, 0);
            }
            wake = rt::nowNs();
            if (run.startLateNs.size() < run.startLateNs.capacity()) {
                run.startLateNs.push_back(
                    static_cast<double>(wake > deadline ? wake - deadline : 0));
            }
        }
        timedTick(run, world, k, wake, dtS, args.pushMm * 1e-3);
    }
}

/// Nearest-rank quantiles of a copy of `ns`, as JSON and as a row.
struct Quantiles {
    double p50 = 0, p99 = 0, p999 = 0, mean = 0;
};
Quantiles quantilesOf(std::vector<double> ns) {
    Quantiles q;
    if (ns.empty()) {
        return q;
    }
    double sum = 0;
    for (const double x : ns) {
        sum += x;
    }
    q.mean = sum / static_cast<double>(ns.size());
    std::sort(ns.begin(), ns.end());
    q.p50 = quantile(ns, 0.5);
    q.p99 = quantile(ns, 0.99);
    q.p999 = quantile(ns, 0.999);
    return q;
}

nlohmann::ordered_json toJson(const Quantiles& q) {
    return {{"ns_p50", q.p50}, {"ns_p99", q.p99}, {"ns_p999", q.p999}, {"ns_mean", q.mean}};
}

/// The device point's distance from the proxy over a run's ticks (m).
nlohmann::ordered_json gapJson(const std::vector<double>& gapM) {
    const Quantiles q = quantilesOf(gapM);
    return {{"p50", q.p50}, {"p99", q.p99}, {"p999", q.p999}, {"mean", q.mean}};
}

void runTick(const TickArgs& args) {
    std::vector<std::string> texts = args.indices;
    if (texts.empty()) {
        texts = {"octree:2:0.005"};
    }
    std::vector<IndexSpec> specs;
    for (const std::string& t : texts) {
        try {
            specs.push_back(IndexSpec::parse(t).withMaxMegabytes(args.maxIndexMb));
        } catch (const InputError& e) {
            throw InputError(std::string("--index: ") + e.what());
        }
    }
    if (args.warmUs >= args.sleepUs) {
        char message[160];
        std::snprintf(message, sizeof message,
                      "--warm-us %g: not shorter than --sleep-us %g; the warm-up happens inside "
                      "the sleep",
                      args.warmUs, args.sleepUs);
        throw InputError(message);
    }
    if (!args.json.empty()) {
        checkOutputFile(args.json, "--json");
        refuseSameFile(args.json, "--json", args.scene, "--scene");
    }
    const Scene scene = loadSceneOrDefault(args.scene);

    const Aabb walkIn = walkBox(scene.bounds(), args.walkEdgeM);
    std::vector<TickTarget> targets;
    for (const IndexSpec& spec : specs) {
        TickTarget target;
        target.spec = spec;
        target.world = std::make_unique<World>(scene, spec);
        std::vector<std::pair<TickMode, bool>> modes{
            {TickMode::Hot, false}, {TickMode::Sleep, false}, {TickMode::Warm, false}};
        if (args.wakeLatencyUs >= 0) {
            modes.insert(modes.end(), {{TickMode::Sleep, true}, {TickMode::Warm, true}});
        }
        for (const auto& [mode, held] : modes) {
            auto run = std::make_unique<TickRun>();
            run->mode = mode;
            run->holdLatency = held;
            if (args.device == "sim") {
                DeviceConfig c = defaultDeviceConfigs().front();
                c.name = "bench";
                run->device = makeDevice(c, scene);
                run->walk = std::make_unique<experiments::HandWalk>(walkIn, args.seed);
                run->hand = run->walk.get();
            } else {
                auto device = std::make_unique<WalkDevice>(walkIn, args.seed);
                run->hand = &device->walk();
                run->device = std::move(device);
            }
            if (run->device->open() != DeviceStatus::Ok) {
                throw std::runtime_error("bench tick: the " + args.device +
                                         " device did not open: " + run->device->errorMessage());
            }
            run->pieces = std::make_unique<TickPieces>();
            run->metrics = std::make_unique<DeviceMetrics>();
            run->contacts = std::make_unique<Mailbox<ContactReport>>();
            run->reader = target.world->registerReader();
            for (std::vector<double>& s : run->stageNs) {
                s.assign(args.ticks, 0.0);
            }
            run->tickNs.assign(args.ticks, 0.0);
            run->gapM.assign(args.ticks, 0.0);
            run->startLateNs.reserve(args.ticks); // filled in the sleep modes only
            target.runs.push_back(std::move(run));
        }
        targets.push_back(std::move(target));
    }

    // Every run walks the same seeded path; the runs take turns in blocks, each block starting
    // with a different one, so a slow spell of the machine falls on all of them alike.
    constexpr std::size_t kTickBlock = 256;
    rt::tightenTimerSlack();
    for (std::size_t done = 0, round = 0; done < args.ticks; ++round) {
        const std::size_t length = std::min(kTickBlock, args.ticks - done);
        std::vector<std::pair<TickTarget*, TickRun*>> order;
        for (TickTarget& t : targets) {
            for (auto& r : t.runs) {
                order.emplace_back(&t, r.get());
            }
        }
        for (std::size_t r = 0; r < order.size(); ++r) {
            const auto [target, run] = order[(r + round) % order.size()];
            driveTicks(*run, *target->world, done, length, args);
        }
        done += length;
    }

    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    std::printf("scene:   %s, %u objects\n",
                args.scene.empty() ? "(embedded default scene)" : args.scene.c_str(), scene.size());
    std::printf("walk:    %zu ticks per mode of 1 ms, seed %llu, device %s, <= 0.5 m/s, "
                "mirrored at the faces of [%g %g %g]..[%g %g %g] m\n",
                args.ticks, static_cast<unsigned long long>(args.seed), args.device.c_str(),
                walkIn.min.x, walkIn.min.y, walkIn.min.z, walkIn.max.x, walkIn.max.y, walkIn.max.z);
    std::printf("modes:   hot = back to back; sleep = after a %.0f us sleep; sleep+warm = the "
                "same with the servo loop's warm-up %.1f us before the deadline\n",
                args.sleepUs, args.warmUs);
    if (args.wakeLatencyUs >= 0) {
        std::printf("         +lat = the same while /dev/cpu_dma_latency holds %d us\n",
                    static_cast<int>(args.wakeLatencyUs));
    }
    std::printf("timing:  steady clock at each stage boundary (%zu readings per tick, one costs "
                "~%.0f ns); nearest-rank quantiles over every tick; runs interleaved in blocks "
                "of %zu ticks\n",
                kStageCount + 1, clockOverheadNs(), kTickBlock);
    for (const TickTarget& target : targets) {
        std::printf("\nindex %s\n%-12s", target.spec.toString().c_str(), "stage");
        for (const auto& run : target.runs) {
            std::printf(" | %-10s %7s %7s %8s", modeName(*run), "p50 ns", "p99 ns", "p99.9 ns");
        }
        std::printf("\n");
        std::vector<std::array<Quantiles, kStageCount + 1>> q(target.runs.size());
        for (std::size_t r = 0; r < target.runs.size(); ++r) {
            for (std::size_t s = 0; s < kStageCount; ++s) {
                q[r][s] = quantilesOf(target.runs[r]->stageNs[s]);
            }
            q[r][kStageCount] = quantilesOf(target.runs[r]->tickNs);
        }
        for (std::size_t s = 0; s <= kStageCount; ++s) {
            std::printf("%-12s", s < kStageCount ? kStages[s] : "tick");
            for (std::size_t r = 0; r < target.runs.size(); ++r) {
                std::printf(" | %-10s %7.0f %7.0f %8.0f", "", q[r][s].p50, q[r][s].p99,
                            q[r][s].p999);
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
        for (std::size_t r = 0; r < target.runs.size(); ++r) {
            const TickRun& run = *target.runs[r];
            const double n = static_cast<double>(run.ticks);
            nlohmann::ordered_json stages = nlohmann::ordered_json::object();
            for (std::size_t s = 0; s < kStageCount; ++s) {
                stages[kStages[s]] = toJson(q[r][s]);
            }
            out.push_back({{"index", target.spec.toString()},
                           {"mode", modeName(run)},
                           {"objects", scene.size()},
                           {"ticks", run.ticks},
                           {"sleep_us", run.mode == TickMode::Hot ? 0.0 : args.sleepUs},
                           {"warm_us", run.mode == TickMode::Warm ? args.warmUs : 0.0},
                           {"wake_latency_us", run.holdLatency ? args.wakeLatencyUs : -1},
                           {"device", args.device},
                           {"walk_min", {walkIn.min.x, walkIn.min.y, walkIn.min.z}},
                           {"walk_max", {walkIn.max.x, walkIn.max.y, walkIn.max.z}},
                           {"stages", stages},
                           {"tick", toJson(q[r][kStageCount])},
                           {"locate_steps_mean", static_cast<double>(run.locateSteps) / n},
                           {"candidates_mean", static_cast<double>(run.candidates) / n},
                           {"contact_fraction", static_cast<double>(run.contactTicks) / n},
                           {"solves_mean", static_cast<double>(run.solves) / n},
                           {"extra_leaves_mean", static_cast<double>(run.extraLeaves) / n},
                           {"pull_backs_mean", static_cast<double>(run.pullBacks) / n},
                           {"gap_m", gapJson(run.gapM)},
                           {"warm_overruns", run.warmOverruns},
                           {"start_late", toJson(quantilesOf(run.startLateNs))}});
            keep(run.kept);
        }
    }
    if (!args.json.empty()) {
        writeFileAtomically(args.json, out.dump(2) + "\n");
        std::printf("\nwrote %s\n", args.json.c_str());
    }
}

} // namespace

void addBenchCommands(CLI::App& app) {
    CLI::App* bench =
        app.add_subcommand("bench", "Measure the speed of the spatial indices and the servo tick");
    bench->require_subcommand(1);
    setExamples(bench, {"hapto bench query --steps 1e5", "hapto bench tick --ticks 5000"});

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
    setExamples(cmd, {"hapto bench query --steps 1e5",
                      "hapto bench query --scene million.hsb --index octree:2:0.005@climb "
                      "--index grid:20 --json"});
    cmd->callback([args] { runQuery(*args); });

    auto targs = std::make_shared<TickArgs>();
    auto* tick = bench->add_subcommand(
        "tick",
        "The servo tick's cost stage by stage (device read, snapshot acquire, locate, "
        "candidates, render, effects, safety, write, metrics) over one scene, along the same "
        "seeded hand walk as bench query, each tick started three ways, side by side in one "
        "run: back to back (hot), after a --sleep-us sleep (a real 1 kHz servo), and after the "
        "same sleep with the servo loop's warm-up --warm-us before the deadline (hapto run "
        "--warm-us); with --wake-latency-us, both sleep modes again while a CPU wake-latency "
        "request is held. The stages are Runtime::servoTick's, in their order, with a steady clock "
        "reading at each "
        "boundary; locate to safety are timed inside the servo's own HapticTick::tick (render "
        "includes its walk over the proxy's path and any re-solve). Reports each "
        "stage's and the whole tick's median, p99 and p99.9 (ns).");
    tick->add_option("--scene", targs->scene, "Scene file (default: the embedded default scene)");
    tick->add_option("--index", targs->indices,
                     "Index to tick over, repeatable: brute, grid:N, octree:M:MIN (MIN in m), "
                     "each optionally with :aabb. Default: octree:2:0.005");
    addMaxIndexMbOption(tick, targs->maxIndexMb);
    tick->add_option("--device", targs->device,
                     "walk: a device that plays the walk (read and write cost nothing but a "
                     "call); sim: a simulated hand (its read and write are timed; the walk still "
                     "drives the tick)")
        ->capture_default_str()
        ->check(CLI::IsMember({"walk", "sim"}));
    tick->add_option("--ticks", targs->ticks, "Ticks per mode and index, e.g. 5000")
        ->capture_default_str()
        ->transform(wholeNumber(1, 1e7));
    tick->add_option("--sleep-us", targs->sleepUs,
                     "Sleep before each tick of the sleep modes (us; 1000 = a 1 kHz servo)")
        ->capture_default_str()
        ->check(finiteRange(1, 1e6));
    tick->add_option("--warm-us", targs->warmUs,
                     "Warm-up before the deadline in the sleep+warm mode (us), shorter than "
                     "--sleep-us")
        ->capture_default_str()
        ->check(finiteRange(0.001, static_cast<double>(kMaxWarmUpNs) / 1000.0));
    tick->add_option("--seed", targs->seed, "Walk seed; same seed, same walk")
        ->capture_default_str()
        ->check(finiteRange(0, kMaxSeed));
    tick->add_option("--walk-edge", targs->walkEdgeM,
                     "Keep the walk in the cube of this edge (m) centred on the scene's centre "
                     "(within the bounds), e.g. to walk the same neighbourhood of a small and a "
                     "large scene of equal density; default: the whole bounds")
        ->check(finiteRange(1e-6, 1e4));
    tick->add_option("--push-mm", targs->pushMm,
                     "After each tick the walking hand is held back to at most this far from "
                     "the proxy (mm; 2 mm is 1.6 N at 800 N/m), as a hand that feels the force; "
                     "0: it walks through everything, leaving the proxy behind (trapped in a "
                     "dense scene, many cm away)")
        ->capture_default_str()
        ->check(finiteRange(0.0, 1e3));
    addWakeLatencyOption(tick, targs->wakeLatencyUs,
                         "the two sleep modes run again, as sleep+lat and sleep+warm+lat, "
                         "interleaved with the others (hapto run --wake-latency-us)");
    tick->add_option("--json", targs->json,
                     "Also write a JSON array of {index, mode, objects, ticks, sleep_us, warm_us, "
                     "wake_latency_us (-1: none), "
                     "device, walk_min, walk_max, stages: {read, ...: {ns_p50, ns_p99, ns_p999, "
                     "ns_mean}}, tick: "
                     "{...}, locate_steps_mean, candidates_mean, contact_fraction} to this file");
    setExamples(tick, {"hapto bench tick --ticks 5000",
                       "hapto bench tick --scene mesh.json --device sim --json tick.json"});
    tick->callback([targs] { runTick(*targs); });
}

} // namespace hapto::cli
