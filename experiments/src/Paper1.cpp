// `hapto experiment paper1`: the paper's experiment 1, lattices of K x K x K cubes.

#include "hapto/experiments/Experiments.h"
#include "hapto/experiments/Sweep.h"

#include "hapto/scenes/Generators.h"

#include <algorithm>
#include <cstdio>
#include <iostream>

namespace hapto::experiments {
namespace {

constexpr double kPaper1CubeM = 0.05;      // the paper's e-Touch boxes
constexpr double kGapM = 0.01;             // free space between neighbouring cubes
constexpr double kPadM = 0.04;             // partitioned space beyond the lattice, on every side
constexpr double kLatticeStandOffM = 0.02; // start this far outside the lattice's +z face

/// The sizes: a geometric-ish sweep of K up to `maxPerSide` (which is always included).
std::vector<int> perSideSweep(int maxPerSide) {
    std::vector<int> ks;
    for (const int k :
         {2, 3, 4, 5, 6, 8, 10, 13, 16, 20, 25, 32, 40, 50, 64, 80, 100, 128, 160, 200, 256}) {
        if (k <= maxPerSide) {
            ks.push_back(k);
        }
    }
    if (ks.empty() || ks.back() != maxPerSide) {
        ks.push_back(maxPerSide);
    }
    return ks;
}

/// K^3 cubes of 5 cm with 1 cm gaps, centred on the origin; the partitioned space is the
/// lattice plus 4 cm on every side ("slightly larger than the object grid"), so the hand
/// has room outside the lattice's faces.
Scene latticeScene(int k) {
    LatticeOptions o;
    o.perSide = k;
    o.cubeSize = kPaper1CubeM;
    o.gap = kGapM;
    Scene lattice = makeLatticeScene(o);
    const double half = 0.5 * (k * kPaper1CubeM + (k - 1) * kGapM) + kPadM;
    std::vector<SceneObject> objects(lattice.objects().begin(), lattice.objects().end());
    return Scene(Aabb{Vec3(-half), Vec3(half)}, std::move(objects));
}

/// In front of the middle of the +z face: 2 cm off the face of the cube nearest the face's
/// centre, the stand-off the touch and slide scripts approach from. The free walk moves in the
/// 4 cm slab between that face and the partitioned space's boundary.
Vec3 latticeStart(int k) {
    const double pitch = kPaper1CubeM + kGapM;
    const double c = (k / 2 - 0.5 * (k - 1)) * pitch; // the centre cube's (or next one's) x, y
    const double face = 0.5 * (k * kPaper1CubeM + (k - 1) * kGapM);
    return Vec3(c, c, face + kLatticeStandOffM);
}

} // namespace

int runPaper1(const Paper1Args& args) {
    const std::filesystem::path out = prepareOutDir(args.common.out);
    const std::vector<SweepRenderer> renderers = {
        {"standard", IndexSpec::brute(), "27 (64 unstable)"},
        {"grid 2x2x2", IndexSpec::grid(2), "216"},
        {"grid 5x5x5", IndexSpec::grid(5), "1728"},
        {"octree M=2", IndexSpec::octree(2, 0.005), ">= 8000 (stopped; load < 40 %)"},
        {"octree M=5", IndexSpec::octree(5, 0.005), ">= 8000 (stopped; load < 40 %)"},
    };
    std::vector<SweepStep> steps;
    for (const int k : args.perSide.empty() ? perSideSweep(args.maxPerSide) : args.perSide) {
        SweepStep step;
        step.objects = static_cast<std::size_t>(k) * k * k;
        step.size = k;
        step.scenes.push_back({0, [k] { return latticeScene(k); },
                               [k](const Scene&, Condition) { return latticeStart(k); }});
        steps.push_back(std::move(step));
    }
    const SweepOptions options = sweepOptionsOf("paper1", args);

    Progress progress("paper1", renderers.size() * args.ratesHz.size() * steps.size() * 3);
    const std::vector<SweepRow> rows = runSweep(renderers, steps, options, progress);

    // Files.
    const auto plots = writeSweepFiles(out, "paper1",
                                       Json{{"max_per_side", args.maxPerSide},
                                            {"cube_m", kPaper1CubeM},
                                            {"gap_m", kGapM},
                                            {"pad_m", kPadM}},
                                       args.common, args.maxIndexMb, renderers, args.ratesHz, rows,
                                       args.verdict, "per_side", progress);

    // Tables.
    std::string md =
        "## Experiment 1: K x K x K lattices of 5 cm cubes\n\n" +
        sweepSmokeHeader(args.common, args.verdict, steps.empty() ? 0 : steps.back().objects) +
        loadNote(args.common, options.servo.tail, ": p50 / p99.9 / max,", "") + "\n";
    md += "\n" + platformNote(rows, args.verdict);
    const auto lines = [&](const SweepRenderer& r, double rate) {
        std::vector<std::vector<std::string>> table;
        for (const SweepStep& step : steps) {
            std::vector<std::string> line{std::to_string(step.objects), std::to_string(step.size)};
            bool any = false;
            for (const Condition c : kConditions) {
                const SweepRow* row = findSweepRow(rows, r.name, rate, step.size, 0, c);
                line.push_back(row ? loadCell(*row) : "-");
                any = any || row;
            }
            if (any) {
                table.push_back(line);
            }
        }
        return table;
    };
    for (const double rate : args.ratesHz) {
        md += rendererTables(renderers, rate, {"# objects", "K", "no touch", "touch", "sliding"},
                             "", lines);
    }
    md += "\n### Max stable objects per renderer\n\n" +
          limitsTable(renderers, args.ratesHz, rows, args.verdict, "K");
    progress.finish(); // the results never share a line with the bar
    finishSweepReport(out, "paper1", md, plots);
    return 0;
}

} // namespace hapto::experiments
