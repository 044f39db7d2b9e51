// The growing-scene sweep behind `hapto experiment paper1` and `paper2`.

#include "hapto/experiments/Sweep.h"

#include "hapto/experiments/Plot.h"
#include "hapto/experiments/Table.h"

#include "hapto/runtime/World.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>

namespace hapto::experiments {
namespace {

/// What an index holds: every box and sphere, and every mesh triangle (not the mesh object).
std::size_t indexedItems(const Scene& scene) {
    std::size_t meshes = 0;
    for (const SceneObject& o : scene.objects()) {
        meshes += o.shape == Shape::Mesh;
    }
    return scene.size() - meshes + scene.triangleCount();
}

/// Objects the script plans against: those within this distance of the start (m). The free
/// walk stays within 8 cm of its start, touch and slide use the nearest surface.
constexpr double kPlanRadiusM = 0.15;

/// Probe ticks per (renderer, rate, scene).
constexpr int kProbeTicks = 8;

struct Key {
    std::string renderer;
    double rateHz;
    bool operator<(const Key& o) const {
        return renderer != o.renderer ? renderer < o.renderer : rateHz < o.rateHz;
    }
};

/// What a sweep carries from one size to the next, and the rows so far.
struct SweepState {
    std::map<Key, bool> active;                   ///< (renderer, rate) pairs still growing.
    std::map<std::string, double> bytesPerObject; ///< Index memory per object at the last size.
    std::set<Key> unstableHere; ///< Pairs with an unstable cell at the current size.
    std::vector<SweepRow> rows; ///< In measurement order.
};

/// One scene of a step, ready to measure: each condition's start (checked clear) and the
/// objects near it that the condition's script plans against.
struct PreparedScene {
    Scene scene;
    std::vector<Vec3> starts;      ///< Per condition (m, world).
    std::vector<Scene> planScenes; ///< Per condition.
};

/// Generates the scene and its starts; throws std::logic_error when a start is not clear.
PreparedScene prepareScene(const SweepScene& sc, const SweepStep& step, const SweepOptions& options,
                           Progress& progress) {
    progress.show("generating " + std::to_string(step.objects) + " objects");
    PreparedScene p{sc.make(), {}, {}};
    for (const Condition c : kConditions) {
        p.starts.push_back(sc.start(p.scene, c));
        requireClear(p.scene, p.starts.back(), 0.0, options.experiment + " start");
        const Vec3 r(kPlanRadiusM);
        p.planScenes.push_back(sceneNear(p.scene, {p.starts.back() - r, p.starts.back() + r}));
    }
    return p;
}

/// The rates at which `r` is measured at `step`: those at which it still grows, and every rate
/// when the step names it in mustRun; the cells at the other rates count as done on `progress`.
std::vector<double> ratesNeeded(SweepState& state, const SweepStep& step, const SweepRenderer& r,
                                const SweepOptions& options, Progress& progress) {
    const bool must =
        std::find(step.mustRun.begin(), step.mustRun.end(), r.name) != step.mustRun.end();
    std::vector<double> rates;
    for (const double rate : options.ratesHz) {
        if (state.active[{r.name, rate}] || must) {
            rates.push_back(rate);
        } else {
            progress.advance(step.scenes.size() * std::size(kConditions), "");
        }
    }
    return rates;
}

/// Records the three cells of `base`'s renderer at `rate` as skipped for `note` (so unstable).
void skipCells(SweepState& state, const SweepRow& base, double rate, const std::string& note,
               Progress& progress) {
    for (const Condition c : kConditions) {
        SweepRow row = base;
        row.rateHz = rate;
        row.condition = c;
        row.skipped = true;
        row.note = note;
        state.rows.push_back(row);
    }
    state.unstableHere.insert({base.renderer, rate});
    progress.advance(std::size(kConditions), base.renderer);
}

/// Measures one cell over `world`: `repeats` timed runs of one hand from the condition's start,
/// concluded into the row. [control]
void measureCell(SweepState& state, World& world, const PreparedScene& p, const SweepRow& base,
                 double rate, std::size_t ci, const SweepOptions& options, Progress& progress) {
    const Condition c = kConditions[ci];
    SweepRow row = base;
    row.rateHz = rate;
    row.condition = c;
    progress.show(base.renderer + " " + std::to_string(p.scene.size()) + " " +
                  std::string(conditionName(c)) + " " + rateText(rate));
    HandPlan hand{simHand("hand", rate, conditionScript(c), 1, p.starts[ci]), &p.planScenes[ci]};
    for (int k = 0; k < options.servo.repeats; ++k) {
        const SessionResult s = runSession(world, {hand}, options.servo);
        row.runs.push_back(figuresOf(s.report.devices.at(0), options.servo.tail));
        row.reachedPhase = row.reachedPhase && s.reached.at(0);
    }
    concludeRow(row);
    if (!row.stable(options.verdict)) {
        state.unstableHere.insert({base.renderer, rate});
    }
    state.rows.push_back(std::move(row));
    progress.advance(1, base.renderer);
}

/// Measures renderer `r` over one prepared scene at `rates`: the memory guard, the index build,
/// the probe (a rate whose probed tick overruns is skipped), then every condition. [control]
void measureRenderer(SweepState& state, const PreparedScene& p, const SweepScene& sc,
                     const SweepStep& step, const SweepRenderer& r,
                     const std::vector<double>& rates, const SweepOptions& options,
                     Progress& progress) {
    const Scene& scene = p.scene;
    SweepRow base;
    base.renderer = r.name;
    base.index = r.spec.toString();
    base.size = step.size;
    base.objects = indexedItems(scene);
    base.seed = sc.seed;
    const auto skipAll = [&](const std::string& note) {
        for (const double rate : rates) {
            skipCells(state, base, rate, note, progress);
        }
    };
    // Memory guard, from the previous size of this renderer.
    if (const auto it = state.bytesPerObject.find(r.name); it != state.bytesPerObject.end()) {
        const double mb = it->second * static_cast<double>(scene.size()) / 1e6;
        if (mb > options.maxIndexMb) {
            skipAll("index would take about " + fmt(mb, 0) +
                    " MB (extrapolated), over --max-index-mb");
            return;
        }
    }
    progress.show("building " + base.index + " over " + std::to_string(scene.size()) + " objects");
    std::unique_ptr<World> world;
    try {
        // The build itself refuses past the limit too (its own estimate).
        world = std::make_unique<World>(scene, r.spec.withMaxMegabytes(static_cast<std::uint64_t>(
                                                   std::ceil(options.maxIndexMb))));
    } catch (const std::exception& e) {
        skipAll(std::string("index build failed: ") + e.what());
        return;
    }
    const IndexStats& stats = world->current().index->stats();
    base.buildS = stats.buildSeconds;
    base.indexMb = static_cast<double>(stats.bytes) / 1e6;
    state.bytesPerObject[r.name] =
        static_cast<double>(stats.bytes) / std::max(1.0, double(scene.size()));
    const double probeS = probeTickSeconds(*world, p.starts[0], kProbeTicks);
    base.probeTickUs = probeS * 1e6;
    for (const double rate : rates) {
        if (probeS * rate > options.skipTickPeriods) {
            skipCells(state, base, rate,
                      "probe: one tick takes " + fmt(probeS * 1e6, 0) + " us, " +
                          fmt(probeS * rate, 1) + " periods",
                      progress);
            continue;
        }
        for (std::size_t ci = 0; ci < std::size(kConditions); ++ci) {
            measureCell(state, *world, p, base, rate, ci, options, progress);
        }
    }
}

} // namespace

MedianInterval SweepRow::interval(double LoadFigures::*figure) const {
    std::vector<double> values;
    for (const LoadFigures& f : runs) {
        values.push_back(f.*figure);
    }
    return medianInterval(std::move(values));
}

Verdict sweepVerdict(bool quick, bool verdictGiven, Verdict given) {
    return quick && !verdictGiven ? Verdict::Load : given;
}

std::string smokeTestHeader(const CommonArgs& common, const std::string& cannotJudge,
                            const std::string& verdict) {
    return "> **Smoke test (--quick)**: " + std::to_string(common.repeats) + " run(s) of " +
           fmt(common.durationS, 2) +
           " s per cell, small sizes. It shows that the experiment runs and writes its files; "
           "it cannot judge " +
           cannotJudge + ". Verdict in this table: " + verdict +
           ". Run without --quick for results.\n\n";
}

std::string sweepSmokeHeader(const CommonArgs& common, Verdict verdict, std::size_t largest,
                             const std::string& limits) {
    if (!common.quick) {
        return {};
    }
    const std::string which =
        verdict == Verdict::Load
            ? "load (p99 load < 100 %: the renderer's own time against the period, as the "
              "paper judged its renderers; deadlines missed are reported, not counted)"
            : "design (p99 load < 100 % and <= 0.1 % deadlines missed)";
    return smokeTestHeader(common,
                           limits + " (it stops at " + std::to_string(largest) +
                               " objects, below the sizes where renderers part), p99.9 load (a run "
                               "of a few hundred ticks has no p99.9 but its maximum) or the "
                               "spread across runs",
                           which);
}

std::string rateText(double rateHz) {
    char text[32];
    if (rateHz >= 1000.0) {
        std::snprintf(text, sizeof text, "%g kHz", rateHz / 1000.0);
    } else {
        std::snprintf(text, sizeof text, "%g Hz", rateHz);
    }
    return text;
}

std::vector<SweepRow> runSweep(const std::vector<SweepRenderer>& renderers,
                               const std::vector<SweepStep>& steps, const SweepOptions& options,
                               Progress& progress) {
    SweepState state;
    for (const SweepRenderer& r : renderers) {
        for (const double rate : options.ratesHz) {
            state.active[{r.name, rate}] = true;
        }
    }
    for (const SweepStep& step : steps) {
        // Per renderer, the rates it is measured at here.
        std::vector<std::vector<double>> rates;
        bool any = false;
        for (const SweepRenderer& r : renderers) {
            rates.push_back(ratesNeeded(state, step, r, options, progress));
            any = any || !rates.back().empty();
        }
        if (!any) {
            continue;
        }
        state.unstableHere.clear();
        for (const SweepScene& sc : step.scenes) {
            const PreparedScene p = prepareScene(sc, step, options, progress);
            for (std::size_t i = 0; i < renderers.size(); ++i) {
                if (!rates[i].empty()) {
                    measureRenderer(state, p, sc, step, renderers[i], rates[i], options, progress);
                }
            }
        }
        for (const Key& k : state.unstableHere) {
            state.active[k] = false;
        }
    }
    return state.rows;
}

void concludeRow(SweepRow& row) {
    row.median = medianOf(row.runs);
    const auto idle = std::find_if(row.runs.begin(), row.runs.end(),
                                   [](const LoadFigures& f) { return f.ticks == 0; });
    if (row.runs.empty() || idle != row.runs.end()) {
        // Nothing was measured: not a load of zero. Skipped, so it is neither stable nor a limit.
        row.skipped = true;
        row.note = row.runs.empty() ? "no run was made"
                                    : "no tick was measured in run " +
                                          std::to_string(idle - row.runs.begin() + 1) + " of " +
                                          std::to_string(row.runs.size()) +
                                          ": the servo thread did not run in the timed window "
                                          "(an overloaded machine?)";
    } else if (!row.reachedPhase) {
        row.note = "the hand did not reach its " + std::string(conditionName(row.condition)) +
                   " phase before timing";
    } else if (!row.median.fault.empty()) {
        row.note = "fault: " + row.median.fault;
    }
}

std::vector<SweepLimit> sweepLimits(const std::vector<SweepRenderer>& renderers,
                                    const std::vector<double>& ratesHz,
                                    const std::vector<SweepRow>& rows, Verdict verdict) {
    std::vector<SweepLimit> limits;
    for (const SweepRenderer& r : renderers) {
        for (const double rate : ratesHz) {
            SweepLimit l;
            l.renderer = r.name;
            l.rateHz = rate;
            // Sizes measured, ascending, and per size: per scene seed, all cells stable?
            std::map<std::size_t, std::pair<int, std::map<std::uint64_t, bool>>> bySize;
            for (const SweepRow& row : rows) {
                if (row.renderer == r.name && row.rateHz == rate) {
                    auto& [size, scenes] = bySize[row.objects];
                    size = row.size;
                    auto [it, fresh] = scenes.try_emplace(row.seed, true);
                    it->second = it->second && row.stable(verdict);
                }
            }
            for (const auto& [objects, entry] : bySize) {
                const auto& [size, scenes] = entry;
                l.largestMeasuredObjects = objects;
                int stableScenes = 0;
                for (const auto& [seed, ok] : scenes) {
                    stableScenes += ok ? 1 : 0;
                }
                if (l.firstUnstableObjects) {
                    continue;
                }
                if (stableScenes == static_cast<int>(scenes.size())) {
                    l.maxStableObjects = objects;
                    l.maxStableSize = size;
                } else {
                    l.firstUnstableObjects = objects;
                    l.firstUnstableSize = size;
                    l.scenesStableAtFirstUnstable = stableScenes;
                    l.scenesAtFirstUnstable = static_cast<int>(scenes.size());
                }
            }
            limits.push_back(l);
        }
    }
    return limits;
}

namespace {

using Int = std::int64_t;

/// The figures of one run, as columns (the CSV's median columns and the JSON's runs).
const std::vector<Column> kFigureColumns = {
    {"ticks", ""},          {"load_mean_pct", "%"},  {"load_p50_pct", "%"},
    {"load_p99_pct", "%"},  {"load_p999_pct", "%"},  {"load_max_pct", "%"},
    {"tick_p50_ns", "ns"},  {"tick_p999_ns", "ns"},  {"tick_max_ns", "ns"},
    {"missed", ""},         {"missed_pct", "%"},     {"late_wakeups", ""},
    {"contact_pct", "%"},   {"candidates_mean", ""}, {"locate_steps_mean", ""},
    {"late_p999_us", "us"}, {"late_max_us", "us"},
};

std::vector<Cell> figureCells(const LoadFigures& m) {
    return {m.ticks,      m.meanPct,     m.p50Pct,     m.p99Pct,         m.p999Pct,
            m.maxPct,     m.tickNsP50,   m.tickNsP999, m.tickNsMax,      m.missed,
            m.missedPct,  m.lateWakeups, m.contactPct, m.candidatesMean, m.locateStepsMean,
            m.lateP999Us, m.lateMaxUs};
}

/// The rows as one table: CSV and JSON share its columns.
Table sweepTable(const std::vector<SweepRow>& rows, const std::string& sizeColumn) {
    std::vector<Column> columns = {{"renderer", ""},  {"index", ""},   {"rate_hz", "Hz"},
                                   {sizeColumn, ""},  {"objects", ""}, {"seed", ""},
                                   {"condition", ""}, {"script", ""},  {"repeats", ""}};
    columns.insert(columns.end(), kFigureColumns.begin(), kFigureColumns.end());
    for (const Column& c : std::vector<Column>{{"load_p50_lo_pct", "%"},
                                               {"load_p50_hi_pct", "%"},
                                               {"load_p999_lo_pct", "%"},
                                               {"load_p999_hi_pct", "%"},
                                               {"interval_coverage", ""},
                                               {"stable", ""},
                                               {"load_stable", ""},
                                               {"skipped", ""},
                                               {"reached_phase", ""},
                                               {"realtime", ""},
                                               {"index_build_s", "s"},
                                               {"index_mb", "MB"},
                                               {"probe_tick_us", "us"},
                                               {"note", ""}}) {
        columns.push_back(c);
    }
    Table table(std::move(columns));
    for (const SweepRow& r : rows) {
        std::vector<Cell> cells = {r.renderer,
                                   r.index,
                                   r.rateHz,
                                   Int(r.size),
                                   Int(r.objects),
                                   Int(r.seed),
                                   std::string(conditionName(r.condition)),
                                   std::string(conditionScript(r.condition)),
                                   Int(r.runs.size())};
        for (Cell& c : figureCells(r.median)) {
            cells.push_back(std::move(c));
        }
        const MedianInterval p50 = r.interval(&LoadFigures::p50Pct);
        const MedianInterval p999 = r.interval(&LoadFigures::p999Pct);
        for (Cell c :
             std::vector<Cell>{p50.lo, p50.hi, p999.lo, p999.hi, p999.coverage, r.stable(),
                               r.loadStable(), r.skipped, r.reachedPhase, r.median.realtime,
                               r.buildS, r.indexMb, r.probeTickUs, r.note}) {
            cells.push_back(std::move(c));
        }
        table.add(std::move(cells));
    }
    return table;
}

} // namespace

void writeSweepCsv(const std::filesystem::path& path, const std::vector<SweepRow>& rows,
                   const std::string& sizeColumn) {
    sweepTable(rows, sizeColumn).writeCsv(path);
}

namespace {

Json optionalJson(const auto& v) {
    return v ? Json(*v) : Json(nullptr);
}

} // namespace

Json sweepJson(const std::vector<SweepRenderer>& renderers, const std::vector<double>& ratesHz,
               const std::vector<SweepRow>& rows, Verdict verdict, const std::string& sizeColumn) {
    Json j;
    const Table table = sweepTable(rows, sizeColumn);
    Json jr = table.json();
    for (std::size_t i = 0; i < rows.size(); ++i) {
        std::vector<Column> columns = kFigureColumns;
        columns.insert(columns.end(),
                       {{"realtime", ""}, {"stable", ""}, {"load_stable", ""}, {"fault", ""}});
        Table runs(std::move(columns));
        for (const LoadFigures& f : rows[i].runs) {
            std::vector<Cell> cells = figureCells(f);
            cells.insert(cells.end(), {f.realtime, f.stable(), f.loadStable(), f.fault});
            runs.add(std::move(cells));
        }
        jr[i]["runs"] = runs.json();
    }
    j["rows"] = jr;
    j["verdict"] = verdictName(verdict);
    const auto limitsJson = [&](Verdict v) {
        Json jl = Json::array();
        for (const SweepLimit& l : sweepLimits(renderers, ratesHz, rows, v)) {
            Json e;
            e["renderer"] = l.renderer;
            e["rate_hz"] = l.rateHz;
            e["max_stable_objects"] = optionalJson(l.maxStableObjects);
            e["max_stable_" + sizeColumn] = optionalJson(l.maxStableSize);
            e["first_unstable_objects"] = optionalJson(l.firstUnstableObjects);
            e["first_unstable_" + sizeColumn] = optionalJson(l.firstUnstableSize);
            e["scenes_stable_at_first_unstable"] = l.scenesStableAtFirstUnstable;
            e["scenes_at_first_unstable"] = l.scenesAtFirstUnstable;
            e["largest_measured_objects"] = l.largestMeasuredObjects;
            jl.push_back(e);
        }
        return jl;
    };
    j["limits"] = limitsJson(verdict);
    j["limits_by_verdict"] = {{"design", limitsJson(Verdict::Design)},
                              {"load", limitsJson(Verdict::Load)}};
    return j;
}

std::string limitsTable(const std::vector<SweepRenderer>& renderers,
                        const std::vector<double>& ratesHz, const std::vector<SweepRow>& rows,
                        Verdict verdict, const std::string& sizeName) {
    const std::vector<SweepLimit> design = sweepLimits(renderers, ratesHz, rows, Verdict::Design);
    const std::vector<SweepLimit> load = sweepLimits(renderers, ratesHz, rows, Verdict::Load);
    const std::vector<SweepLimit>& chosen = verdict == Verdict::Design ? design : load;
    std::vector<std::vector<std::string>> table;
    for (std::size_t i = 0; i < chosen.size(); ++i) {
        const SweepLimit& l = chosen[i];
        std::string paper;
        for (const SweepRenderer& r : renderers) {
            if (r.name == l.renderer) {
                paper = r.paperResult;
            }
        }
        const auto objects = [&](const std::optional<std::size_t>& n,
                                 const std::optional<int>& size) {
            if (!n) {
                return std::string("none");
            }
            return static_cast<std::size_t>(*size) == *n
                       ? std::to_string(*n)
                       : std::to_string(*n) + " (" + sizeName + " " + std::to_string(*size) + ")";
        };
        std::string firstUnstable = "none up to " + std::to_string(l.largestMeasuredObjects);
        if (l.firstUnstableObjects) {
            firstUnstable = objects(l.firstUnstableObjects, l.firstUnstableSize);
            if (l.scenesAtFirstUnstable > 1) {
                firstUnstable += ", " + std::to_string(l.scenesStableAtFirstUnstable) + "/" +
                                 std::to_string(l.scenesAtFirstUnstable) + " scenes stable";
            }
        }
        table.push_back({l.renderer, rateText(l.rateHz),
                         objects(design[i].maxStableObjects, design[i].maxStableSize),
                         objects(load[i].maxStableObjects, load[i].maxStableSize), firstUnstable,
                         paper});
    }
    return markdownTable({"renderer", "rate", "max stable (DESIGN: p99.9 < 100 %, <= 0.1 % missed)",
                          "max stable (load: p99.9 < 100 %)",
                          "first unstable (" + std::string(verdictName(verdict)) + " verdict)",
                          "paper (PHANToM, 1 kHz, PIII 800 MHz)"},
                         table);
}

std::string platformNote(const std::vector<SweepRow>& rows, Verdict verdict) {
    std::vector<double> late, missed;
    std::size_t measured = 0, fifo = 0, loadOnly = 0;
    Tail tail = Tail::P999;
    for (const SweepRow& r : rows) {
        if (r.skipped) {
            continue;
        }
        ++measured;
        tail = r.median.tail;
        fifo += r.median.realtime ? 1 : 0;
        late.push_back(r.median.lateP999Us);
        missed.push_back(r.median.missedPct);
        loadOnly += r.loadStable() && !r.stable() ? 1 : 0;
    }
    return "Sweep verdict: " + std::string(verdictName(verdict)) +
           (verdict == Verdict::Design ? " (p99.9 load < 100 % and <= 0.1 % deadlines missed)"
                                       : " (p99.9 load < 100 %; missed deadlines reported, not "
                                         "counted)") +
           ". SCHED_FIFO granted in " + std::to_string(fifo) + " of " + std::to_string(measured) +
           " measured cells. Wake-up lateness p99.9, median over "
           "cells: " +
           fmt(median(late), 0) +
           " us; deadlines missed, median over cells: " + fmt(median(missed), 2) +
           " %; cells within load but over 0.1 % missed: " + std::to_string(loadOnly) + ". " +
           verdictNote(tail) + "\n";
}

std::string loadCell(const SweepRow& row) {
    if (row.skipped) {
        return "skipped";
    }
    const LoadFigures& m = row.median;
    std::string cell =
        fmt(m.p50Pct, m.p50Pct < 10 ? 2 : 1) + " / " + fmt(m.p999Pct, m.p999Pct < 10 ? 2 : 1);
    if (row.runs.size() > 1) { // the p99.9's interval across repeats
        const MedianInterval p999 = row.interval(&LoadFigures::p999Pct);
        cell += " [" + fmt(p999.lo, p999.lo < 10 ? 2 : 1) + ", " +
                fmt(p999.hi, p999.hi < 10 ? 2 : 1) + "]";
    }
    cell += " / " + fmt(m.maxPct, m.maxPct < 10 ? 2 : 0);
    if (!row.loadStable()) {
        cell += " UNSTABLE (load)";
    } else if (!row.stable()) {
        cell += " UNSTABLE (" + fmt(m.missedPct, 1) + "% missed)";
    }
    if (!row.reachedPhase) {
        cell += " (no contact)";
    }
    return cell;
}

const SweepRow* findSweepRow(const std::vector<SweepRow>& rows, const std::string& renderer,
                             double rateHz, int size, std::uint64_t seed, Condition condition) {
    for (const SweepRow& row : rows) {
        if (row.renderer == renderer && row.rateHz == rateHz && row.size == size &&
            row.seed == seed && row.condition == condition) {
            return &row;
        }
    }
    return nullptr;
}

std::string rendererTables(const std::vector<SweepRenderer>& renderers, double rateHz,
                           const std::vector<std::string>& header, const std::string& suffix,
                           const RendererLines& linesOf) {
    std::string md;
    for (const SweepRenderer& r : renderers) {
        md += "\n### " + r.name + " (" + r.spec.toString() + "), " + rateText(rateHz) + suffix +
              "\n\n";
        md += markdownTable(header, linesOf(r, rateHz));
    }
    return md;
}

std::string loadNote(const CommonArgs& common, Tail tail, const std::string& figures,
                     const std::string& per) {
    return "Load = wake-up to force written, % of the servo period" + figures + " median of " +
           std::to_string(common.repeats) + " run(s) of " + fmt(common.durationS, 2) + " s" + per +
           "; [lo, hi] after p99.9: its interval across the runs. " +
           intervalNote(static_cast<std::size_t>(common.repeats)) +
           " UNSTABLE: " + std::string(tailName(tail)) + " >= 100 % or > 0.1 % deadlines missed.";
}

PlotSpec sweepPlot(const std::string& experiment, const std::vector<SweepRenderer>& renderers,
                   double rateHz, const std::vector<SweepRow>& rows, Verdict verdict) {
    PlotSpec spec;
    char name[64];
    std::snprintf(name, sizeof name, "%s-load-%gHz", experiment.c_str(), rateHz);
    spec.name = name;
    spec.title = experiment + ": haptic load against objects, " + rateText(rateHz) +
                 ", p99.9 solid with its interval, p50 dashed (medians over the runs" +
                 (experiment == "paper2" ? std::string(" of every scene)") : std::string(")"));
    spec.shareY = true; // the three conditions side by side on one scale
    spec.unstableTitle = "unstable (" + std::string(verdictName(verdict)) + " verdict)";
    for (const Condition c : kConditions) {
        PlotPanel panel;
        panel.title = std::string(conditionName(c));
        panel.xLabel = "objects";
        panel.yLabel = "load (% of the period)";
        panel.logX = true;
        panel.logY = true;
        panel.limitY = 100.0;
        panel.limitTitle = "100 % (one period)";
        std::set<std::size_t> sizes;
        for (std::size_t k = 0; k < renderers.size(); ++k) {
            const SweepRenderer& r = renderers[k];
            // Per size: the loads over its scenes, and whether any of its cells was unstable.
            std::map<std::size_t, std::vector<double>> p999, p50;
            std::map<std::size_t, bool> unstable;
            for (const SweepRow& row : rows) {
                if (row.renderer == r.name && row.rateHz == rateHz && row.condition == c &&
                    !row.skipped) {
                    // Every run of every scene (a row without runs: its medians).
                    const std::vector<LoadFigures> runs =
                        row.runs.empty() ? std::vector<LoadFigures>{row.median} : row.runs;
                    for (const LoadFigures& f : runs) {
                        p999[row.objects].push_back(f.p999Pct);
                        p50[row.objects].push_back(f.p50Pct);
                    }
                    unstable[row.objects] = unstable[row.objects] || !row.stable(verdict);
                    sizes.insert(row.objects);
                }
            }
            PlotSeries tail{r.name + " p99.9", {}, {}, false, static_cast<int>(k) + 1};
            PlotSeries mid{r.name + " p50", {}, {}, true, static_cast<int>(k) + 1};
            for (const auto& [n, loads] : p999) {
                const MedianInterval t = medianInterval(loads);
                tail.points.emplace_back(static_cast<double>(n), t.median);
                tail.errors.emplace_back(t.lo, t.hi);
                tail.unstable.push_back(unstable[n]);
                mid.points.emplace_back(static_cast<double>(n), median(p50[n]));
            }
            panel.series.push_back(std::move(tail));
            panel.series.push_back(std::move(mid));
        }
        panel.xTics.assign(sizes.begin(), sizes.end());
        spec.panels.push_back(std::move(panel));
    }
    return spec;
}

void drawPlotNoting(const std::filesystem::path& dir, const PlotSpec& spec, Progress& progress,
                    std::vector<std::filesystem::path>& files) {
    const PlotResult pr = drawPlot(dir, spec);
    if (!pr.problem.empty()) {
        progress.note("hapto experiment: plot skipped: " + pr.problem);
    }
    files.insert(files.end(), pr.files.begin(), pr.files.end());
}

std::vector<std::filesystem::path> plotSweep(const std::filesystem::path& dir,
                                             const std::string& experiment,
                                             const std::vector<SweepRenderer>& renderers,
                                             const std::vector<double>& ratesHz,
                                             const std::vector<SweepRow>& rows, Verdict verdict,
                                             Progress& progress, const std::string& caption) {
    std::vector<std::filesystem::path> files;
    for (const double rate : ratesHz) {
        PlotSpec spec = sweepPlot(experiment, renderers, rate, rows, verdict);
        spec.caption = caption;
        drawPlotNoting(dir, spec, progress, files);
    }
    return files;
}

std::string repeatsCaption(const CommonArgs& common) {
    const MedianInterval m =
        medianInterval(std::vector<double>(static_cast<std::size_t>(common.repeats), 0.0));
    char coverage[32];
    std::snprintf(coverage, sizeof coverage, "%.4g %%", 100.0 * m.coverage);
    const std::string runs = std::to_string(common.repeats) + " run(s) of " +
                             fmt(common.durationS, 2) + " s per cell" +
                             (common.quick ? " (--quick: a smoke test)" : "");
    if (common.repeats < 2) {
        return runs + "; one run per point: no interval";
    }
    return runs + "; points: medians over the runs; bars: order-statistic interval of the " +
           "median, coverage " + coverage;
}

std::vector<std::filesystem::path>
writeSweepFiles(const std::filesystem::path& out, const std::string& name, Json options,
                const CommonArgs& common, double maxIndexMb,
                const std::vector<SweepRenderer>& renderers, const std::vector<double>& ratesHz,
                const std::vector<SweepRow>& rows, Verdict verdict, const std::string& sizeColumn,
                Progress& progress) {
    writeSweepCsv(out / (name + ".csv"), rows, sizeColumn);
    options["rates_hz"] = ratesHz;
    options["duration_s"] = common.durationS;
    options["repeats"] = common.repeats;
    options["realtime_requested"] = common.realtime;
    options["quick"] = common.quick;
    options["max_index_mb"] = maxIndexMb;
    options["verdict"] = verdictName(verdict);
    options["verdict_percentile"] = tailName(tailFor(common.quick));
    Json j;
    j["experiment"] = name;
    j["machine"] = machineJson();
    j["options"] = std::move(options);
    const Json body = sweepJson(renderers, ratesHz, rows, verdict, sizeColumn);
    for (const char* key : {"verdict", "rows", "limits", "limits_by_verdict"}) {
        j[key] = body[key];
    }
    writeText(out / (name + ".json"), j.dump(2) + "\n");
    return plotSweep(out, name, renderers, ratesHz, rows, verdict, progress,
                     repeatsCaption(common));
}

void finishSweepReport(const std::filesystem::path& out, const std::string& name,
                       std::string markdown, const std::vector<std::filesystem::path>& plots) {
    markdown +=
        "\nFiles: " + (out / (name + ".csv")).string() + ", " + (out / (name + ".json")).string();
    for (const auto& p : plots) {
        markdown += ", " + p.string();
    }
    markdown += "\n";
    writeText(out / (name + ".md"), markdown);
    std::cout << markdown << std::flush;
}

} // namespace hapto::experiments
