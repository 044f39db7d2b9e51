// Figures as gnuplot scripts: p50 beside p99.9, one y range across panels, a tic at every
// measured x, unstable points marked and named in the key; checked as text. Hostile names are
// also drawn by the real gnuplot (gnuplot-nox), which must run none of them as a command.

#include "hapto/experiments/Plot.h"
#include "hapto/experiments/Sweep.h"
#include "hapto/io/InputError.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

using namespace hapto;
using namespace hapto::experiments;

namespace {

std::vector<std::string> linesStartingWith(const std::string& text, const std::string& prefix) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        if (line.rfind(prefix, 0) == 0) {
            out.push_back(line);
        }
    }
    return out;
}

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
        ++n;
    }
    return n;
}

SweepRow row(const std::string& renderer, std::size_t objects, Condition c, double p50,
             double p999) {
    SweepRow r;
    r.renderer = renderer;
    r.rateHz = 1000;
    r.size = static_cast<int>(objects);
    r.objects = objects;
    r.condition = c;
    r.median.p50Pct = p50;
    r.median.p99Pct = p999;
    r.median.p999Pct = p999;
    r.median.ticks = 1000;
    return r;
}

} // namespace

TEST_CASE("a sweep figure: p50 and p99.9 per renderer, shared y range, tics, unstable marks") {
    const std::vector<SweepRenderer> renderers = {{"standard", IndexSpec::brute(), ""},
                                                  {"octree M=2", IndexSpec::octree(2, 0.005), ""}};
    std::vector<SweepRow> rows;
    for (const Condition c : kConditions) {
        const double k = c == Condition::Sliding ? 40.0 : 1.0; // sliding loads far higher
        rows.push_back(row("standard", 8, c, 1 * k, 2 * k));
        rows.push_back(row("standard", 27, c, 3 * k, 5 * k));
        rows.push_back(row("octree M=2", 8, c, 0.5, 1));
        rows.push_back(row("octree M=2", 27, c, 0.6, 1.2));
    }
    rows[1 + 8].median.p999Pct = 250; // standard, 27 objects, sliding: over the period
    const PlotSpec spec = sweepPlot("paper1", renderers, 1000, rows, Verdict::Load);
    REQUIRE(spec.panels.size() == 3);
    CHECK(spec.shareY);
    for (const PlotPanel& p : spec.panels) {
        REQUIRE(p.series.size() == 4); // two renderers x (p99.9, p50)
        CHECK(p.series[0].title == "standard p99.9");
        CHECK(p.series[1].title == "standard p50");
        CHECK_FALSE(p.series[0].dashed);
        CHECK(p.series[1].dashed);
        CHECK(p.series[0].style == p.series[1].style); // one colour per renderer
        CHECK(p.series[0].style != p.series[2].style);
        CHECK(p.xTics == std::vector<double>{8, 27});
    }
    const PlotSeries& standardSliding = spec.panels[2].series[0];
    CHECK(standardSliding.unstable == std::vector<bool>{false, true});
    CHECK(spec.panels[0].series[0].unstable == std::vector<bool>{false, false});

    const std::string script = plotScript(spec);
    // Each panel's yrange, in the PNG and the SVG, is the same: the shared one.
    const std::vector<std::string> ranges = linesStartingWith(script, "set yrange");
    REQUIRE(ranges.size() == 6);
    CHECK(std::set<std::string>(ranges.begin(), ranges.end()).size() == 1);
    const auto range = sharedYRange(spec);
    REQUIRE(range);
    CHECK(range->first == Approx(0.5)); // the smallest p50
    CHECK(range->second == Approx(250));
    // Tics at every size, labelled.
    CHECK(count(script, "set xtics (\"8\" 8, \"27\" 27)") == 6);
    // p50 dashed, p99.9 solid; the unstable point in its own block, named in the key.
    CHECK(count(script, "title \"standard p50\"") == 6);
    CHECK(count(script, "title \"standard p99.9\"") == 6);
    CHECK(script.find("$u2 << EOD\n27 250\nEOD\n") != std::string::npos);
    CHECK(script.find("$u0") == std::string::npos); // no unstable point in "no touch"
    CHECK(count(script, "title \"unstable (load verdict)\"") == 2); // PNG and SVG, one panel
    CHECK(script.find("dt 2 title \"standard p50\"") != std::string::npos);
    CHECK(script.find("dt 1 title \"standard p99.9\"") != std::string::npos);
}

