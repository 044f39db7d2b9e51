// `hapto experiment paper2`: the paper's experiment 2, random scenes of 5 cm cubes.

#include "hapto/experiments/Experiments.h"
#include "hapto/experiments/Sweep.h"

#include "hapto/scenes/Generators.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <optional>

namespace hapto::experiments {
namespace {

constexpr double kWorkspaceM = 0.25;  // the paper's 25 cm work cube
constexpr double kPaper2CubeM = 0.05; // 5 cm cubes

const char* kTable2Grid = "grid 5x5x5";
const char* kTable2Octree = "octree M=2";
constexpr std::size_t kTable2Count = 200;

std::string p999Cell(const SweepRow* row) {
    if (!row) {
        return "-";
    }
    if (row->skipped) {
        return "skipped";
    }
    std::string cell = fmt(row->median.p999Pct, row->median.p999Pct < 10 ? 2 : 1) + "%";
    if (!row->stable()) {
        cell += " UNSTABLE";
    }
    return cell;
}

/// The counts asked for, sorted, each once.
std::vector<std::size_t> sortedCounts(std::vector<std::size_t> counts) {
    std::sort(counts.begin(), counts.end());
    counts.erase(std::unique(counts.begin(), counts.end()), counts.end());
    return counts;
}

/// One step per count: scenes of seeds 1..seeds, the hand at the centre the generator keeps
/// clear; the Table 2 renderers always run at the Table 2 count.
std::vector<SweepStep> paper2Steps(const Paper2Args& args, const std::vector<std::size_t>& counts) {
    std::vector<SweepStep> steps;
    const double keepClear = args.keepClearM;
    for (const std::size_t n : counts) {
        SweepStep step;
        step.objects = n;
        step.size = static_cast<int>(n);
        if (n == kTable2Count) {
            step.mustRun = {kTable2Grid, kTable2Octree};
        }
        for (int s = 1; s <= args.seeds; ++s) {
            const auto seed = static_cast<std::uint64_t>(s);
            step.scenes.push_back({seed,
                                   [n, seed, keepClear] {
                                       RandomOptions o;
                                       o.count = n;
                                       o.seed = seed;
                                       o.workspace = kWorkspaceM;
                                       o.cubeSize = kPaper2CubeM;
                                       o.keepClear = keepClear;
                                       return makeRandomScene(o);
                                   },
                                   [](const Scene&, Condition) { return Vec3(0.0); }});
        }
        steps.push_back(std::move(step));
    }
    return steps;
}

/// The analogue of the paper's Table 2 at one rate: per seed, the p99.9 load of the grid 5x5x5
/// and the octree in each condition.
std::string table2(const std::vector<SweepRow>& rows, double rate, int seeds) {
    std::vector<std::vector<std::string>> t2;
    for (int s = 1; s <= seeds; ++s) {
        std::vector<std::string> line{std::to_string(s)};
        for (const char* r : {kTable2Grid, kTable2Octree}) {
            for (const Condition c : kConditions) {
                line.push_back(p999Cell(findSweepRow(rows, r, rate, int{kTable2Count},
                                                     static_cast<std::uint64_t>(s), c)));
            }
        }
        t2.push_back(line);
    }
    return "\n### Table 2 analogue: " + std::to_string(kTable2Count) +
           "-object scenes, p99.9 load, " + rateText(rate) + "\n\n" +
           markdownTable({"scene (seed)", "grid no touch", "grid touch", "grid sliding",
                          "octree no touch", "octree touch", "octree sliding"},
                         t2);
}

/// One count's cell of a renderer's table: the median over the scenes' p99.9 loads and how many
/// scenes were stable ("skipped" when every scene was); nullopt when no scene was measured.
std::optional<std::string> overScenesCell(const std::vector<SweepRow>& rows,
                                          const std::string& renderer, double rate, std::size_t n,
                                          int seeds, Condition c) {
    std::vector<double> p999;
    int stable = 0, measured = 0;
    for (int s = 1; s <= seeds; ++s) {
        if (const SweepRow* row = findSweepRow(rows, renderer, rate, static_cast<int>(n),
                                               static_cast<std::uint64_t>(s), c)) {
            ++measured;
            stable += row->stable() ? 1 : 0;
            if (!row->skipped) {
                p999.push_back(row->median.p999Pct);
            }
        }
    }
    if (measured == 0) {
        return std::nullopt;
    }
    const double m = median(p999);
    return (p999.empty() ? std::string("skipped") : fmt(m, m < 10 ? 2 : 1) + "%") + " (" +
           std::to_string(stable) + "/" + std::to_string(measured) + " stable)";
}

/// A renderer's table at one rate: a line per count it reached, a cell per condition.
std::vector<std::vector<std::string>> overScenesLines(const std::vector<SweepRow>& rows,
                                                      const std::vector<std::size_t>& counts,
                                                      int seeds, const SweepRenderer& r,
                                                      double rate) {
    std::vector<std::vector<std::string>> table;
    for (const std::size_t n : counts) {
        std::vector<std::string> line{std::to_string(n)};
        bool any = false;
        for (const Condition c : kConditions) {
            const std::optional<std::string> cell = overScenesCell(rows, r.name, rate, n, seeds, c);
            line.push_back(cell.value_or("-"));
            any = any || cell;
        }
        if (any) {
            table.push_back(line);
        }
    }
    return table;
}

} // namespace

int runPaper2(const Paper2Args& args) {
    const std::filesystem::path out = prepareOutDir(args.common.out);
    const std::vector<SweepRenderer> renderers = {
        {"standard", IndexSpec::brute(), "20 (50 unstable)"},
        {"grid 2x2x2", IndexSpec::grid(2), "100 (unstable when sliding)"},
        {"grid 5x5x5", IndexSpec::grid(5), "200"},
        {"octree M=2", IndexSpec::octree(2, 0.005), "200 (and some 500-object scenes)"},
    };
    const std::vector<std::size_t> counts = sortedCounts(args.counts);
    const std::vector<SweepStep> steps = paper2Steps(args, counts);
    const SweepOptions options = sweepOptionsOf("paper2", args);

    Progress progress("paper2", renderers.size() * args.ratesHz.size() * counts.size() *
                                    static_cast<std::size_t>(args.seeds) * 3);
    const std::vector<SweepRow> rows = runSweep(renderers, steps, options, progress);

    const auto plots = writeSweepFiles(out, "paper2",
                                       Json{{"counts", counts},
                                            {"seeds", args.seeds},
                                            {"workspace_m", kWorkspaceM},
                                            {"cube_m", kPaper2CubeM},
                                            {"keep_clear_m", args.keepClearM}},
                                       args.common, args.maxIndexMb, renderers, args.ratesHz, rows,
                                       args.verdict, "count", progress);

    std::string md =
        "## Experiment 2: random scenes of 5 cm cubes in a 25 cm cube\n\n" +
        sweepSmokeHeader(args.common, args.verdict, counts.empty() ? 0 : counts.back()) +
        loadNote(args.common, options.servo.tail, ";", " per scene") + "\n";
    md += "\n" + platformNote(rows, args.verdict);
    const bool hasTable2 = std::find(counts.begin(), counts.end(), kTable2Count) != counts.end();
    for (const double rate : args.ratesHz) {
        if (hasTable2) {
            md += table2(rows, rate, args.seeds);
        }
        // Per renderer: median over scenes of p99.9, and how many scenes were stable.
        md += rendererTables(renderers, rate, {"# objects", "no touch", "touch", "sliding"},
                             ": median p99.9 load over scenes",
                             [&](const SweepRenderer& r, double rateHz) {
                                 return overScenesLines(rows, counts, args.seeds, r, rateHz);
                             });
    }
    md += "\n### Max stable objects per renderer (every scene stable)\n\n" +
          limitsTable(renderers, args.ratesHz, rows, args.verdict, "count");
    progress.finish(); // the results never share a line with the bar
    finishSweepReport(out, "paper2", md, plots);
    return 0;
}

} // namespace hapto::experiments
