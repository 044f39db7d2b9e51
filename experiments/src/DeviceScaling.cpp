// `hapto experiment scaling`: haptic load against the number of devices sharing one world,
// and cursor steps per locate against N for the three cursor strategies.

#include "hapto/experiments/Experiments.h"

#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/experiments/HandWalk.h"
#include "hapto/experiments/Plot.h"
#include "hapto/experiments/Progress.h"
#include "hapto/experiments/Stats.h"
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

/// The device counts to run: those asked, else 1, 2, 4, ... up to maxDevices and it.
std::vector<int> deviceCounts(const DevicesArgs& args) {
    if (!args.deviceCounts.empty()) {
        return args.deviceCounts;
    }
    const int maxDevices = args.maxDevices;
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
    double worstMissedPct = 0;       ///< Worst device's missed deadlines (% of ticks), median.
    double lateWakeups = 0;          ///< Late wake-ups over all devices, median.
    int stableRuns = 0;              ///< Repeats in which every device was stable.
    MedianInterval loadSum;          ///< loadSumPct's median and interval over repeats (%).
    MedianInterval medianDeviceP999; ///< The median device's p99.9 load over repeats (%).
    MedianInterval worstP999;        ///< The worst device's p99.9 load over repeats (%).
    bool realtime = true;            ///< SCHED_FIFO granted to every servo thread.
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

/// A whole number as a table cell.
Cell whole(auto value) {
    return Cell(static_cast<std::int64_t>(value));
}

/// What the whole run shares: its arguments, the scene, the two index specs and the verdict.
struct ScalingSetup {
    const DevicesArgs& args;
    const Scene& scene;
    IndexSpec spec;       ///< The index the hands run over.
    IndexSpec cursorSpec; ///< The octree the cursor part walks.
    ServoSettings servo;  ///< Duration, repeats, realtime and the verdict's percentile.
};

/// The device-scaling part's results, in measurement order.
struct ScalingResults {
    std::vector<ScalingRow> rows;        ///< One per (rate, device count).
    std::vector<PerDeviceRow> perDevice; ///< One per (rate, device count, repeat, device).
    std::string realtimeNote;            ///< The last run's note when SCHED_FIFO was refused.
};

/// One repeat of one cell, over its devices: sums, the mean device, and the worst device per
/// figure (each figure's own worst).
struct RepeatFigures {
    double loadSumPct = 0, loadPerCorePct = 0, deviceMeanLoadPct = 0;
    double worstP50Pct = 0, worstP99Pct = 0, worstP999Pct = 0, worstMaxPct = 0;
    double worstMissedPct = 0, lateWakeups = 0;
    double medianDeviceP999Pct = 0; ///< The median over devices of their p99.9 load (%).
    bool allStable = true;          ///< The run was stable and so was every device.
    bool realtime = true;           ///< Every device got SCHED_FIFO.
    std::string fault;              ///< The last device fault, or empty.
};

/// Folds one run's per-device figures into the repeat's figures. [control]
RepeatFigures repeatFigures(const RunReport& r, const std::vector<LoadFigures>& devices) {
    RepeatFigures x;
    x.allStable = r.stable;
    double mean = 0;
    for (const LoadFigures& f : devices) {
        mean += f.meanPct;
        x.worstP50Pct = std::max(x.worstP50Pct, f.p50Pct);
        x.worstP99Pct = std::max(x.worstP99Pct, f.p99Pct);
        x.worstP999Pct = std::max(x.worstP999Pct, f.p999Pct);
        x.worstMaxPct = std::max(x.worstMaxPct, f.maxPct);
        x.worstMissedPct = std::max(x.worstMissedPct, f.missedPct);
        x.lateWakeups += f.lateWakeups;
        x.realtime = x.realtime && f.realtime;
        x.allStable = x.allStable && f.stable();
        if (!f.fault.empty()) {
            x.fault = f.fault;
        }
    }
    x.loadSumPct = 100.0 * r.loadSum;
    x.loadPerCorePct = 100.0 * r.loadPerCore;
    x.deviceMeanLoadPct = mean / std::max<std::size_t>(1, devices.size());
    std::vector<double> p999;
    for (const LoadFigures& f : devices) {
        p999.push_back(f.p999Pct);
    }
    x.medianDeviceP999Pct = median(p999);
    return x;
}

/// One figure of every repeat.
std::vector<double> valuesOver(const std::vector<RepeatFigures>& runs,
                               double RepeatFigures::*figure) {
    std::vector<double> values;
    for (const RepeatFigures& x : runs) {
        values.push_back(x.*figure);
    }
    return values;
}

/// The median over repeats of one figure.
double medianOver(const std::vector<RepeatFigures>& runs, double RepeatFigures::*figure) {
    return median(valuesOver(runs, figure));
}

/// Fills a cell's row from its repeats: medians of every figure, stable repeats counted,
/// realtime only when every device of every repeat had it, the last fault as the note.
void concludeScalingRow(ScalingRow& row, const std::vector<RepeatFigures>& runs) {
    for (const RepeatFigures& x : runs) {
        row.realtime = row.realtime && x.realtime;
        row.stableRuns += x.allStable ? 1 : 0;
        if (!x.fault.empty()) {
            row.note = "fault: " + x.fault;
        }
    }
    row.loadSumPct = medianOver(runs, &RepeatFigures::loadSumPct);
    row.loadPerCorePct = medianOver(runs, &RepeatFigures::loadPerCorePct);
    row.deviceMeanLoadPct = medianOver(runs, &RepeatFigures::deviceMeanLoadPct);
    row.worstP50Pct = medianOver(runs, &RepeatFigures::worstP50Pct);
    row.worstP99Pct = medianOver(runs, &RepeatFigures::worstP99Pct);
    row.worstP999Pct = medianOver(runs, &RepeatFigures::worstP999Pct);
    row.worstMaxPct = medianOver(runs, &RepeatFigures::worstMaxPct);
    row.worstMissedPct = medianOver(runs, &RepeatFigures::worstMissedPct);
    row.lateWakeups = medianOver(runs, &RepeatFigures::lateWakeups);
    row.loadSum = medianInterval(valuesOver(runs, &RepeatFigures::loadSumPct));
    row.medianDeviceP999 = medianInterval(valuesOver(runs, &RepeatFigures::medianDeviceP999Pct));
    row.worstP999 = medianInterval(valuesOver(runs, &RepeatFigures::worstP999Pct));
}

/// `devices` simulated hands at `rateHz`, hand i from starts[i] with seed i + 1.
std::vector<HandPlan> scalingHands(const ScalingSetup& setup, const std::vector<Vec3>& starts,
                                   double rateHz, int devices) {
    std::vector<HandPlan> hands;
    for (int i = 0; i < devices; ++i) {
        hands.push_back(
            {simHand("hand" + std::to_string(i), rateHz, setup.args.script,
                     static_cast<std::uint64_t>(i + 1), starts[static_cast<std::size_t>(i)]),
             &setup.scene});
    }
    return hands;
}

/// Runs one (rate, device count) cell `repeats` times over `world`; appends its row and its
/// per-device rows to `results`. [control]
void measureCell(World& world, const ScalingSetup& setup, const std::vector<Vec3>& starts,
                 double rate, int devices, ScalingResults& results, Progress& progress) {
    const std::vector<HandPlan> hands = scalingHands(setup, starts, rate, devices);
    ScalingRow row;
    row.rateHz = rate;
    row.devices = devices;
    row.repeats = setup.args.common.repeats;
    row.tail = setup.servo.tail;
    std::vector<RepeatFigures> runs;
    for (int k = 0; k < setup.args.common.repeats; ++k) {
        progress.show(std::to_string(devices) + " devices at " + rateText(rate));
        const RunReport r = runSession(world, hands, setup.servo).report;
        row.cores = r.cores;
        if (!r.realtimeNote.empty()) {
            results.realtimeNote = r.realtimeNote;
        }
        std::vector<LoadFigures> figures;
        for (std::size_t i = 0; i < r.devices.size(); ++i) {
            figures.push_back(figuresOf(r.devices[i], setup.servo.tail));
            results.perDevice.push_back({rate, devices, k, static_cast<int>(i), figures.back()});
        }
        runs.push_back(repeatFigures(r, figures));
        progress.advance(1, std::to_string(devices) + " devices at " + rateText(rate));
    }
    concludeScalingRow(row, runs);
    results.rows.push_back(row);
}

/// The cursor part: one walk per N, three rows each (root, climb, links).
std::vector<CursorRow> measureCursors(const ScalingSetup& setup, Progress& progress) {
    std::vector<CursorRow> rows;
    if (!setup.args.cursor) {
        return rows;
    }
    for (const std::size_t n : setup.args.cursorObjects) {
        for (CursorRow& r : cursorWalk(n, setup.cursorSpec, setup.args.walkSteps, progress)) {
            rows.push_back(r);
        }
        progress.advance(1, "cursor N=" + std::to_string(n));
    }
    return rows;
}

/// One row per (rate, device count); the p99 column shows in markdown only for quick runs,
/// whose verdict reads it.
Table scalingTable(const std::vector<ScalingRow>& rows, bool quick) {
    Table t({
        {"rate_hz", "Hz", -1, "", ColumnIn::Data},
        {"devices", "", -1, "devices"},
        {"repeats", "", -1, "", ColumnIn::Data},
        {"load_sum_pct", "%", -1, "", ColumnIn::Data},
        {"load_sum_lo_pct", "%", -1, "", ColumnIn::Data},
        {"load_sum_hi_pct", "%", -1, "", ColumnIn::Data},
        {"load_sum_cell", "", -1, "load sum % (one core), median [interval]", ColumnIn::Markdown},
        {"load_per_core_pct", "%", 2, "per core %"},
        {"device_load_mean_pct", "%", 2, "per device mean %"},
        {"worst_load_p50_pct", "%", 2, "worst p50 %"},
        {"worst_load_p99_pct", "%", 1, "worst p99 %", quick ? ColumnIn::All : ColumnIn::Data},
        {"median_device_p999_pct", "%", -1, "", ColumnIn::Data},
        {"median_device_p999_lo_pct", "%", -1, "", ColumnIn::Data},
        {"median_device_p999_hi_pct", "%", -1, "", ColumnIn::Data},
        {"median_device_p999_cell", "", -1, "median device p99.9 % [interval]", ColumnIn::Markdown},
        {"worst_load_p999_pct", "%", -1, "", ColumnIn::Data},
        {"worst_load_p999_lo_pct", "%", -1, "", ColumnIn::Data},
        {"worst_load_p999_hi_pct", "%", -1, "", ColumnIn::Data},
        {"worst_p999_cell", "", -1, "worst device p99.9 % [interval]", ColumnIn::Markdown},
        {"worst_load_max_pct", "%", 1, "worst max %"},
        {"worst_missed_pct", "%", 2, "worst missed %"},
        {"late_wakeups", "", -1, "", ColumnIn::Data},
        {"stable_runs", "", -1, "", ColumnIn::Data},
        {"interval_coverage", "", -1, "", ColumnIn::Data},
        {"stable", "", -1, "", ColumnIn::Data},
        {"realtime", "", -1, "", ColumnIn::Data},
        {"cores", "", -1, "", ColumnIn::Data},
        {"note", "", -1, "", ColumnIn::Data},
        {"verdict", "", -1, "verdict", ColumnIn::Markdown},
    });
    for (const ScalingRow& r : rows) {
        t.add({r.rateHz,
               whole(r.devices),
               whole(r.repeats),
               r.loadSumPct,
               r.loadSum.lo,
               r.loadSum.hi,
               intervalText(r.loadSum, 2),
               r.loadPerCorePct,
               r.deviceMeanLoadPct,
               r.worstP50Pct,
               r.worstP99Pct,
               r.medianDeviceP999.median,
               r.medianDeviceP999.lo,
               r.medianDeviceP999.hi,
               intervalText(r.medianDeviceP999, 1),
               r.worstP999Pct,
               r.worstP999.lo,
               r.worstP999.hi,
               intervalText(r.worstP999, 1),
               r.worstMaxPct,
               r.worstMissedPct,
               r.lateWakeups,
               whole(r.stableRuns),
               r.loadSum.coverage,
               r.stable(),
               r.realtime,
               whole(r.cores),
               r.note,
               std::string(r.stable() ? "stable" : "UNSTABLE") + " (" +
                   std::to_string(r.stableRuns) + "/" + std::to_string(r.repeats) + " runs)"});
    }
    return t;
}

/// One row per device of every run.
Table perDeviceTable(const std::vector<PerDeviceRow>& rows) {
    Table t({
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
    for (const PerDeviceRow& r : rows) {
        t.add({r.rateHz, whole(r.devices), whole(r.repeat), whole(r.device), r.f.meanPct,
               r.f.p50Pct, r.f.p99Pct, r.f.p999Pct, r.f.maxPct, r.f.ticks, r.f.missed,
               r.f.missedPct, r.f.lateWakeups, r.f.contactPct, r.f.candidatesMean, r.f.stable(),
               r.f.fault});
    }
    return t;
}

/// One row per (N, strategy).
Table cursorTable(const std::vector<CursorRow>& rows) {
    Table t({
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
    for (const CursorRow& r : rows) {
        t.add({whole(r.objects), whole(r.perSide), whole(r.depth), whole(r.leaves), r.log8NOverM,
               r.strategy, whole(r.locates), whole(r.leafChanges), r.stepsPerLocate(),
               r.stepsPerChange(), r.nsPerLocate, whole(r.mismatches)});
    }
    return t;
}

/// devices.json: the machine, the options, the scaling rows each with its per-device rows, and
/// the cursor rows.
Json scalingJson(const ScalingSetup& setup, const ScalingResults& results, const Table& scaling,
                 const Table& perDevice, const Table& cursor) {
    const DevicesArgs& args = setup.args;
    Json j;
    j["experiment"] = "devices";
    j["machine"] = machineJson();
    j["options"] = {
        {"rates_hz", args.ratesHz},
        {"device_counts", deviceCounts(args)},
        {"scene", args.scene.empty() ? "(embedded default scene)" : args.scene},
        {"objects", setup.scene.size()},
        {"index", setup.spec.toString()},
        {"script", args.script},
        {"duration_s", args.common.durationS},
        {"repeats", args.common.repeats},
        {"realtime_requested", args.common.realtime},
        {"quick", args.common.quick},
        {"verdict_percentile", tailName(setup.servo.tail)},
        {"interval", "order statistics of the median over repeats"},
        {"interval_coverage",
         medianInterval(std::vector<double>(static_cast<std::size_t>(args.common.repeats), 0.0))
             .coverage},
        {"cursor_index", setup.cursorSpec.toString()},
        {"cursor_objects", args.cursorObjects},
        {"walk_steps", args.walkSteps}};
    j["realtime_note"] = results.realtimeNote;
    Json jd = scaling.json();
    for (std::size_t i = 0; i < results.rows.size(); ++i) {
        Json devs = Json::array();
        for (std::size_t k = 0; k < results.perDevice.size(); ++k) {
            const PerDeviceRow& d = results.perDevice[k];
            if (d.rateHz == results.rows[i].rateHz && d.devices == results.rows[i].devices) {
                devs.push_back(perDevice.json(k));
            }
        }
        jd[i]["per_device"] = devs;
    }
    j["devices"] = jd;
    j["cursor"] = cursor.json();
    return j;
}

/// A series of one figure of the rows at `rate`: the medians, their intervals as error bars,
/// rings where the cell was unstable; drawn `shift` devices right of its count (so the bars of
/// two series at one count do not hide each other).
PlotSeries intervalSeries(std::string title, int style, bool dashed,
                          const std::vector<ScalingRow>& rows, double rate,
                          MedianInterval ScalingRow::*figure, double shift = 0.0) {
    PlotSeries s{std::move(title), {}, {}, dashed, style};
    for (const ScalingRow& r : rows) {
        if (r.rateHz == rate) {
            const MedianInterval& m = r.*figure;
            s.points.emplace_back(r.devices + shift, m.median);
            s.errors.emplace_back(m.lo, m.hi);
            s.unstable.push_back(!r.stable());
        }
    }
    return s;
}

/// devices-load: total load against the device count on linear axes (a linear law shows as a
/// line), and per device: the median device's p99.9 (solid) beside the worst device's (dashed;
/// a maximum over more devices grows with their count by itself), a colour per rate, the
/// intervals across repeats as bars, rings where a cell was unstable.
PlotSpec scalingPlot(const ScalingSetup& setup, const std::vector<ScalingRow>& rows,
                     const std::vector<int>& counts) {
    PlotSpec p;
    p.name = "devices-load";
    p.title = "Haptic load against devices over one world (" + setup.spec.toString() + ", " +
              std::to_string(setup.scene.size()) + " objects, script " + setup.args.script + ")";
    p.caption = repeatsCaption(setup.args.common);
    // Two quantities (% of one core, % of the period), so each panel keeps its own scale.
    p.unstableTitle = "unstable (" + std::string(tailName(setup.servo.tail)) +
                      " load >= 100 % or > 0.1 % missed)";
    PlotPanel total =
        panel("total: sum of the devices' mean loads", "devices (linear)", "load (% of one core)");
    PlotPanel tail = panel("per device p99.9: median device solid, worst device dashed",
                           "devices (linear)", "p99.9 load (% of the period)");
    tail.logY = true;
    tail.limitY = 100.0;
    tail.limitTitle = "100 % (one period)";
    for (const int d : counts) {
        total.xTics.push_back(d);
        tail.xTics.push_back(d);
    }
    int style = 1;
    for (const double rate : setup.args.ratesHz) {
        total.series.push_back(
            intervalSeries(rateText(rate), style, false, rows, rate, &ScalingRow::loadSum));
        tail.series.push_back(intervalSeries(rateText(rate) + " median device", style, false, rows,
                                             rate, &ScalingRow::medianDeviceP999));
        tail.series.push_back(intervalSeries(rateText(rate) + " worst device", style, true, rows,
                                             rate, &ScalingRow::worstP999, 0.06));
        ++style;
    }
    p.panels = {total, tail};
    return p;
}

/// cursor-steps: steps per locate and per leaf change against N, a series per strategy, with
/// log8(N/M) for reference (root has no per-change series: it descends at every locate).
PlotSpec cursorPlot(const ScalingSetup& setup, const std::vector<CursorRow>& rows) {
    PlotSpec p;
    p.name = "cursor-steps";
    p.title = "Cursor steps against N (" + setup.cursorSpec.toString() +
              ", K^3 lattices, hand-speed walk)";
    PlotPanel perLocate{
        "per locate (log scale)", "objects N", "mean steps per locate", true, true, {}, {}, {}, {}};
    PlotPanel perChange{
        "per leaf change", "objects N", "mean steps per leaf change", true, false, {}, {}, {}, {}};
    for (const std::size_t n : setup.args.cursorObjects) {
        perLocate.xTics.push_back(static_cast<double>(n));
        perChange.xTics.push_back(static_cast<double>(n));
    }
    for (const char* s : {"root", "climb", "links"}) {
        PlotSeries a{s, {}, {}, false, -1}, b{s, {}, {}, false, -1};
        for (const CursorRow& r : rows) {
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
    for (const CursorRow& r : rows) {
        if (r.strategy == std::string("root")) {
            ref.points.emplace_back(r.objects, r.log8NOverM);
        }
    }
    perChange.series.push_back(ref);
    p.panels = {perLocate, perChange};
    return p;
}

/// The scaling section of devices.md: how it was measured, a table per rate, the realtime note.
std::string scalingMarkdown(const ScalingSetup& setup, const ScalingResults& results,
                            const Table& scaling) {
    const DevicesArgs& args = setup.args;
    std::string md =
        "## Load against devices: " + std::to_string(setup.scene.size()) + " objects, " +
        setup.spec.toString() + ", script " + args.script + "\n\n" +
        (args.common.quick
             ? smokeTestHeader(args.common,
                               "how load grows with devices (few counts, one rate), p99.9 load "
                               "(a run of a few hundred ticks has none but its maximum), the "
                               "spread across runs, or the cursor's steps at large N",
                               "design, on p99 (every device: p99 load < 100 % and <= 0.1 % "
                               "deadlines missed)")
             : std::string()) +
        "Every device has its own servo thread over one shared World. Loads in % (wake-up to "
        "force written over the period). " +
        intervalNote(static_cast<std::size_t>(args.common.repeats)) +
        " Load sum: the devices' mean loads added (% of one core). Per device p99.9: the "
        "median device (the middle one of the cell's devices, a typical device) beside the "
        "worst device (the largest of the cell's devices: it grows with the device count by "
        "itself, as a maximum over more samples). " +
        verdictNote(setup.servo.tail) + "\n";
    for (const double rate : args.ratesHz) {
        md += "\n### " + rateText(rate) + "\n\n";
        md += scaling.markdown([&](std::size_t i) { return results.rows[i].rateHz == rate; });
    }
    if (!results.realtimeNote.empty()) {
        md += "\nNote: " + results.realtimeNote + "\n";
    }
    return md;
}

/// The cursor section of devices.md: what the strategies are, and a line per N with the three
/// side by side (rows come in threes: root, climb, links). Empty without cursor rows.
std::string cursorMarkdown(const ScalingSetup& setup, const std::vector<CursorRow>& rows) {
    if (rows.empty()) {
        return {};
    }
    std::string md =
        "\n## Cursor steps against N (" + setup.cursorSpec.toString() +
        ", K^3 lattices of 5 cm cubes, " + std::to_string(setup.args.walkSteps) +
        " steps of a 1 ms hand-speed walk)\n\n"
        "Steps = links followed (parent, child, neighbour) per locate. root: descend from "
        "the root at every locate (no cache); climb: from the cached leaf up to the first "
        "ancestor holding the point and down (the paper's octree without neighbour "
        "links); links: across faces through neighbour links. The paper's claim (2.2.4): "
        "O(M + log8(N/M)) per leaf change without links, O(M) with them.\n\n";
    std::vector<std::vector<std::string>> t;
    for (std::size_t i = 0; i + 2 < rows.size(); i += 3) {
        const CursorRow& root = rows[i];
        const CursorRow& climb = rows[i + 1];
        const CursorRow& links = rows[i + 2];
        t.push_back({std::to_string(root.objects), std::to_string(root.depth),
                     fmt(root.log8NOverM, 2),
                     fmt(1000.0 * double(links.leafChanges) / double(links.locates), 1),
                     fmt(root.stepsPerLocate(), 3), fmt(climb.stepsPerLocate(), 3),
                     fmt(links.stepsPerLocate(), 3), fmt(climb.stepsPerChange(), 2),
                     fmt(links.stepsPerChange(), 2),
                     fmt(root.nsPerLocate, 1) + " / " + fmt(climb.nsPerLocate, 1) + " / " +
                         fmt(links.nsPerLocate, 1)});
    }
    return md + markdownTable({"N", "depth", "log8(N/M)", "leaf changes /1000 locates",
                               "steps/locate root", "climb", "links", "steps/leaf change climb",
                               "links", "ns/locate root / climb / links"},
                              t);
}

/// Writes the CSVs, devices.json, the plots and devices.md into `out`; returns the markdown.
std::string writeScalingFiles(const std::filesystem::path& out, const ScalingSetup& setup,
                              const ScalingResults& results, const std::vector<CursorRow>& cursors,
                              const std::vector<int>& counts, Progress& progress) {
    // Each table declared once, written as CSV and JSON (and markdown).
    const Table scaling = scalingTable(results.rows, setup.args.common.quick);
    const Table perDevice = perDeviceTable(results.perDevice);
    const Table cursor = cursorTable(cursors);
    scaling.writeCsv(out / "devices.csv");
    perDevice.writeCsv(out / "devices-per-device.csv");
    cursor.writeCsv(out / "cursor.csv");
    writeText(out / "devices.json",
              scalingJson(setup, results, scaling, perDevice, cursor).dump(2) + "\n");

    std::vector<std::filesystem::path> plots;
    drawPlotNoting(out, scalingPlot(setup, results.rows, counts), progress, plots);
    if (!cursors.empty()) {
        drawPlotNoting(out, cursorPlot(setup, cursors), progress, plots);
    }

    std::string md = scalingMarkdown(setup, results, scaling) + cursorMarkdown(setup, cursors);
    md += "\nFiles: " + (out / "devices.csv").string() + ", " +
          (out / "devices-per-device.csv").string() + ", " + (out / "cursor.csv").string() + ", " +
          (out / "devices.json").string() + ", " + (out / "devices.md").string();
    for (const auto& p : plots) {
        md += ", " + p.string();
    }
    md += "\n";
    writeText(out / "devices.md", md);
    return md;
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
    const std::vector<int> counts = deviceCounts(args);

    Progress progress("devices", args.ratesHz.size() * counts.size() *
                                         static_cast<std::size_t>(args.common.repeats) +
                                     (args.cursor ? args.cursorObjects.size() : 0));
    progress.show("building " + spec.toString() + " over " + std::to_string(scene.size()) +
                  " objects");
    World world(shared, spec);
    const std::vector<Vec3> starts =
        clearStarts(scene, *world.current().index, *std::max_element(counts.begin(), counts.end()));

    ScalingSetup setup{args, scene, spec, cursorSpec, {}};
    setup.servo.durationS = args.common.durationS;
    setup.servo.repeats = args.common.repeats;
    setup.servo.realtime = args.common.realtime;
    setup.servo.tail = tailFor(args.common.quick);

    ScalingResults results;
    for (const double rate : args.ratesHz) {
        for (const int d : counts) {
            measureCell(world, setup, starts, rate, d, results, progress);
        }
    }
    const std::vector<CursorRow> cursors = measureCursors(setup, progress);

    const std::string md = writeScalingFiles(out, setup, results, cursors, counts, progress);
    progress.finish(); // the results never share a line with the bar
    std::cout << md << std::flush;
    return 0;
}

} // namespace hapto::experiments
