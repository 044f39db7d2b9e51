// `hapto trace export|info|plot`: look inside trace files written by `hapto run --record`.

#include "Commands.h"
#include "Options.h"

#include "hapto/devices/TraceColumns.h"
#include "hapto/devices/TraceReader.h"
#include "hapto/experiments/Plot.h"
#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/BodyTrace.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <iostream>
#include <memory>
#include <stdexcept>

namespace hapto::cli {
namespace {

// Writes the CSV: one header row (the columns of the trace's version, TraceColumns.h), one row
// per sample; numbers round-trip exactly. Another kind of trace gets its own writer beside this
// one, dispatched in the export command's callback.
void exportCsv(const std::string& tracePath, const std::string& outPath) {
    const bool toFile = !outPath.empty() && outPath != "-";
    if (toFile) {
        refuseSameFile(outPath, "-o", tracePath, "the trace");
        checkOutputFile(outPath, "-o");
    }
    TraceReader reader(tracePath);
    const std::uint32_t version = reader.header().version;
    TextOutput csv(toFile ? outPath : std::string());
    std::string& out = csv.text();
    out = traceCsvHeader(version);
    TraceSample s;
    std::uint64_t rows = 0;
    while (reader.next(s)) {
        appendTraceCsvRow(s, version, out);
        ++rows;
        csv.afterRow();
    }
    csv.finish();
    if (toFile) {
        std::cerr << "wrote " << rows << " samples to " << outPath << "\n";
    }
}

// The dynamic bodies' trace (DIR/bodies.trace, BodyTrace.h) as CSV: one row per body per step.
void exportBodyCsv(const std::string& tracePath, const std::string& outPath) {
    const bool toFile = !outPath.empty() && outPath != "-";
    if (toFile) {
        refuseSameFile(outPath, "-o", tracePath, "the trace");
        checkOutputFile(outPath, "-o");
    }
    const BodyTrace trace = readBodyTrace(tracePath);
    TextOutput csv(toFile ? outPath : std::string());
    csv.text() = bodyTraceCsvHeader();
    for (const BodyTraceSample& s : trace.samples) {
        appendBodyTraceCsvRow(trace, s, csv.text());
        csv.afterRow();
    }
    csv.finish();
    if (toFile) {
        std::cerr << "wrote " << trace.samples.size() << " body samples to " << outPath << "\n";
    }
}

void printInfo(const std::string& tracePath) {
    TraceReader reader(tracePath);
    const TraceHeader& h = reader.header();
    std::uint64_t first = 0, last = 0, notOk = 0, gaps = 0, n = 0;
    double maxForce = 0.0;
    TraceSample s;
    while (reader.next(s)) {
        if (n == 0) {
            first = s.tick;
        } else if (s.tick != last + 1) {
            gaps += s.tick - last - 1;
        }
        last = s.tick;
        notOk += s.status != DeviceStatus::Ok;
        maxForce = std::max(maxForce, glm::length(s.forceN));
        ++n;
    }
    std::printf("trace:    %s\n", tracePath.c_str());
    std::printf("device:   %s (%s)\n", h.name.c_str(), h.kind.c_str());
    std::printf("rate:     %g Hz\n", h.rateHz);
    std::printf("format:   version %u\n", h.version);
    if (h.hasConfiguration()) {
        const WorkspaceTransform& t = h.transform;
        std::printf("transform: translation [%g, %g, %g] m, rotation [%g, %g, %g, %g], scale %g\n",
                    t.translation.x, t.translation.y, t.translation.z, t.rotation.w, t.rotation.x,
                    t.rotation.y, t.rotation.z, t.scale);
        std::printf("tool tip: [%g, %g, %g] m\n", h.toolTipM.x, h.toolTipM.y, h.toolTipM.z);
        std::printf("clamp:    %g N%s\n", h.maxForceN, h.maxForceN > 0 ? "" : " (the default)");
    }
    std::printf("samples:  %llu%s\n", static_cast<unsigned long long>(n),
                h.finished ? "" : " (recording was not closed)");
    if (n > 0) {
        std::printf("ticks:    %llu .. %llu, %llu not recorded\n",
                    static_cast<unsigned long long>(first), static_cast<unsigned long long>(last),
                    static_cast<unsigned long long>(gaps));
        std::printf("not ok:   %llu reads\n", static_cast<unsigned long long>(notOk));
        std::printf("max |F|:  %.4f N\n", maxForce);
    }
}

/// The most points a plotted series gets: a longer trace is drawn from every k-th sample (the
/// contact spans still come from every sample).
constexpr std::size_t kMaxPlotPoints = 4000;

/// The time axis of a sample (s since the session started).
double seconds(const TraceSample& s) {
    return static_cast<double>(s.timeNs) * 1e-9;
}

/// The spans of time a device was in contact (contact count > 0: version 2 traces), each from
/// its first sample in contact to its last.
std::vector<std::pair<double, double>> contactSpans(const std::vector<TraceSample>& samples) {
    std::vector<std::pair<double, double>> contact;
    for (std::size_t k = 0; k < samples.size(); ++k) {
        if (samples[k].contactCount == 0) {
            continue;
        }
        // Extend the last span when this sample follows it, else start one.
        const double x = seconds(samples[k]);
        const double step = k > 0 ? x - seconds(samples[k - 1]) : 0.0;
        if (!contact.empty() && k > 0 && samples[k - 1].contactCount > 0 &&
            x >= contact.back().first && x - contact.back().second <= step) {
            contact.back().second = std::max(contact.back().second, x);
        } else {
            contact.emplace_back(x, x);
        }
    }
    return contact;
}

/// One trace's series for tracePlot: position, proxy (version 2 traces) and force per axis,
/// |F| and tick time, drawn from at most kMaxPlotPoints samples, in device colour `style`:
/// x, y and z told apart by dash type, |F| solid.
struct TraceSeries {
    experiments::PlotSeries position[3], proxy[3], force[4], tick;

