// `hapto report plot`: the JSON report of `hapto run --report` drawn per device. A report holds
// summaries, not time series: each panel has the devices along x (one tic each, by name) and a
// line per statistic.

#include "Commands.h"
#include "Options.h"

#include "hapto/experiments/Plot.h"
#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"
#include "hapto/io/OutputFile.h"

#include <iostream>
#include <memory>

namespace hapto::cli {
namespace {

using namespace hapto::json;

/// What the figure needs of one device of a report.
struct ReportDevice {
    std::string name;
    double ticks = 0.0;
    double load[4] = {0, 0, 0, 0};  // p50, p99, p99.9, max: fractions of a period
    double lateness[3] = {0, 0, 0}; // p50, p99, max (ns)
    double contactTicks = 0.0;      // ticks in contact
    double missedDeadlines = 0.0;   // deadlines missed
};

std::vector<ReportDevice> readReport(const std::string& path) {
    const std::string text = readFile(path, "report");
    const Source w(path);
    const Json root = parseText(text, w);
    const Path top;
    object(w, root, top);
    const Path devicesPath = top / "devices";
    const Json& devices = required(w, root, top, "devices");
    if (!devices.is_array() || devices.empty()) {
        w.fail(devicesPath, "expected a non-empty array of devices (is this a `hapto run "
                            "--report` file?), got " +
                                describe(devices));
    }
    std::vector<ReportDevice> out;
    for (std::size_t i = 0; i < devices.size(); ++i) {
        const Path at = devicesPath[i];
        const Json& d = object(w, devices[i], at);
        ReportDevice r;
        r.name = printableString(w, required(w, d, at, "name"), at / "name", "the device name");
        r.ticks = ranged(w, required(w, d, at, "ticks"), at / "ticks", 0.0, kUnbounded, false,
                         "the tick count");
        const Path loadPath = at / "load";
        const Json& load = object(w, required(w, d, at, "load"), loadPath);
        const char* loads[4] = {"p50", "p99", "p999", "max"};
        for (int k = 0; k < 4; ++k) {
            r.load[k] = ranged(w, required(w, load, loadPath, loads[k]), loadPath / loads[k], 0.0,
                               kUnbounded, false, "a load (fraction of a period)");
        }
        const Path latePath = at / "lateness_ns";
        const Json& late = object(w, required(w, d, at, "lateness_ns"), latePath);
        const char* lates[3] = {"p50", "p99", "max"};
        for (int k = 0; k < 3; ++k) {
            r.lateness[k] = ranged(w, required(w, late, latePath, lates[k]), latePath / lates[k],
                                   0.0, kUnbounded, false, "a lateness (ns)");
        }
        r.contactTicks = ranged(w, required(w, d, at, "contact_ticks"), at / "contact_ticks", 0.0,
                                kUnbounded, false, "the contact tick count");
        r.missedDeadlines =
            ranged(w, required(w, d, at, "missed_deadlines"), at / "missed_deadlines", 0.0,
                   kUnbounded, false, "the missed deadline count");
        out.push_back(r);
    }
    return out;
}

experiments::PlotSpec reportPlot(const std::string& path, const std::vector<ReportDevice>& devs) {
    using experiments::panel;
    using experiments::PlotPanel;
    using experiments::PlotSeries;
    experiments::PlotSpec spec;
    spec.name = "report";
    spec.title = "hapto run report: " + path;
    spec.columns = 3;
    PlotPanel tick = panel("tick time", "device", "tick time (% of the period)");
    PlotPanel late = panel("wake-up lateness", "device", "lateness (us)");
    PlotPanel ticks = panel("ticks", "device", "% of the device's ticks");
    tick.limitY = 100.0;
    tick.limitTitle = "one period";
    const char* loadTitles[4] = {"p50", "p99", "p99.9", "max"};
    const char* lateTitles[3] = {"p50", "p99", "max"};
    for (int k = 0; k < 4; ++k) {
        PlotSeries s;
        s.title = loadTitles[k];
        s.dashed = k == 0;
        for (std::size_t i = 0; i < devs.size(); ++i) {
            s.points.emplace_back(static_cast<double>(i + 1), 100.0 * devs[i].load[k]);
        }
        tick.series.push_back(s);
    }
    for (int k = 0; k < 3; ++k) {
        PlotSeries s;
        s.title = lateTitles[k];
        s.dashed = k == 0;
        for (std::size_t i = 0; i < devs.size(); ++i) {
            s.points.emplace_back(static_cast<double>(i + 1), devs[i].lateness[k] * 1e-3);
        }
        late.series.push_back(s);
    }
    PlotSeries contact, missed;
    contact.title = "in contact";
    missed.title = "missed deadlines";
    for (std::size_t i = 0; i < devs.size(); ++i) {
        const double n = std::max(1.0, devs[i].ticks);
        const double x = static_cast<double>(i + 1);
        contact.points.emplace_back(x, 100.0 * devs[i].contactTicks / n);
        missed.points.emplace_back(x, 100.0 * devs[i].missedDeadlines / n);
    }
    ticks.series = {contact, missed};
    double most = 0;
    for (const ReportDevice& d : devs) {
        most = std::max(most, d.ticks);
    }
    spec.caption = "one run, " + std::to_string(devs.size()) + " device(s), up to " +
                   std::to_string(static_cast<long long>(most)) +
                   " ticks each; devices are categories: points, not joined";
    for (PlotPanel* p : {&tick, &late, &ticks}) {
        for (PlotSeries& s : p->series) {
            s.pointsOnly = true; // devices are categories: no line joins them
        }
        for (std::size_t i = 0; i < devs.size(); ++i) {
            p->xTics.push_back(static_cast<double>(i + 1));
            p->xTicLabels.push_back(devs[i].name);
        }
        spec.panels.push_back(*p);
    }
    return spec;
}

void plotReport(const std::string& path, const PlotOutputs& outputs) {
    outputs.check(std::span(&path, 1), "the report");
    const std::vector<ReportDevice> devices = readReport(path);
    outputs.draw(reportPlot(path, devices));
}

} // namespace

void addReportCommands(CLI::App& app) {
    CLI::App* report =
        app.add_subcommand("report", "Look at the JSON reports written by `hapto run --report`");
    report->require_subcommand(1);
    setExamples(report, {"hapto report plot run.json -o run.png"});
    auto* cmd = report->add_subcommand(
        "plot", "Draw a run report as PNG or SVG with gnuplot: tick time (% of the period), "
                "wake-up lateness and contact and missed ticks, per device");
    auto path = std::make_shared<std::string>();
    auto outputs = std::make_shared<PlotOutputs>();
    cmd->add_option("report", *path, "The report (hapto run --report FILE.json)")->required();
    addPlotOutputOptions(cmd, *outputs);
    setExamples(cmd, {"hapto report plot run.json -o run.png   # after hapto run --report run.json",
                      "hapto report plot run.json -o run.svg --script run.gp"});
    cmd->callback([path, outputs] { plotReport(*path, *outputs); });
}

} // namespace hapto::cli
