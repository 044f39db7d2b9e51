// The sweep's arithmetic: medians over repeats, the verdicts (p99.9, or p99 for quick runs),
// and the limits drawn from them.

#include "hapto/experiments/Sweep.h"

#include <catch2/catch.hpp>

using namespace hapto;
using namespace hapto::experiments;

namespace {

LoadFigures figures(double p50, double p99, double p999, double missedPct = 0.0) {
    LoadFigures f;
    f.p50Pct = p50;
    f.p99Pct = p99;
    f.p999Pct = p999;
    f.maxPct = p999;
    f.ticks = 1000;
    f.missedPct = missedPct;
    return f;
}

SweepRow row(const std::string& renderer, std::size_t objects, std::uint64_t seed, double p999,
             double missedPct = 0.0) {
    SweepRow r;
    r.renderer = renderer;
    r.rateHz = 1000;
    r.size = static_cast<int>(objects);
    r.objects = objects;
    r.seed = seed;
    r.median = figures(1, p999 / 2, p999, missedPct);
    r.runs = {r.median};
    return r;
}

} // namespace

TEST_CASE("median: the middle value, 0 for none, any order") {
    CHECK(median({}) == 0.0);
    CHECK(median({3.0}) == 3.0);
    CHECK(median({5.0, 1.0, 3.0}) == 3.0);
    const double even = median({4.0, 1.0, 3.0, 2.0});
    CHECK((even == 2.0 || even == 3.0 || even == 2.5));
}

TEST_CASE("medianOf takes each figure's median, the first fault, and realtime only if all") {
    std::vector<LoadFigures> runs = {figures(1, 5, 90), figures(3, 6, 200), figures(2, 7, 95)};
    runs[0].realtime = runs[1].realtime = true;
    runs[1].fault = "disconnected";
    const LoadFigures m = medianOf(runs);
    CHECK(m.p50Pct == 2);
    CHECK(m.p999Pct == 95);
    CHECK(m.p99Pct == 6);
    CHECK(m.fault == "disconnected");
    CHECK_FALSE(m.realtime);
    CHECK_FALSE(m.stable()); // a fault is never stable
}

TEST_CASE("verdicts: p99.9 < 100 % (and <= 0.1 % missed for DESIGN), quick runs read p99") {
    LoadFigures f = figures(10, 60, 120);
    CHECK_FALSE(f.loadStable()); // p99.9 over the period
    f.tail = Tail::P99;
    CHECK(f.loadStable()); // a quick run: its p99 is what it can judge
    CHECK(f.stable());
    f.missedPct = 0.2;
    CHECK(f.loadStable());
    CHECK_FALSE(f.stable()); // DESIGN also counts misses
    LoadFigures none = figures(10, 20, 30);
    none.ticks = 0;
    CHECK_FALSE(none.loadStable()); // no ticks, no verdict
    CHECK(tailName(Tail::P99) == "p99");
    CHECK(tailName(Tail::P999) == "p99.9");
    CHECK(tailFor(true) == Tail::P99);
    CHECK(tailFor(false) == Tail::P999);
    CHECK(verdictNote(Tail::P99).find("p99") != std::string::npos);
    // medianOf keeps the tail the runs were judged on.
    CHECK(medianOf({f, f}).tail == Tail::P99);
}

TEST_CASE("sweep limits: largest size with every scene stable, first size with one unstable") {
    const std::vector<SweepRenderer> renderers = {{"octree", IndexSpec::brute(), ""}};
    std::vector<SweepRow> rows = {
        row("octree", 10, 1, 20),  row("octree", 10, 2, 30),
        row("octree", 20, 1, 40),  row("octree", 20, 2, 150), // one scene of two unstable
        row("octree", 50, 1, 300),                            // still measured after
    };
    rows[2].median.missedPct = 0.5; // stable by load, not by DESIGN
    const auto load = sweepLimits(renderers, {1000}, rows, Verdict::Load);
    REQUIRE(load.size() == 1);
    CHECK(load[0].maxStableObjects == 10u);
    CHECK(load[0].firstUnstableObjects == 20u);
    CHECK(load[0].scenesAtFirstUnstable == 2);
    CHECK(load[0].scenesStableAtFirstUnstable == 1);
    CHECK(load[0].largestMeasuredObjects == 50u);
    const auto design = sweepLimits(renderers, {1000}, rows, Verdict::Design);
    CHECK(design[0].scenesStableAtFirstUnstable == 0); // scene 1 at 20 missed too many
    // A skipped cell is unstable whatever its figures.
    rows[0].skipped = true;
    CHECK_FALSE(rows[0].stable(Verdict::Load));
    CHECK_FALSE(sweepLimits(renderers, {1000}, rows, Verdict::Load)[0].maxStableObjects);
}