    TraceSeries(const std::vector<TraceSample>& samples, const TraceHeader& h,
                const std::string& device, int style) {
        const char* axes[3] = {"x", "y", "z"};
        for (int a = 0; a < 3; ++a) {
            position[a].title = proxy[a].title = device + " " + axes[a];
            force[a].title = device + " F" + axes[a];
            for (experiments::PlotSeries* series : {&position[a], &proxy[a], &force[a]}) {
                series->linesOnly = true;
                series->style = style;
                series->dash = a + 2;
            }
            position[a].dash = proxy[a].dash = a + 1;
        }
        force[3].title = device + " |F|";
        tick.title = device;
        for (experiments::PlotSeries* series : {&force[3], &tick}) {
            series->linesOnly = true;
            series->style = style;
        }
        const std::size_t stride =
            std::max<std::size_t>(1, (samples.size() + kMaxPlotPoints - 1) / kMaxPlotPoints);
        for (std::size_t k = 0; k < samples.size(); k += stride) {
            add(samples[k], h.version);
        }
        if (!samples.empty() && (samples.size() - 1) % stride != 0) {
            add(samples.back(), h.version); // the last sample always
        }
    }

private:
    void add(const TraceSample& s, int version) {
        const double x = seconds(s);
        for (int a = 0; a < 3; ++a) {
            position[a].points.emplace_back(x, s.positionM[a]);
            if (version >= 2) {
                proxy[a].points.emplace_back(x, s.proxyM[a]);
            }
            force[a].points.emplace_back(x, s.forceN[a]);
        }
        force[3].points.emplace_back(x, glm::length(s.forceN));
        tick.points.emplace_back(x, static_cast<double>(s.computeNs) * 1e-3);
    }
};

/// A figure of traces: position, proxy, force and tick time against time, one colour per
/// device, shaded where a device was in contact (version 2 traces: contact count > 0).
experiments::PlotSpec tracePlot(const std::vector<std::string>& paths) {
    using experiments::panel;
    using experiments::PlotPanel;
    experiments::PlotSpec spec;
    spec.name = "trace";
    spec.title = "hapto trace";
    spec.columns = 2;
    spec.panelWidthPx = 640;
    spec.heightPx = 400;
    PlotPanel position =
        panel("position (gimbal centre, device frame)", "time (s)", "position (m)");
    PlotPanel proxy = panel("proxy (device frame)", "time (s)", "proxy (m)");
    PlotPanel force = panel("force written (device frame)", "time (s)", "force (N)");
    PlotPanel tick = panel("tick time (wake-up to force written)", "time (s)", "tick time (us)");
    std::vector<std::pair<double, double>> spans; // every device's contact spans
    std::vector<int> spanStyles;                  // the device (style) of each
    std::vector<std::string> spanTitles;          // per device: its key text
    double endS = 0;
    int style = 0;
    for (const std::string& path : paths) {
        TraceHeader h;
        const std::vector<TraceSample> samples = TraceReader::load(path, &h);
        const std::string device = h.name.empty() ? path : h.name;
        if (paths.size() > 1 && spec.title == "hapto trace") {
            spec.title = "hapto trace: " + std::to_string(paths.size()) + " devices";
        } else if (paths.size() == 1) {
            spec.title = "hapto trace: " + device + " (" + h.kind + ", " + path + ")";
        }
        ++style; // one colour per device (plotColour)
        if (!samples.empty()) {
            endS = std::max(endS, seconds(samples.back()));
        }
        for (const auto& span : contactSpans(samples)) {
            spans.push_back(span);
            spanStyles.push_back(style);
        }
        spanTitles.push_back(device + " in contact");
        const TraceSeries series(samples, h, device, style);
        for (int a = 0; a < 3; ++a) {
            position.series.push_back(series.position[a]);
            proxy.series.push_back(series.proxy[a]);
            force.series.push_back(series.force[a]);
        }
        force.series.push_back(series.force[3]);
        tick.series.push_back(series.tick);
    }
    char caption[160];
    std::snprintf(caption, sizeof caption,
                  "%zu device(s), one run of %.3g s; shading: each device's contact spans in "
                  "its colour",
                  paths.size(), endS);
    spec.caption = caption;
    // Each device's spans in its own translucent colour: overlaps show both.
    for (PlotPanel* p : {&position, &proxy, &force, &tick}) {
        p->spans = spans;
        p->spanStyles = spanStyles;
        p->spanStyleTitles = spanTitles;
        spec.panels.push_back(*p);
    }
    return spec;
}

void plotTraces(const std::vector<std::string>& paths, const PlotOutputs& outputs) {
    outputs.check(paths, "a trace");
    outputs.draw(tracePlot(paths));
}

} // namespace

void PlotOutputs::check(std::span<const std::string> inputs, const std::string& inputName) const {
    for (const std::string& input : inputs) {
        refuseSameFile(out, "-o", input, inputName);
        if (!script.empty()) {
            refuseSameFile(script, "--script", input, inputName);
        }
    }
    const std::string ext = std::filesystem::path(out).extension().string();
    if (ext != ".png" && ext != ".svg") {
        throw InputError(out + ": -o names the plot, a file ending in .png or .svg");
    }
    checkOutputFile(out, "-o");
    if (!script.empty()) {
        refuseSameFile(script, "--script", out, "the plot");
        checkOutputFile(script, "--script");
    }
}

void PlotOutputs::draw(const experiments::PlotSpec& spec) const {
    experiments::drawPlotFile(spec, out, script);
    std::cerr << "wrote " << out << (script.empty() ? "" : " and " + script) << "\n";
}

void addPlotOutputOptions(CLI::App* cmd, PlotOutputs& outputs) {
    cmd->add_option("-o,--output", outputs.out, "The plot: OUT.png or OUT.svg")->required();
    cmd->add_option("--script", outputs.script, "Also keep the gnuplot script, data inline");
}

void addTraceCommands(CLI::App& app) {
    CLI::App* trace =
        app.add_subcommand("trace", "Look inside trace files written by `hapto run --record`");
    trace->require_subcommand(1);
    setExamples(trace, {"hapto trace info traces/left.trace",
                        "hapto trace plot traces/*.trace -o traces.png"});
    {
        auto* cmd = trace->add_subcommand(
            "export",
            "Write a trace as CSV, every column it holds: tick, time_ns, position (m, device "
            "frame), force (N), compute_ns, io_ns, status, buttons; version 2 traces also the "
            "proxy (m), velocity (m/s), orientation (quaternion), angular velocity (rad/s), "
            "contact count and the sample flags (0/1). A bodies.trace (the dynamic bodies): "
            "time_s, id, x, y, z (centre of mass, m, world), qw, qx, qy, qz, vx, vy, vz (m/s), "
            "wx, wy, wz (rad/s), one row per body per dynamics step");
        auto path = std::make_shared<std::string>();
        auto out = std::make_shared<std::string>();
        cmd->add_option("trace", *path, "The trace file")->required();
        cmd->add_option("-o,--output", *out, "CSV file to write (default: standard output)");
        setExamples(cmd, {"hapto trace export traces/left.trace -o left.csv",
                          "hapto trace export traces/bodies.trace -o bodies.csv"});
        cmd->callback([path, out] {
            if (isBodyTrace(*path)) {
                exportBodyCsv(*path, *out);
            } else {
                exportCsv(*path, *out);
            }
        });
    }
    {
        auto* cmd = trace->add_subcommand("info", "Describe a trace: device, rate, samples");
        auto path = std::make_shared<std::string>();
        cmd->add_option("trace", *path, "The trace file")->required();
        setExamples(cmd, {"hapto trace info traces/left.trace"});
        cmd->callback([path] { printInfo(*path); });
    }
    {
        auto* cmd = trace->add_subcommand(
            "plot", "Draw traces (one per device) as PNG or SVG with gnuplot: position, proxy "
                    "and force (device frame) and tick time against time, shaded in contact");
        auto paths = std::make_shared<std::vector<std::string>>();
        auto outputs = std::make_shared<PlotOutputs>();
        cmd->add_option("traces", *paths, "The trace files (one line colour each)")->required();
        addPlotOutputOptions(cmd, *outputs);
        setExamples(cmd, {"hapto trace plot traces/left.trace traces/right.trace -o hands.png"});
        cmd->callback([paths, outputs] { plotTraces(*paths, *outputs); });
    }
}

} // namespace hapto::cli