TEST_CASE("without a shared y range each panel takes its own, limit line included") {
    PlotSpec spec;
    spec.name = "t";
    spec.title = "two panels";
    PlotPanel a, b;
    a.series.push_back({"a", {{1, 10}, {2, 20}}, {}, false, -1});
    b.series.push_back({"b", {{1, 1000}, {2, 2000}}, {}, false, -1});
    a.limitY = 100.0;
    spec.panels = {a, b};
    const std::vector<std::string> separate = linesStartingWith(plotScript(spec), "set yrange");
    REQUIRE(separate.size() == 4);
    CHECK(separate[0] != separate[1]);
    // Linear: from 0 to the limit (100) plus a tenth of the span, so the limit line shows.
    CHECK(separate[0] == "set yrange [0:109]");
    spec.shareY = true;
    const std::vector<std::string> shared = linesStartingWith(plotScript(spec), "set yrange");
    CHECK(std::set<std::string>(shared.begin(), shared.end()).size() == 1);
}

TEST_CASE("a panel with no usable point says so instead of failing") {
    PlotSpec spec;
    spec.name = "empty";
    PlotPanel p;
    p.logY = true;
    p.series.push_back({"zero", {{1, 0.0}}, {}, false, -1}); // not drawable on a log scale
    spec.panels = {p};
    const std::string script = plotScript(spec);
    CHECK(script.find("'no data'") != std::string::npos);
    CHECK(script.find("$d0_0") == std::string::npos);
    // gnuplot draws it (a v1 trace has no proxy panel data): `plot 1/0` was an error.
    test::TempDir dir;
    spec.panels.push_back(spec.panels[0]);
    spec.panels[1].logY = false;
    drawPlotFile(spec, dir / "empty.svg");
    CHECK_THAT(test::readFile(dir / "empty.svg"), Catch::Contains("no data"));
}

namespace {

/// Text that runs `touch PWNED-<tag>-N` (relative: in gnuplot's folder) if gnuplot or a shell
/// ever reads it as code, with quotes, a backslash, a newline and a NUL around it.
std::string hostile(const std::string& tag) {
    return "x`touch PWNED-" + tag + "-1`y $(touch PWNED-" + tag + "-2) '\"\\ @out\nz" +
           std::string(1, '\0') + "'; system('touch PWNED-" + tag + "-3'); '";
}

/// A one-panel figure with `text` in every place a text reaches the script.
PlotSpec figureNamed(const std::string& text) {
    PlotSpec spec;
    spec.name = "hostile";
    spec.title = text;
    spec.unstableTitle = text;
    PlotPanel p;
    p.title = p.xLabel = p.yLabel = p.limitTitle = p.spanTitle = text;
    p.series.push_back({text, {{1, 1}, {2, 3}}, {false, true}, false, -1});
    p.xTics = {1, 2};
    p.xTicLabels = {text, text};
    p.limitY = 2.0;
    p.spans = {{1.2, 1.5}};
    spec.panels = {p, p};
    return spec;
}

} // namespace

TEST_CASE("every text of a figure is an ASCII string constant, every special byte escaped") {
    const std::string script = plotScript(figureNamed("it's a `b` \"c\" @m $d\\\nd\xC3\xA9"));
    // Quotes, backslash, backquote, @, $ and non-ASCII bytes in octal; a newline shown as \n.
    const std::string q = R"("it\047s a \140b\140 \042c\042 \100m \044d\134\134nd\303\251")";
    CHECK(count(script, "set title " + q) == 4); // two panels, PNG and SVG
    CHECK(count(script, "set xlabel " + q) == 4);
    CHECK(count(script, "set xtics (" + q + " 1, " + q + " 2)") == 4);
    for (const char* before : {"dt 1", "lc rgb 'black'", "lc rgb 'red'", "solid 1.0"}) {
        INFO(before); // the series, the unstable mark, the limit, the span's key
        CHECK(count(script, std::string(before) + " title " + q) == 4);
    }
    CHECK(count(script, "set multiplot layout 1,2 title " + q) == 2);
    // No backquote anywhere: gnuplot substitutes backquotes even inside strings.
    CHECK(script.find('`') == std::string::npos);
    // Every line is one command: the name's newline did not end one.
    CHECK(script.find("\nd") == std::string::npos);
}

