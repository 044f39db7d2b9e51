// `hapto experiment grasp`: the one-factor-at-a-time sweep of GraspCell, its table, figures and
// report (design note in GraspExperiment.h).

#include "hapto/experiments/GraspExperiment.h"

#include "hapto/experiments/Plot.h"
#include "hapto/experiments/Progress.h"
#include "hapto/experiments/Stats.h"
#include "hapto/experiments/Sweep.h"
#include "hapto/experiments/Table.h"
#include "hapto/experiments/TickBench.h"
#include "hapto/io/InputError.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace hapto::experiments {
namespace {

/// A factor swept: its name, its axis label, the cell's field it sets, the list it takes.
struct Factor {
    const char* name;
    const char* option; // the command's option for its list
    const char* axis;
    double GraspCellSpec::*field;
    std::vector<double> GraspArgs::*values;
};

/// The factors swept, in table order.
constexpr Factor kFactors[] = {
    {"squeeze", "--squeezes", "squeeze force, each hand (N)", &GraspCellSpec::squeezeN,
     &GraspArgs::squeezesN},
    {"mass", "--masses", "mass (kg)", &GraspCellSpec::massKg, &GraspArgs::massesKg},
    {"stiffness", "--stiffnesses", "surface stiffness (N/m)", &GraspCellSpec::stiffnessNPerM,
     &GraspArgs::stiffnessesNPerM},
    {"servo rate", "--rates", "servo rate (Hz)", &GraspCellSpec::servoRateHz, &GraspArgs::ratesHz},
};

bool sameCell(const GraspCellSpec& a, const GraspCellSpec& b) {
    return a.squeezeN == b.squeezeN && a.massKg == b.massKg &&
           a.stiffnessNPerM == b.stiffnessNPerM && a.servoRateHz == b.servoRateHz;
}

/// One distinct cell: its spec, the first run's figures, whether every run agreed, and the
/// step's cost over the runs (us).
struct CellRun {
    GraspCellSpec spec;
    GraspCellResult result;
    bool repeatable = true;
    MedianInterval stepP50Us, stepP999Us;
};

/// One table row: a factor and the cell it points at.
struct RowRef {
    const Factor* factor;
    std::size_t cell;
};

/// The distinct cells of the sweep and the rows that show them; refuses (InputError) a value a
/// cell cannot run, naming its factor.
std::vector<RowRef> planCells(const GraspArgs& a, std::vector<CellRun>& cells) {
    std::vector<RowRef> rows;
    for (const Factor& f : kFactors) {
        for (const double v : a.*f.values) {
            GraspCellSpec spec = a.base;
            spec.*f.field = v;
            try {
                checkGraspCellSpec(spec);
            } catch (const std::invalid_argument& e) {
                throw InputError("experiment grasp: " + std::string(f.option) + " " + csvNumber(v) +
                                 ": " + e.what());
            }
            std::size_t k = 0;
            while (k < cells.size() && !sameCell(cells[k].spec, spec)) {
                ++k;
            }
            if (k == cells.size()) {
                cells.push_back({spec, {}, true, {}, {}});
            }
            rows.push_back({&f, k});
        }
    }
    return rows;
}

/// Runs a cell `repeats` times: the first run's figures, the others checked against them.
void runCell(CellRun& cell, int repeats) {
    std::vector<double> p50, p999;
    for (int r = 0; r < repeats; ++r) {
        GraspCellResult res = runGraspCell(cell.spec);
        const Quantiles q = quantilesOf(res.stepCpuNs);
        p50.push_back(q.p50 / 1000.0);
        p999.push_back(q.p999 / 1000.0);
        if (r == 0) {
            cell.result = std::move(res);
        } else if (!sameGraspFigures(cell.result, res)) {
            cell.repeatable = false;
        }
    }
    cell.stepP50Us = medianInterval(p50);
    cell.stepP999Us = medianInterval(p999);
}

bool expectHold(const GraspCellSpec& s) {
    return graspHoldMargin(s) >= 1.0;
}

Table graspTable() {
    return Table({
        {"factor", "", -1, "", ColumnIn::Data},
        {"squeeze_n", "N", 2},
        {"mass_kg", "kg", 3},
        {"stiffness_n_per_m", "N/m", 0},
        {"servo_rate_hz", "Hz", 0},
        {"squeeze_felt_n", "N", 3, "squeeze felt (N)"},
        {"hold_margin", "", 2, "mu_s(F1+F2)/mg"},
        {"expected", "", -1, "expected"},
        {"held", "", -1, "held"},
        {"verdict", "", -1, "verdict"},
        {"slip_max_mm", "mm", 3, "slip max (mm)"},
        {"slip_final_mm", "mm", 3, "slip final (mm)"},
        {"slip_elastic_mm", "mm", 3, "mg/2k (mm)"},
        {"slip_onset_s", "s", 3, "slip > 1 mm at (s)"},
        {"lift_mm", "mm", 1, "lift (mm)"},
        {"penetration_mm", "mm", -1, "deepest pen. (mm)"},
        {"energy_gain_j", "J", -1, "energy gain (J)"},
        {"force_error_median_pct", "%", 2, "force err. med (%)"},
        {"force_error_worst_pct", "%", 1, "force err. worst (%)"},
        {"coupling_a", "", 3, "", ColumnIn::Data},
        {"step_p50_us", "us", 2, "", ColumnIn::Data},
        {"step_p50_lo_us", "us", 2, "", ColumnIn::Data},
        {"step_p50_hi_us", "us", 2, "", ColumnIn::Data},
        {"step_p999_us", "us", 1, "", ColumnIn::Data},
        {"step_p999_lo_us", "us", 1, "", ColumnIn::Data},
        {"step_p999_hi_us", "us", 1, "", ColumnIn::Data},
        {"step_cpu", "", -1, "step CPU p50 / p99.9 (us)", ColumnIn::Markdown},
        {"repeatable", "", -1, "", ColumnIn::Data},
        {"stable", "", -1, "", ColumnIn::Data},
        {"samples", "", -1, "", ColumnIn::Data},
    });
}

/// sum k h^2 / m of the two hands at the dynamics step h: DESIGN's coupling figure (the
/// energy never grows for a <= 1).
double couplingA(const GraspCellSpec& s) {
    const double h = 1.0 / s.dynamicsRateHz;
    return 2.0 * s.stiffnessNPerM * h * h / s.massKg;
}

void addRow(Table& t, const Factor& f, const CellRun& c) {
    const GraspCellSpec& s = c.spec;
    const GraspCellResult& r = c.result;
    const bool expected = expectHold(s);
    t.add({std::string(f.name),
           s.squeezeN,
           s.massKg,
           s.stiffnessNPerM,
           s.servoRateHz,
           r.squeezeFeltN,
           graspHoldMargin(s),
           std::string(expected ? "hold" : "slip"),
           std::string(r.grasp.held ? "held" : "dropped"),
           std::string(expected == r.grasp.held ? "agrees" : "DISAGREES"),
           r.grasp.maxSlipM * 1e3,
           r.grasp.finalSlipM * 1e3,
           graspElasticSlipM(s) * 1e3,
           r.slipOnsetS,
           r.liftM * 1e3,
           r.deepestPenetrationM * 1e3,
           r.largestEnergyGainJ,
           r.grasp.forceErrorMedian * 100.0,
           r.grasp.forceErrorWorst * 100.0,
           couplingA(s),
           c.stepP50Us.median,
           c.stepP50Us.lo,
           c.stepP50Us.hi,
           c.stepP999Us.median,
           c.stepP999Us.lo,
           c.stepP999Us.hi,
           intervalText(c.stepP50Us, 2) + " / " + intervalText(c.stepP999Us, 1),
           c.repeatable,
           r.stable,
           static_cast<std::int64_t>(r.grasp.samples)});
}

/// One figure, a panel per factor; `series` gives each panel's lines from its rows.
template <class Series>
PlotSpec graspPlot(const std::string& name, const std::string& title, const std::string& yLabel,
                   bool logY, const std::vector<RowRef>& rows, const std::vector<CellRun>& cells,
                   Series series) {
    PlotSpec spec;
    spec.name = name;
    spec.title = title;
    spec.columns = 2;
    spec.unstableTitle = "held/dropped disagrees with mu_s(F1+F2) >= m g";
    for (const Factor& f : kFactors) {
        PlotPanel p = panel(f.name, f.axis, yLabel);
        p.logX = true;
        p.logY = logY;
        std::vector<const CellRun*> mine;
        for (const RowRef& r : rows) {
            if (r.factor == &f) {
                mine.push_back(&cells[r.cell]);
            }
        }
        p.series = series(f, mine);
        if (!p.series.empty() && !mine.empty()) {
            spec.panels.push_back(std::move(p));
        }
    }
    return spec;
}

/// A line of `value(cell)` against the factor, each point marked when the verdict disagrees.
template <class Value>
PlotSeries line(const std::string& title, const Factor& f, const std::vector<const CellRun*>& cells,
                Value value, bool dashed = false) {
    PlotSeries s;
    s.title = title;
    s.dashed = dashed;
    for (const CellRun* c : cells) {
        s.points.emplace_back(c->spec.*f.field, value(*c));
        s.unstable.push_back(expectHold(c->spec) != c->result.grasp.held);
    }
    return s;
}

std::vector<std::filesystem::path> drawGraspPlots(const std::filesystem::path& out,
                                                  const std::vector<RowRef>& rows,
                                                  const std::vector<CellRun>& cells,
                                                  Progress& progress) {
    std::vector<std::filesystem::path> files;
    const double floorMm = 1e-4; // log axes: a zero slip is drawn at 0.1 um
    drawPlotNoting(
        out,
        graspPlot("grasp-slip", "Grasp: slip of the box against the hands, and its penetration",
                  "mm", true, rows, cells,
                  [&](const Factor& f, const std::vector<const CellRun*>& c) {
                      return std::vector<PlotSeries>{
                          line("max slip", f, c,
                               [&](const CellRun& r) {
                                   return std::max(floorMm, r.result.grasp.maxSlipM * 1e3);
                               }),
                          line(
                              "deepest penetration", f, c,
                              [&](const CellRun& r) {
                                  return std::max(floorMm, r.result.deepestPenetrationM * 1e3);
                              },
                              true)};
                  }),
        progress, files);
    drawPlotNoting(
        out,
        graspPlot(
            "grasp-force", "Grasp: |hands' vertical force - m g| / m g while held", "%", false,
            rows, cells,
            [&](const Factor& f, const std::vector<const CellRun*>& c) {
                return std::vector<PlotSeries>{
                    line("worst", f, c,
                         [](const CellRun& r) { return r.result.grasp.forceErrorWorst * 100.0; }),
                    line(
                        "median", f, c,
                        [](const CellRun& r) { return r.result.grasp.forceErrorMedian * 100.0; },
                        true)};
            }),
        progress, files);
    drawPlotNoting(
        out,
        graspPlot("grasp-step", "Grasp: the dynamics step's CPU time (a timing: it varies)", "us",
                  true, rows, cells,
                  [&](const Factor& f, const std::vector<const CellRun*>& c) {
                      return std::vector<PlotSeries>{
                          line("p99.9", f, c, [](const CellRun& r) { return r.stepP999Us.median; }),
                          line(
                              "p50", f, c, [](const CellRun& r) { return r.stepP50Us.median; },
                              true)};
                  }),
        progress, files);
    return files;
}

Json optionsJson(const GraspArgs& a) {
    const GraspCellSpec& b = a.base;
    return Json{{"quick", a.common.quick},
                {"repeats", a.common.repeats},
                {"design", "one factor at a time around the default cell"},
                {"default_cell", Json{{"squeeze_n", b.squeezeN},
                                      {"mass_kg", b.massKg},
                                      {"stiffness_n_per_m", b.stiffnessNPerM},
                                      {"servo_rate_hz", b.servoRateHz},
                                      {"dynamics_rate_hz", b.dynamicsRateHz},
                                      {"static_friction", b.staticFriction},
                                      {"dynamic_friction", b.dynamicFriction},
                                      {"box_half_extent_m", b.halfExtentM}}},
                {"squeezes_n", a.squeezesN},
                {"masses_kg", a.massesKg},
                {"stiffnesses_n_per_m", a.stiffnessesNPerM},
                {"servo_rates_hz", a.ratesHz},
                {"window", "squeeze end (4.5 s) to carry end (7.0 s) of the grasp scripts"},
                {"step_cost", "CPU time of the stepping thread per dynamics step (step mode)"}};
}

std::string verdictSummary(const Table& t) {
    const std::size_t verdict = t.column("verdict"), rep = t.column("repeatable");
    std::size_t disagree = 0, unrepeatable = 0;
    for (const auto& row : t.rows()) {
        disagree += std::get<std::string>(row[verdict]) != "agrees" ? 1 : 0;
        unrepeatable += std::get<bool>(row[rep]) ? 0 : 1;
    }
    return std::to_string(t.size() - disagree) + " of " + std::to_string(t.size()) +
           " rows agree with the analytic rule" +
           (disagree ? " (" + std::to_string(disagree) + " DISAGREE)" : std::string()) + "; " +
           (unrepeatable ? std::to_string(unrepeatable) + " rows' figures differed between runs"
                         : std::string("every row's figures were identical in every run")) +
           ".\n";
}

std::string graspMarkdown(const GraspArgs& a, const Table& t) {
    const GraspCellSpec& b = a.base;
    std::string md = "## Grasp: two simulated hands lift and carry a dynamic box (step mode)\n\n";
    if (a.common.quick) {
        md += "QUICK RUN (--quick): a smoke subset, the default cell and a 0.3 N squeeze, one "
              "run each; not the full sweep.\n\n";
    }
    md += "A " + fmt(200.0 * b.halfExtentM, 0) + " cm box on a floor, mu_s " +
          fmt(b.staticFriction, 2) + " / mu_d " + fmt(b.dynamicFriction, 2) + ", dynamics at " +
          fmt(b.dynamicsRateHz, 0) +
          " Hz; the grasp scripts squeeze, lift 5 cm and carry 10 cm. One factor at a time "
          "around the default cell (squeeze " +
          fmt(b.squeezeN, 2) + " N a hand, " + fmt(b.massKg, 3) + " kg, " +
          fmt(b.stiffnessNPerM, 0) + " N/m, servo " + fmt(b.servoRateHz, 0) +
          " Hz). Slip = movement of the box's centre of mass relative to the hands' midpoint, "
          "from the end of the squeeze (4.5 s) to the end of the carry (7.0 s); force error = "
          "|hands' vertical force - m g| / m g while lifted and carried (5.5-7.0 s); "
          "penetration and energy gain of the box from the run report. Expected: hold iff "
          "mu_s (F1 + F2) >= m g; held = final slip <= 10 mm. ";
    md += "Step CPU: the stepping thread's CPU time per dynamics step (step mode: the runtime's "
          "own step time reads 0 there); a timing, it varies from run to run: the median over " +
          std::to_string(a.common.repeats) + " run(s) of each run's p50 and p99.9. " +
          intervalNote(a.common.repeats) + " Everything else is the same every run (checked).\n\n" +
          verdictSummary(t);
    const std::size_t factor = t.column("factor");
    for (const Factor& f : kFactors) {
        md += "\n### Against " + std::string(f.name) + "\n\n" + t.markdown([&](std::size_t i) {
            return std::get<std::string>(t.rows()[i][factor]) == f.name;
        });
    }
    return md;
}
} // namespace

