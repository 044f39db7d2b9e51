// Figures as gnuplot scripts: p50 beside p99.9, one y range across panels, a tic at every
// measured x, unstable points marked and named in the key. No gnuplot needed: the script is
// checked as text.

#include "hapto/experiments/Plot.h"
#include "hapto/experiments/Sweep.h"

#include <catch2/catch.hpp>

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
}