TEST_CASE("gnuplot draws hostile names as text and runs none of them", "[threads]") {
    test::TempDir root;
    // The output's folder is hostile too (no NUL: a path cannot hold one).
    std::string folder = hostile("dir");
    folder.erase(folder.find('\0'), 1);
    const std::filesystem::path dir = root / folder;
    std::filesystem::create_directories(dir);
    const test::InFolder inRoot(root.path());
    for (const std::string ext : {".png", ".svg"}) {
        INFO(ext);
        const std::filesystem::path out = dir / ("plot" + ext);
        drawPlotFile(figureNamed(hostile("name")), out, dir / "plot.gp");
        CHECK(std::filesystem::file_size(out) > 0);
        const PlotResult r = drawPlot(dir, figureNamed(hostile("figure")));
        CHECK(r.problem == "");
        CHECK(r.files.size() == 2);
    }
    CHECK_THAT(test::readFile(dir / "plot.svg"),
               Catch::Contains("x`touch PWNED-name-1`y $(touch PWNED-name-2)"));
    CHECK(test::pwned(root.path()).empty());
    // Only the outputs are left: no temporary, no log.
    std::set<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
        names.insert(e.path().filename().string());
    }
    CHECK(names == std::set<std::string>{"plot.png", "plot.svg", "plot.gp", "hostile.gp",
                                         "hostile.png", "hostile.svg"});
}

TEST_CASE("error bars, points-only series, dash types, a caption and per-style spans") {
    PlotSpec spec;
    spec.name = "bars";
    spec.title = "load";
    spec.caption = "5 run(s) of 0.5 s per cell";
    PlotPanel p = panel("per device", "devices", "load (%)");
    PlotSeries joined{"joined", {{1, 2}, {2, 4}}, {}, false, 1};
    joined.errors = {{1.5, 2.5}, {3, 5}};
    PlotSeries points{"points", {{1, 3}, {2, 6}}, {}, false, 2};
    points.errors = {{2, 4}}; // the second point has no bar: drawn at its value
    points.pointsOnly = true; // categories: not joined
    PlotSeries dotted{"dotted", {{1, 1}}, {}, false, 3};
    dotted.dash = 3;
    p.series = {joined, points, dotted};
    p.xTics = {1, 2};
    p.spans = {{1.1, 1.2}, {1.5, 1.9}};
    p.spanStyles = {1, 2};
    p.spanStyleTitles = {"a in contact", "b in contact"};
    spec.panels = {p};
    const std::string script = plotScript(spec);
    // Bars: four columns per point, the ends as given, or the value where none is.
    CHECK(script.find("$d0_0 << EOD\n1 2 1.5 2.5\n2 4 3 5\nEOD\n") != std::string::npos);
    CHECK(script.find("$d0_1 << EOD\n1 3 2 4\n2 6 6 6\nEOD\n") != std::string::npos);
    CHECK(script.find("$d0_0 using 1:2:3:4 with yerrorlines lc rgb '" + plotColour(1) + "'") !=
          std::string::npos);
    CHECK(script.find("$d0_1 using 1:2:3:4 with yerrorbars lc rgb '" + plotColour(2) + "'") !=
          std::string::npos);
    CHECK(script.find("$d0_2 using 1:2 with linespoints") != std::string::npos);
    CHECK(script.find("dt 3 title \"dotted\"") != std::string::npos);
    // The y range holds the bars' ends (the widest: 1.5 .. 6), not only the medians.
    const auto range = sharedYRange(spec);
    REQUIRE(range);
    CHECK(range->first == Approx(1.0));
    CHECK(range->second == Approx(6.0));
    // The caption is a line of the title.
    CHECK(script.find("set title \"load: per device\".\"\\n\".\"5 run(s) of 0.5 s per cell\"") !=
          std::string::npos);
    // Each span in its style's colour, each style once in the key.
    CHECK(script.find("to 1.2, graph 1 behind fillcolor rgb '" + plotColour(1) + "'") !=
          std::string::npos);
    CHECK(script.find("to 1.9, graph 1 behind fillcolor rgb '" + plotColour(2) + "'") !=
          std::string::npos);
    CHECK(count(script, "title \"a in contact\"") == 2); // PNG and SVG
    CHECK(count(script, "title \"b in contact\"") == 2);
}

TEST_CASE("the palette's colours are distinct and cycle") {
    std::set<std::string> colours;
    for (int s = 1; s <= 10; ++s) {
        colours.insert(plotColour(s));
    }
    CHECK(colours.size() == 10);
    CHECK(plotColour(11) == plotColour(1));
    CHECK(plotColour(0) == plotColour(10));
}