GraspArgs quickGraspArgs(GraspArgs a) {
    a.common.quick = true;
    a.common.repeats = 1;
    a.squeezesN = {0.3, a.base.squeezeN};
    a.massesKg = {a.base.massKg};
    a.stiffnessesNPerM = {a.base.stiffnessNPerM};
    a.ratesHz = {a.base.servoRateHz};
    return a;
}

} // namespace hapto::experiments

namespace hapto::experiments {

int runGrasp(const GraspArgs& a) {
    std::vector<CellRun> cells;
    const std::vector<RowRef> rows = planCells(a, cells);
    const std::filesystem::path out = prepareOutDir(a.common.out);
    Progress progress("grasp", cells.size() * static_cast<std::size_t>(a.common.repeats));
    for (CellRun& c : cells) {
        char label[96];
        std::snprintf(label, sizeof label, "%.2f N, %.3f kg, %.0f N/m, %.0f Hz", c.spec.squeezeN,
                      c.spec.massKg, c.spec.stiffnessNPerM, c.spec.servoRateHz);
        progress.show(label);
        runCell(c, a.common.repeats);
        progress.advance(static_cast<std::size_t>(a.common.repeats), label);
    }
    Table table = graspTable();
    for (const RowRef& r : rows) {
        addRow(table, *r.factor, cells[r.cell]);
    }
    table.writeCsv(out / "grasp.csv");
    Json j;
    j["experiment"] = "grasp";
    j["machine"] = machineJson();
    j["options"] = optionsJson(a);
    j["rows"] = table.json();
    writeText(out / "grasp.json", j.dump(2) + "\n");
    const auto plots = drawGraspPlots(out, rows, cells, progress);
    progress.finish();
    finishSweepReport(out, "grasp", graspMarkdown(a, table), plots);
    return 0;
}

} // namespace hapto::experiments