TEST_CASE("a sweep cell in which a run measured no tick is skipped, never a load of zero") {
    const std::vector<SweepRenderer> renderers = {{"octree", IndexSpec::brute(), ""}};
    SweepRow idle = row("octree", 10, 1, 20);
    idle.runs = {figures(1, 2, 3), LoadFigures{}, figures(1, 2, 3)}; // run 2 ticked nothing
    concludeRow(idle);
    CHECK(idle.skipped);
    CHECK_THAT(idle.note, Catch::Contains("no tick was measured in run 2 of 3"));
    CHECK_FALSE(idle.stable(Verdict::Load));
    CHECK_FALSE(idle.stable(Verdict::Design));
    // It is not the largest stable size, though its other runs were light.
    const std::vector<SweepRow> rows = {row("octree", 5, 1, 20), idle};
    const auto limits = sweepLimits(renderers, {1000}, rows, Verdict::Load);
    CHECK(limits[0].maxStableObjects == 5u);
    CHECK(limits[0].firstUnstableObjects == 10u);

    SweepRow none = row("octree", 10, 1, 20);
    none.runs.clear();
    concludeRow(none);
    CHECK(none.skipped);
    CHECK_THAT(none.note, Catch::Contains("no run"));
}

TEST_CASE("a measured sweep cell takes its runs' medians and notes a missed phase or a fault") {
    SweepRow r = row("octree", 10, 1, 20);
    r.runs = {figures(1, 2, 10), figures(1, 2, 30), figures(1, 2, 20)};
    r.condition = Condition::Sliding;
    concludeRow(r);
    CHECK_FALSE(r.skipped);
    CHECK(r.median.p999Pct == 20);
    CHECK(r.note.empty());
    CHECK(r.stable(Verdict::Design));

    r.reachedPhase = false;
    concludeRow(r);
    CHECK_FALSE(r.skipped);
    CHECK_THAT(r.note, Catch::Contains("did not reach its sliding phase"));

    r.reachedPhase = true;
    r.runs[0].fault = "read-failed";
    r.runs[1].fault = "read-failed";
    concludeRow(r);
    CHECK_THAT(r.note, Catch::Contains("fault: read-failed"));
    CHECK_FALSE(r.stable(Verdict::Load));
}

TEST_CASE("findSweepRow: the first row of the cell named by all five keys, null for any other") {
    std::vector<SweepRow> rows = {row("grid", 200, 1, 10), row("grid", 200, 2, 20),
                                  row("octree", 200, 1, 30), row("grid", 200, 1, 40)};
    rows[3].condition = Condition::Touch;
    const SweepRow* hit = findSweepRow(rows, "grid", 1000, 200, 2, Condition::NoTouch);
    REQUIRE(hit == &rows[1]);
    CHECK(findSweepRow(rows, "grid", 1000, 200, 1, Condition::Touch) == &rows[3]);
    CHECK(findSweepRow(rows, "octree", 1000, 200, 1, Condition::NoTouch) == &rows[2]);
    CHECK(findSweepRow(rows, "grid", 4000, 200, 1, Condition::NoTouch) == nullptr);
    CHECK(findSweepRow(rows, "grid", 1000, 100, 1, Condition::NoTouch) == nullptr);
    CHECK(findSweepRow(rows, "grid", 1000, 200, 3, Condition::NoTouch) == nullptr);
    CHECK(findSweepRow(rows, "grid", 1000, 200, 2, Condition::Sliding) == nullptr);
    CHECK(findSweepRow(rows, "brute", 1000, 200, 1, Condition::NoTouch) == nullptr);

    rows.push_back(row("grid", 200, 2, 50)); // a second row of one cell: the first wins
    CHECK(findSweepRow(rows, "grid", 1000, 200, 2, Condition::NoTouch) == &rows[1]);
}

