// `hapto experiment scaling`: haptic load against the number of devices sharing one world,
// and cursor steps per locate against N for the three cursor strategies.

#include "hapto/experiments/Experiments.h"

#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/experiments/HandWalk.h"
#include "hapto/experiments/Plot.h"
#include "hapto/experiments/Progress.h"
#include "hapto/experiments/Sweep.h"
#include "hapto/experiments/Table.h"

#include "hapto/core/Random.h"
#include "hapto/index/Cursor.h"
#include "hapto/index/Overlap.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/SceneFile.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

namespace hapto::experiments {
namespace {

/// Hands start at least this far from every object's box (m) and from each other (x2).
constexpr double kClearM = 0.005;

/// True when no item's box (an object's, or a mesh triangle's), grown by `marginM`, holds `p`:
/// checked against the candidates of the leaves holding p and p moved by the margin along
/// each axis.
bool isClear(const Scene& scene, const SpatialIndex& index, const Vec3& p, double marginM) {
    if (!index.inBounds(p)) {
        return false;
    }
    for (int probe = 0; probe < 7; ++probe) {
        Vec3 q = p;
        if (probe > 0) {
            q[(probe - 1) / 2] += (probe % 2 ? marginM : -marginM);
        }
        for (const std::uint32_t item : index.locate(q).candidates) {
            Aabb box = itemAabb(scene, item);
            box.min -= Vec3(marginM);
            box.max += Vec3(marginM);
            if (box.contains(p)) {
                return false;
            }
        }
    }
    return true;
}

/// `count` clear start points: the centre of the bounds if clear, then seeded random points,
/// each clear of objects and 1 cm from the others. Throws InputError when the scene has no room.
std::vector<Vec3> clearStarts(const Scene& scene, const SpatialIndex& index, int count) {
    std::vector<Vec3> starts;
    const Aabb& b = scene.bounds();
    const Vec3 inset = glm::min(Vec3(0.01), 0.25 * b.size());
    Random rng(7);
    const auto farFromOthers = [&](const Vec3& p) {
        return std::all_of(starts.begin(), starts.end(),
                           [&](const Vec3& s) { return glm::length(s - p) >= 2 * kClearM; });
    };
    if (isClear(scene, index, b.center(), kClearM)) {
        starts.push_back(b.center());
    }
    for (int attempt = 0; static_cast<int>(starts.size()) < count; ++attempt) {
        if (attempt == 200000) {
            throw InputError("experiment scaling: found only " + std::to_string(starts.size()) +
                             " clear start points in the scene for " + std::to_string(count) +
                             " devices; use a scene with more free space or fewer devices");
        }
        const Vec3 p(rng.uniform(b.min.x + inset.x, b.max.x - inset.x),
                     rng.uniform(b.min.y + inset.y, b.max.y - inset.y),
                     rng.uniform(b.min.z + inset.z, b.max.z - inset.z));
        if (isClear(scene, index, p, kClearM) && farFromOthers(p)) {
            starts.push_back(p);
        }
    }
    return starts;
}

std::vector<int> deviceCounts(int maxDevices) {
    std::vector<int> counts;
    for (int d = 1; d <= maxDevices; d *= 2) {
        counts.push_back(d);
    }
    if (counts.back() != maxDevices) {
        counts.push_back(maxDevices);
    }
    return counts;
}

/// One (rate, device count) over its repeats.
struct ScalingRow {
    double rateHz = 0;
    int devices = 0;
    int repeats = 0;
    double loadSumPct = 0;        ///< Sum of the devices' mean loads (% of one core), median.
    double loadPerCorePct = 0;    ///< loadSum / cores (%), median.
    double deviceMeanLoadPct = 0; ///< Mean over devices of their mean load (%), median.
    double worstP50Pct = 0, worstP99Pct = 0, worstP999Pct = 0, worstMaxPct = 0; ///< Worst (%).
    double worstMissedPct = 0; ///< Worst device's missed deadlines (% of ticks), median.
    double lateWakeups = 0;    ///< Late wake-ups over all devices, median.
    int stableRuns = 0;        ///< Repeats in which every device was stable.
    bool realtime = true;      ///< SCHED_FIFO granted to every servo thread.
    int cores = 1;
    std::string note;
    Tail tail = Tail::P999; ///< The percentile the verdict reads.
    /// DESIGN.md's verdict on the medians of the worst device (p99 for quick runs). [any thread]
    bool stable() const {
        return note.empty() && (tail == Tail::P99 ? worstP99Pct : worstP999Pct) < 100.0 &&
               worstMissedPct <= 0.1;
    }
};

struct PerDeviceRow {
    double rateHz;
    int devices, repeat, device;
    LoadFigures f;
};

/// One cursor strategy's walk.
struct CursorRow {
    std::size_t objects = 0;
    int perSide = 0;
    std::uint32_t depth = 0;
    std::uint64_t leaves = 0;
    double log8NOverM = 0;
    std::string strategy;
    std::uint64_t locates = 0, leafChanges = 0, steps = 0, mismatches = 0;
    double nsPerLocate = 0;
    double stepsPerLocate() const { return locates ? double(steps) / double(locates) : 0.0; }
    double stepsPerChange() const {
        return leafChanges ? double(steps) / double(leafChanges) : 0.0;
    }
};

const char* strategyName(CursorStrategy s) {
    switch (s) {
    case CursorStrategy::FromRoot:
        return "root";
    case CursorStrategy::Climb:
        return "climb";
    case CursorStrategy::NeighbourLinks:
        return "links";
    }
    return "?";
}

template <class T> void keep(const T& value) {
    asm volatile("" : : "g"(value) : "memory");
}

/// Drives three cursors (root, climb, links) over one octree along the same hand-speed walk.
std::vector<CursorRow> cursorWalk(std::size_t n, const IndexSpec& spec, std::size_t walkSteps,
                                  Progress& progress) {
    const int k = std::max(2, static_cast<int>(std::lround(std::cbrt(static_cast<double>(n)))));
    LatticeOptions lo;
    lo.perSide = k;
    progress.show("cursor: lattice K=" + std::to_string(k));
    const Scene scene = makeLatticeScene(lo);
    progress.show("cursor: building " + spec.toString() + " over " + std::to_string(scene.size()) +
                  " objects");
    const std::unique_ptr<SpatialIndex> index = buildIndex(scene, spec);
    const CursorStrategy strategies[] = {CursorStrategy::FromRoot, CursorStrategy::Climb,
                                         CursorStrategy::NeighbourLinks};
    std::vector<CursorRow> rows(3);
    std::vector<Cursor> cursors;
    std::vector<double> ns(3, 0.0);
    std::vector<std::uint32_t> lastLeaf(3, kNoLeaf);
    for (int s = 0; s < 3; ++s) {
        cursors.emplace_back(*index, strategies[s]);
        CursorRow& r = rows[static_cast<std::size_t>(s)];
        r.objects = scene.size();
        r.perSide = k;
        r.depth = index->stats().depth;
        r.leaves = index->stats().leaves;
        r.log8NOverM = std::log(static_cast<double>(scene.size()) / std::max(1, spec.maxObjects)) /
                       std::log(8.0);
        r.strategy = strategyName(strategies[s]);
    }
    HandWalk walk(scene.bounds(), 1);
    constexpr std::size_t kBlock = 4096;
    std::vector<Vec3> block(kBlock);
    std::vector<std::uint32_t> leaves(kBlock);
    std::uint64_t touched = 0;
    progress.show("cursor: walking " + std::to_string(scene.size()) + " objects");
    for (std::size_t done = 0; done < walkSteps;) {
        const std::size_t len = std::min(kBlock, walkSteps - done);
        for (std::size_t i = 0; i < len; ++i) {
            block[i] = walk.next();
        }
        for (std::size_t s = 0; s < 3; ++s) {
            CursorRow& r = rows[s];
            Cursor& c = cursors[s];
            std::uint64_t steps = 0, changes = 0, mismatches = 0;
            std::uint32_t last = lastLeaf[s];
            const auto t0 = std::chrono::steady_clock::now();
            for (std::size_t i = 0; i < len; ++i) {
                const LocateResult res = c.locate(block[i]);
                steps += res.steps;
                changes += res.leaf != last ? 1 : 0;
                last = res.leaf;
                touched += res.candidates.size();
                if (s == 0) {
                    leaves[i] = res.leaf;
                } else if (leaves[i] != res.leaf) {
                    ++mismatches;
                }
            }
            const auto t1 = std::chrono::steady_clock::now();
            keep(touched);
            ns[s] += std::chrono::duration<double, std::nano>(t1 - t0).count();
            lastLeaf[s] = last;
            r.locates += len;
            r.steps += steps;
            r.leafChanges += changes;
            r.mismatches += mismatches;
        }
        done += len;
    }
    for (std::size_t s = 0; s < 3; ++s) {
        rows[s].nsPerLocate =
            ns[s] / static_cast<double>(std::max<std::uint64_t>(1, rows[s].locates));
    }
    return rows;
}

} // namespace

int runDevices(const DevicesArgs& args) {
    const std::filesystem::path out = prepareOutDir(args.common.out);
    if (args.script != "walk" && args.script != "slide") {
        throw InputError("--script '" + args.script + "': expected walk or slide");
    }
    const IndexSpec spec = IndexSpec::parse(args.index).withMaxMegabytes(args.maxIndexMb);
    IndexSpec cursorSpec = spec.kind == IndexSpec::Kind::Octree
                               ? spec
                               : IndexSpec::octree(2, 0.005).withMaxMegabytes(args.maxIndexMb);
    const auto shared = std::make_shared<const Scene>(
        args.scene.empty() ? makeDefaultScene() : loadSceneFile(args.scene));
    const Scene& scene = *shared; // the world shares it: one copy
    const std::vector<int> counts = deviceCounts(args.maxDevices);

    Progress progress("devices", args.ratesHz.size() * counts.size() *
                                         static_cast<std::size_t>(args.common.repeats) +
                                     (args.cursor ? args.cursorObjects.size() : 0));
    progress.show("building " + spec.toString() + " over " + std::to_string(scene.size()) +
                  " objects");
    World world(shared, spec);
    const std::vector<Vec3> starts = clearStarts(scene, *world.current().index, args.maxDevices);

    ServoSettings servo;
    servo.durationS = args.common.durationS;
    servo.repeats = args.common.repeats;
    servo.realtime = args.common.realtime;
    servo.tail = tailFor(args.common.quick);
    const bool quick = args.common.quick;

    std::vector<ScalingRow> rows;
    std::vector<PerDeviceRow> perDevice;
    std::string realtimeNote;
    for (const double rate : args.ratesHz) {
        for (const int d : counts) {
            std::vector<HandPlan> hands;
            for (int i = 0; i < d; ++i) {
                hands.push_back({simHand("hand" + std::to_string(i), rate, args.script,
                                         static_cast<std::uint64_t>(i + 1),
                                         starts[static_cast<std::size_t>(i)]),
                                 &scene});
            }
            ScalingRow row;
            row.rateHz = rate;
            row.devices = d;
            row.repeats = args.common.repeats;
            row.tail = servo.tail;
            std::vector<double> sum, perCore, devMean, w50, w99, w999, wMax, wMissed, late;
            for (int k = 0; k < args.common.repeats; ++k) {
                progress.show(std::to_string(d) + " devices at " + rateText(rate));
                const SessionResult s = runSession(world, hands, servo);
                const RunReport& r = s.report;
                row.cores = r.cores;
                if (!r.realtimeNote.empty()) {
                    realtimeNote = r.realtimeNote;
                }
                double mean = 0, a = 0, a99 = 0, b = 0, c = 0, m = 0, l = 0;
                bool allStable = r.stable;
                for (std::size_t i = 0; i < r.devices.size(); ++i) {
                    const LoadFigures f = figuresOf(r.devices[i], servo.tail);
                    perDevice.push_back({rate, d, k, static_cast<int>(i), f});
                    mean += f.meanPct;
                    a = std::max(a, f.p50Pct);
                    a99 = std::max(a99, f.p99Pct);
                    b = std::max(b, f.p999Pct);
                    c = std::max(c, f.maxPct);
                    m = std::max(m, f.missedPct);
                    l += f.lateWakeups;
                    row.realtime = row.realtime && f.realtime;
                    allStable = allStable && f.stable();
                    if (!f.fault.empty()) {
                        row.note = "fault: " + f.fault;
                    }
                }
                sum.push_back(100.0 * r.loadSum);
                perCore.push_back(100.0 * r.loadPerCore);
                devMean.push_back(mean / std::max<std::size_t>(1, r.devices.size()));
                w50.push_back(a);
                w99.push_back(a99);
                w999.push_back(b);
                wMax.push_back(c);
                wMissed.push_back(m);
                late.push_back(l);
                row.stableRuns += allStable ? 1 : 0;
                progress.advance(1, std::to_string(d) + " devices at " + rateText(rate));
            }
            row.loadSumPct = median(sum);
            row.loadPerCorePct = median(perCore);
            row.deviceMeanLoadPct = median(devMean);
            row.worstP50Pct = median(w50);
            row.worstP99Pct = median(w99);
            row.worstP999Pct = median(w999);
            row.worstMaxPct = median(wMax);
            row.worstMissedPct = median(wMissed);
            row.lateWakeups = median(late);
            rows.push_back(row);
        }
    }

    std::vector<CursorRow> cursorRows;
    if (args.cursor) {
        for (const std::size_t n : args.cursorObjects) {
            for (CursorRow& r : cursorWalk(n, cursorSpec, args.walkSteps, progress)) {
                cursorRows.push_back(r);
            }
            progress.advance(1, "cursor N=" + std::to_string(n));
        }
    }

    // Files: each table declared once, written as CSV and JSON (and markdown below).
    const auto I = [](auto v) { return Cell(static_cast<std::int64_t>(v)); };
    Table devicesTable({
        {"rate_hz", "Hz", -1, "", ColumnIn::Data},
        {"devices", "", -1, "devices"},
        {"repeats", "", -1, "", ColumnIn::Data},
        {"load_sum_pct", "%", 2, "load sum % (one core)"},
        {"load_per_core_pct", "%", 2, "per core %"},
        {"device_load_mean_pct", "%", 2, "per device mean %"},
        {"worst_load_p50_pct", "%", 2, "worst p50 %"},
        {"worst_load_p99_pct", "%", 1, "worst p99 %", quick ? ColumnIn::All : ColumnIn::Data},
        {"worst_load_p999_pct", "%", 1, "worst p99.9 %"},
        {"worst_load_max_pct", "%", 1, "worst max %"},
        {"worst_missed_pct", "%", 2, "worst missed %"},
        {"late_wakeups", "", -1, "", ColumnIn::Data},
        {"stable_runs", "", -1, "", ColumnIn::Data},
        {"stable", "", -1, "", ColumnIn::Data},
        {"realtime", "", -1, "", ColumnIn::Data},
        {"cores", "", -1, "", ColumnIn::Data},
        {"note", "", -1, "", ColumnIn::Data},
        {"verdict", "", -1, "verdict", ColumnIn::Markdown},
    });
    for (const ScalingRow& r : rows) {
        devicesTable.add({r.rateHz, I(r.devices), I(r.repeats), r.loadSumPct, r.loadPerCorePct,
                          r.deviceMeanLoadPct, r.worstP50Pct, r.worstP99Pct, r.worstP999Pct,
                          r.worstMaxPct, r.worstMissedPct, r.lateWakeups, I(r.stableRuns),
                          r.stable(), r.realtime, I(r.cores), r.note,
                          std::string(r.stable() ? "stable" : "UNSTABLE") + " (" +
                              std::to_string(r.stableRuns) + "/" + std::to_string(r.repeats) +
                              " runs)"});
    }
    Table perDeviceTable({
        {"rate_hz", "Hz"},
        {"devices", ""},
        {"repeat", ""},
        {"device", ""},
        {"load_mean_pct", "%"},
        {"load_p50_pct", "%"},
        {"load_p99_pct", "%"},
        {"load_p999_pct", "%"},
        {"load_max_pct", "%"},
        {"ticks", ""},
        {"missed", ""},
        {"missed_pct", "%"},
        {"late_wakeups", ""},
        {"contact_pct", "%"},
        {"candidates_mean", ""},
        {"stable", ""},
        {"fault", ""},
    });
    for (const PerDeviceRow& r : perDevice) {
        perDeviceTable.add({r.rateHz, I(r.devices), I(r.repeat), I(r.device), r.f.meanPct,
                            r.f.p50Pct, r.f.p99Pct, r.f.p999Pct, r.f.maxPct, r.f.ticks, r.f.missed,
                            r.f.missedPct, r.f.lateWakeups, r.f.contactPct, r.f.candidatesMean,
                            r.f.stable(), r.f.fault});
    }
    Table cursorTable({
        {"objects", ""},
        {"per_side", ""},
        {"depth", ""},
        {"leaves", ""},
        {"log8_n_over_m", ""},
        {"strategy", ""},
        {"locates", ""},
        {"leaf_changes", ""},
        {"steps_per_locate", ""},
        {"steps_per_leaf_change", ""},
        {"ns_per_locate", "ns"},
        {"leaf_mismatches", ""},
    });
    for (const CursorRow& r : cursorRows) {
        cursorTable.add({I(r.objects), I(r.perSide), I(r.depth), I(r.leaves), r.log8NOverM,
                         r.strategy, I(r.locates), I(r.leafChanges), r.stepsPerLocate(),
                         r.stepsPerChange(), r.nsPerLocate, I(r.mismatches)});
    }
    devicesTable.writeCsv(out / "devices.csv");
    perDeviceTable.writeCsv(out / "devices-per-device.csv");
    cursorTable.writeCsv(out / "cursor.csv");
    Json j;
    j["experiment"] = "devices";
    j["machine"] = machineJson();
    j["options"] = {{"rates_hz", args.ratesHz},
                    {"max_devices", args.maxDevices},
                    {"scene", args.scene.empty() ? "(embedded default scene)" : args.scene},
                    {"objects", scene.size()},
                    {"index", spec.toString()},
                    {"script", args.script},
                    {"duration_s", args.common.durationS},
                    {"repeats", args.common.repeats},
                    {"realtime_requested", args.common.realtime},
                    {"quick", args.common.quick},
                    {"verdict_percentile", tailName(servo.tail)},
                    {"cursor_index", cursorSpec.toString()},
                    {"cursor_objects", args.cursorObjects},
                    {"walk_steps", args.walkSteps}};
    j["realtime_note"] = realtimeNote;
    Json jd = devicesTable.json();
    for (std::size_t i = 0; i < rows.size(); ++i) {
        Json devs = Json::array();
        for (std::size_t k = 0; k < perDevice.size(); ++k) {
            if (perDevice[k].rateHz == rows[i].rateHz && perDevice[k].devices == rows[i].devices) {
                devs.push_back(perDeviceTable.json(k));
            }
        }
        jd[i]["per_device"] = devs;
    }
    j["devices"] = jd;
    j["cursor"] = cursorTable.json();
    writeText(out / "devices.json", j.dump(2) + "\n");

    // Plots.
    std::vector<std::filesystem::path> plots;
    {
        PlotSpec p;
        p.name = "devices-load";
        p.title = "Haptic load against devices over one world (" + spec.toString() + ", " +
                  std::to_string(scene.size()) + " objects, script " + args.script + ")";
        // Two quantities (% of one core, % of the period), so each panel keeps its own scale.
        p.unstableTitle =
            "unstable (" + std::string(tailName(servo.tail)) + " load >= 100 % or > 0.1 % missed)";
        PlotPanel total{"total: sum of mean loads",
                        "devices",
                        "load (% of one core)",
                        true,
                        false,
                        {},
                        {},
                        {},
                        {}};
        PlotPanel worst{"worst device: p99.9 solid, p50 dashed",
                        "devices",
                        "load (% of the period)",
                        true,
                        true,
                        {},
                        100.0,
                        "100 % (one period)",
                        {}};
        for (const int d : counts) {
            total.xTics.push_back(d);
            worst.xTics.push_back(d);
        }
        int style = 1;
        for (const double rate : args.ratesHz) {
            PlotSeries a{rateText(rate), {}, {}, false, style};
            PlotSeries b{rateText(rate) + " p99.9", {}, {}, false, style};
            PlotSeries c{rateText(rate) + " p50", {}, {}, true, style};
            for (const ScalingRow& r : rows) {
                if (r.rateHz == rate) {
                    a.points.emplace_back(r.devices, r.loadSumPct);
                    a.unstable.push_back(!r.stable());
                    b.points.emplace_back(r.devices, r.worstP999Pct);
                    b.unstable.push_back(!r.stable());
                    c.points.emplace_back(r.devices, r.worstP50Pct);
                }
            }
            total.series.push_back(a);
            worst.series.push_back(b);
            worst.series.push_back(c);
            ++style;
        }
        p.panels = {total, worst};
        const PlotResult pr = drawPlot(out, p);
        if (!pr.problem.empty()) {
            progress.note("hapto experiment: plot skipped: " + pr.problem);
        }
        plots.insert(plots.end(), pr.files.begin(), pr.files.end());
    }
    if (!cursorRows.empty()) {
        PlotSpec p;
        p.name = "cursor-steps";
        p.title =
            "Cursor steps against N (" + cursorSpec.toString() + ", K^3 lattices, hand-speed walk)";
        PlotPanel perLocate{"per locate (log scale)",
                            "objects N",
                            "mean steps per locate",
                            true,
                            true,
                            {},
                            {},
                            {},
                            {}};
        PlotPanel perChange{"per leaf change",
                            "objects N",
                            "mean steps per leaf change",
                            true,
                            false,
                            {},
                            {},
                            {},
                            {}};
        for (const std::size_t n : args.cursorObjects) {
            perLocate.xTics.push_back(static_cast<double>(n));
            perChange.xTics.push_back(static_cast<double>(n));
        }
        for (const char* s : {"root", "climb", "links"}) {
            PlotSeries a{s, {}, {}, false, -1}, b{s, {}, {}, false, -1};
            for (const CursorRow& r : cursorRows) {
                if (r.strategy == s) {
                    a.points.emplace_back(r.objects, r.stepsPerLocate());
                    b.points.emplace_back(r.objects, r.stepsPerChange());
                }
            }
            perLocate.series.push_back(a);
            if (std::string(s) == "root") { // root descends at every locate, change or not
                b.points.clear();
            }
            perChange.series.push_back(b);
        }
        PlotSeries ref{"log8(N/M)", {}, {}, true, -1};
        for (const CursorRow& r : cursorRows) {
            if (r.strategy == std::string("root")) {
                ref.points.emplace_back(r.objects, r.log8NOverM);
            }
        }
        perChange.series.push_back(ref);
        p.panels = {perLocate, perChange};
        const PlotResult pr = drawPlot(out, p);
        if (!pr.problem.empty()) {
            progress.note("hapto experiment: plot skipped: " + pr.problem);
        }
        plots.insert(plots.end(), pr.files.begin(), pr.files.end());
    }

    // Tables.
    std::string md = "## Load against devices: " + std::to_string(scene.size()) + " objects, " +
                     spec.toString() + ", script " + args.script + "\n\n" +
                     "Every device has its own servo thread over one shared World. Loads in % "
                     "(wake-up to force written over the period); medians of " +
                     std::to_string(args.common.repeats) + " run(s) of " +
                     fmt(args.common.durationS, 2) + " s. " + verdictNote(servo.tail) + "\n";
    for (const double rate : args.ratesHz) {
        md += "\n### " + rateText(rate) + "\n\n";
        md += devicesTable.markdown([&](std::size_t i) { return rows[i].rateHz == rate; });
    }
    if (!realtimeNote.empty()) {
        md += "\nNote: " + realtimeNote + "\n";
    }
    if (!cursorRows.empty()) {
        md += "\n## Cursor steps against N (" + cursorSpec.toString() +
              ", K^3 lattices of 5 cm cubes, " + std::to_string(args.walkSteps) +
              " steps of a 1 ms hand-speed walk)\n\n"
              "Steps = links followed (parent, child, neighbour) per locate. root: descend from "
              "the root at every locate (no cache); climb: from the cached leaf up to the first "
              "ancestor holding the point and down (the paper's octree without neighbour "
              "links); links: across faces through neighbour links. The paper's claim (2.2.4): "
              "O(M + log8(N/M)) per leaf change without links, O(M) with them.\n\n";
        std::vector<std::vector<std::string>> t;
        for (std::size_t i = 0; i + 2 < cursorRows.size(); i += 3) {
            const CursorRow& root = cursorRows[i];
            const CursorRow& climb = cursorRows[i + 1];
            const CursorRow& links = cursorRows[i + 2];
            t.push_back({std::to_string(root.objects), std::to_string(root.depth),
                         fmt(root.log8NOverM, 2),
                         fmt(1000.0 * double(links.leafChanges) / double(links.locates), 1),
                         fmt(root.stepsPerLocate(), 3), fmt(climb.stepsPerLocate(), 3),
                         fmt(links.stepsPerLocate(), 3), fmt(climb.stepsPerChange(), 2),
                         fmt(links.stepsPerChange(), 2),
                         fmt(root.nsPerLocate, 1) + " / " + fmt(climb.nsPerLocate, 1) + " / " +
                             fmt(links.nsPerLocate, 1)});
        }
        md += markdownTable({"N", "depth", "log8(N/M)", "leaf changes /1000 locates",
                             "steps/locate root", "climb", "links", "steps/leaf change climb",
                             "links", "ns/locate root / climb / links"},
                            t);
    }
    md += "\nFiles: " + (out / "devices.csv").string() + ", " +
          (out / "devices-per-device.csv").string() + ", " + (out / "cursor.csv").string() + ", " +
          (out / "devices.json").string() + ", " + (out / "devices.md").string();
    for (const auto& p : plots) {
        md += ", " + p.string();
    }
    md += "\n";
    writeText(out / "devices.md", md);
    progress.finish(); // the results never share a line with the bar
    std::cout << md << std::flush;
    return 0;
}

} // namespace hapto::experiments