TEST_CASE("rendererTables: a heading and a table per renderer, in order, from its own lines") {
    const std::vector<SweepRenderer> renderers = {{"standard", IndexSpec::brute(), "-"},
                                                  {"grid 5x5x5", IndexSpec::grid(5), "-"}};
    const std::string md = rendererTables(
        renderers, 4000, {"n", "load"}, ": over scenes", [](const SweepRenderer& r, double rate) {
            return std::vector<std::vector<std::string>>{{r.name, std::to_string(int(rate))}};
        });
    const std::size_t first = md.find("\n### standard (brute), 4 kHz: over scenes\n\n");
    const std::size_t second = md.find("\n### grid 5x5x5 (grid:5), 4 kHz: over scenes\n\n");
    REQUIRE(first != std::string::npos);
    REQUIRE(second != std::string::npos);
    CHECK(first < second);
    const std::string standardPart = md.substr(first, second - first);
    CHECK_THAT(standardPart, Catch::Contains("| standard | 4000 |"));
    CHECK_THAT(standardPart, !Catch::Contains("grid 5x5x5 |"));
    CHECK_THAT(md.substr(second), Catch::Contains("| grid 5x5x5 | 4000 |"));
    CHECK(rendererTables({}, 1000, {"n"}, "", [](const SweepRenderer&, double) {
              return std::vector<std::vector<std::string>>{};
          }).empty());
}

TEST_CASE("loadNote: the load, the runs behind each cell and what UNSTABLE reads, in one line") {
    CommonArgs common;
    common.repeats = 3;
    common.durationS = 0.5;
    CHECK(loadNote(common, Tail::P999, ": p50 / p99.9 / max,", "") ==
          "Load = wake-up to force written, % of the servo period: p50 / p99.9 / max, median of "
          "3 run(s) of 0.50 s; [lo, hi] after p99.9: its interval across the runs. " +
              intervalNote(3) + " UNSTABLE: p99.9 >= 100 % or > 0.1 % deadlines missed.");
    common.repeats = 1;
    common.durationS = 0.15;
    CHECK(loadNote(common, Tail::P99, ";", " per scene") ==
          "Load = wake-up to force written, % of the servo period; median of 1 run(s) of 0.15 s "
          "per scene; [lo, hi] after p99.9: its interval across the runs. " +
              intervalNote(1) + " UNSTABLE: p99 >= 100 % or > 0.1 % deadlines missed.");
}

TEST_CASE("a sweep row's interval across its runs is in the CSV and JSON and holds the median") {
    SweepRow r;
    r.renderer = "standard";
    r.index = "brute";
    r.rateHz = 1000;
    for (const double p999 : {5.0, 1.0, 3.0, 2.0, 4.0}) {
        LoadFigures f;
        f.ticks = 100;
        f.p50Pct = p999 / 10;
        f.p999Pct = p999;
        f.maxPct = p999;
        r.runs.push_back(f);
    }
    concludeRow(r);
    const MedianInterval m = r.interval(&LoadFigures::p999Pct);
    CHECK(m.median == 3.0);
    CHECK(m.lo == 1.0);
    CHECK(m.hi == 5.0);
    const Json j =
        sweepJson({{"standard", IndexSpec::brute(), ""}}, {1000}, {r}, Verdict::Load, "count");
    const Json& row = j["rows"][0];
    CHECK(row["load_p999_pct"] == 3.0);
    CHECK(row["load_p999_lo_pct"] == 1.0);
    CHECK(row["load_p999_hi_pct"] == 5.0);
    CHECK(row["load_p50_lo_pct"] == Approx(0.1));
    CHECK(row["interval_coverage"] == Approx(0.9375));
    CHECK_THAT(loadCell(r), Catch::Contains("3.00 [1.00, 5.00]"));
}
