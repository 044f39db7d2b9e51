// `hapto experiment paper1|paper2|meshes|scaling`: the paper's experiments and load scaling,
// measured by the real Runtime, written as CSV, JSON, markdown and gnuplot figures.

#include "Commands.h"
#include "Options.h"

#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/experiments/Experiments.h"
#include "hapto/experiments/Stats.h"
#include "hapto/experiments/Sweep.h"
#include "hapto/experiments/Table.h"

#include "hapto/io/InputError.h"

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace hapto::cli {
namespace {

using namespace hapto::experiments;

/// The options every experiment has; `quick` values apply unless the option was given.
struct CommonOptions {
    CLI::Option* out = nullptr;
    CLI::Option* duration = nullptr;
    CLI::Option* repeats = nullptr;
    std::string verdict = "design"; ///< --verdict's text (sweeps only), parsed after parsing.
    CLI::Option* verdictOption = nullptr;
    int quickRepeats = 1; ///< --repeats under --quick unless given.
};

/// A sweep list option (--counts, --rates, ...): its text, read by parseSweepList after parsing
/// so that every list takes the same forms (1,2,4; 1-8; 1:8; 1000:4000:1000).
struct ListOption {
    std::string text;
    CLI::Option* option = nullptr;
    /// True when the option was given.
    bool given() const { return option && option->count() > 0; }
};

/// Adds `name` as a sweep list option; `defaultText` shows in the help.
CLI::Option* addList(CLI::App* cmd, ListOption& list, const std::string& name,
                     const std::string& help, const std::string& defaultText) {
    list.text = defaultText;
    list.option = cmd->add_option(name, list.text,
                                  help + "; a list: 1,2,4 or a range 1-8 / 1:8 / 1:8:2 (whole "
                                         "numbers; A:B:STEP for any number)")
                      ->capture_default_str();
    return list.option;
}

/// The whole numbers of a list option from `min` to `max`, as T, ascending when `sorted`.
template <class T>
std::vector<T> countsOf(const ListOption& list, const std::string& name, double min, double max,
                        bool sorted) {
    std::vector<T> values;
    for (const std::int64_t v : parseCountList(list.text, name, min, max)) {
        values.push_back(static_cast<T>(v));
    }
    if (sorted) {
        std::sort(values.begin(), values.end());
    }
    return values;
}

void addCommon(CLI::App* cmd, CommonArgs& a, CommonOptions& o, const std::string& name) {
    a.out = "out/" + name;
    o.out = cmd->add_option("--out", a.out,
                            "Folder for the CSV, JSON, markdown and plot files (created)")
                ->capture_default_str();
    cmd->add_flag("--quick", a.quick,
                  "A smoke test of seconds: small sizes, 0.15 s per run, few repeats, the "
                  "report says which claims it cannot judge (options given explicitly still "
                  "apply)");
    o.duration = cmd->add_option("--duration", a.durationS,
                                 "Timed servo run per measurement (s); --quick: 0.15")
                     ->capture_default_str()
                     ->check(finiteRange(0.02, 60));
    o.repeats = cmd->add_option("--repeats", a.repeats,
                                "Runs per measurement; every figure is the median over them, "
                                "with its order-statistic interval (5 runs: [min, max], 93.75 % "
                                "coverage; 6 or more: 95 %); --quick: " +
                                    std::to_string(o.quickRepeats))
                    ->capture_default_str()
                    ->check(finiteRange(1, 99));
    addRealtimeFlag(cmd, a.realtime, "");
}

void applyQuick(CommonArgs& a, const CommonOptions& o) {
    if (a.quick) {
        if (o.duration->count() == 0) {
            a.durationS = 0.15;
        }
        if (o.repeats->count() == 0) {
            a.repeats = o.quickRepeats;
        }
    }
}

/// `--rates HZ,HZ` (and its deprecated spelling `--rate`): servo rates, 100..100000 Hz each.
CLI::Option* addRates(CLI::App* cmd, ListOption& rates, const std::vector<double>& ratesHz,
                      const std::string& note) {
    return addList(cmd, rates, "--rates,--rate",
                   "Servo rates (Hz, 100..100000); " + note + " (--rate: the old spelling)",
                   sweepListText(ratesHz));
}

/// The rates --rates gives, when it was given.
void applyRates(const ListOption& rates, std::vector<double>& ratesHz) {
    if (rates.given()) {
        ratesHz = parseSweepList(rates.text, "--rates", {100, 100000, false});
    }
}

CLI::Option* addVerdict(CLI::App* cmd, std::string& verdict) {
    return cmd
        ->add_option("--verdict", verdict,
                     "What stops a renderer's growth and names the first unstable size: design "
                     "(DESIGN.md: p99.9 load < 100 % and <= 0.1 % deadlines missed) or load "
                     "(p99.9 load < 100 % only, for machines whose wake-ups are late by "
                     "themselves); both verdicts are reported either way; --quick: load (the "
                     "paper's: the renderer's time against the period)")
        ->capture_default_str();
}

/// The options of a sweep experiment (paper1, paper2, meshes): the common ones and --verdict.
void addSweepCommon(CLI::App* cmd, CommonArgs& a, CommonOptions& o, const std::string& name) {
    addCommon(cmd, a, o, name);
    o.verdictOption = addVerdict(cmd, o.verdict);
}

/// After parsing a sweep experiment: applies --quick and returns the verdict --verdict names.
Verdict applySweepCommon(CommonArgs& a, const CommonOptions& o) {
    applyQuick(a, o);
    return sweepVerdict(a.quick, o.verdictOption->count() > 0,
                        parseVerdict(o.verdict, "--verdict"));
}

/// `--max-index-mb` of a sweep: the memory an index may be extrapolated to (MB) from the
/// previous `step` ("size" or "count") before the sweep skips it.
void addSweepIndexLimit(CLI::App* cmd, double& maxIndexMb, const std::string& step) {
    cmd->add_option("--max-index-mb", maxIndexMb,
                    "Skip an index whose memory, extrapolated from the previous " + step +
                        ", would pass this (MB)")
        ->capture_default_str()
        ->check(finiteRange(1e-3, 1e9));
}

/// Ends the process with an experiment's exit code unless it succeeded.
void exitOnFailure(int rc) {
    if (rc != 0) {
        std::exit(rc);
    }
}

/// `hapto experiment paper1`: lattices of growing K; --quick stops at K = 4.
void addPaper1Command(CLI::App* exp) {
    auto a = std::make_shared<Paper1Args>();
    auto o = std::make_shared<CommonOptions>();
    auto* cmd = exp->add_subcommand(
        "paper1",
        "Experiment 1: K x K x K lattices of 5 cm cubes (1 cm gaps) for growing K; renderers "
        "standard (brute), grid 2x2x2, grid 5x5x5, octree M=2 and M=5 (min leaf 5 mm); hands "
        "in the no touch / touch / sliding conditions (scripts free, touch, slide) just "
        "outside the lattice's +z face. A renderer stops growing after its first unstable "
        "K. Prints the analogue of the paper's Table 1 and the max stable objects");
    addSweepCommon(cmd, a->common, *o, "paper1");
    setExamples(cmd, {"hapto experiment paper1 --quick",
                      "hapto experiment paper1 --rates 1000 --max-per-side 20 --out out/p1",
                      "hapto experiment paper1 --per-side 2-12 --repeats 9"});
    auto rates = std::make_shared<ListOption>();
    addRates(cmd, *rates, a->ratesHz, "e.g. 1000,10000");
    auto perSide = std::make_shared<ListOption>();
    addList(cmd, *perSide, "--per-side",
            "K values to run (2..400, instead of the sizes up to --max-per-side)", "");
    auto* maxK = cmd->add_option("--max-per-side", a->maxPerSide,
                                 "Largest K (cubes per lattice side; K^3 objects); sizes "
                                 "2,3,4,5,6,8,10,13,16,20,25,32,40,50,64,80,100,... up to "
                                 "it; --quick: 4")
                     ->capture_default_str()
                     ->check(finiteRange(2, 400));
    addSweepIndexLimit(cmd, a->maxIndexMb, "size");
    cmd->callback([a, o, maxK, rates, perSide] {
        a->verdict = applySweepCommon(a->common, *o);
        applyRates(*rates, a->ratesHz);
        if (perSide->given()) {
            a->perSide = countsOf<int>(*perSide, "--per-side", 2, 400, true);
        }
        if (a->common.quick && maxK->count() == 0) {
            a->maxPerSide = 4;
        }
        exitOnFailure(runPaper1(*a));
    });
}

/// `hapto experiment paper2`: random scenes per count and seed; --quick runs 10, 20 and 50
/// objects with two seeds, --decades adds 10^3 .. 10^6.
void addPaper2Command(CLI::App* exp) {
    auto a = std::make_shared<Paper2Args>();
    auto o = std::make_shared<CommonOptions>();
    auto decades = std::make_shared<bool>(false);
    auto* cmd = exp->add_subcommand(
        "paper2",
        "Experiment 2: random scenes of 5 cm cubes in a 25 cm cube, several seeds per "
        "count, clear around the centre where the hand starts; renderers standard, grid "
        "2x2x2, grid 5x5x5 and octree M=2; conditions no touch / touch / sliding. Prints "
        "the analogue of the paper's Table 2 (200-object scenes) and the max stable objects");
    addSweepCommon(cmd, a->common, *o, "paper2");
    setExamples(cmd, {"hapto experiment paper2 --quick",
                      "hapto experiment paper2 --counts 100,200,500 --decades",
                      "hapto experiment paper2 --counts 100:1000:100"});
    auto counts = std::make_shared<ListOption>();
    std::string defaultCounts;
    for (const std::size_t n : a->counts) {
        defaultCounts += (defaultCounts.empty() ? "" : ",") + std::to_string(n);
    }
    auto* countsOpt = addList(cmd, *counts, "--counts",
                              "Objects per scene (1..1e8); --quick: 10,20,50", defaultCounts);
    cmd->add_flag("--decades", *decades,
                  "Also 1000, 10000, 100000 and 1000000 objects (a renderer still stops "
                  "after its first unstable count)");
    auto* seeds = cmd->add_option("--seeds", a->seeds, "Scenes per count (seeds 1..N); --quick: 2")
                      ->capture_default_str()
                      ->check(finiteRange(1, 100));
    auto rates = std::make_shared<ListOption>();
    addRates(cmd, *rates, a->ratesHz, "e.g. 1000,10000");
    cmd->add_option("--keep-clear", a->keepClearM,
                    "No object within this distance of the centre, where the hand starts (m)")
        ->capture_default_str()
        ->check(finiteRange(0.005, 0.1));
    addSweepIndexLimit(cmd, a->maxIndexMb, "count");
    cmd->callback([a, o, decades, countsOpt, counts, seeds, rates] {
        a->verdict = applySweepCommon(a->common, *o);
        applyRates(*rates, a->ratesHz);
        if (counts->given()) {
            a->counts = countsOf<std::size_t>(*counts, "--counts", 1, 1e8, true);
        }
        if (a->common.quick) {
            if (countsOpt->count() == 0) {
                a->counts = {10, 20, 50};
            }
            if (seeds->count() == 0) {
                a->seeds = 2;
            }
        }
        if (*decades) {
            for (const std::size_t n : {1000, 10000, 100000, 1000000}) {
                a->counts.push_back(n);
            }
        }
        exitOnFailure(runPaper2(*a));
    });
}

/// `hapto experiment meshes`: one generated closed mesh of growing triangle counts; --quick
/// stops at 1000 triangles.
void addMeshesCommand(CLI::App* exp) {
    auto a = std::make_shared<MeshesArgs>();
    auto o = std::make_shared<CommonOptions>();
    auto shape = std::make_shared<std::string>("sphere");
    auto* cmd = exp->add_subcommand(
        "meshes",
        "Load against triangle count: one generated closed mesh (geodesic sphere or torus, "
        "as `hapto scene mesh` makes) of 1e2, 3e2, 1e3, ... triangles up to --max-triangles; "
        "renderers standard (brute force), a uniform grid and an octree over the triangles; "
        "hands in the no touch / touch / sliding conditions pressing in from the mesh's +z "
        "side. A renderer stops growing after its first unstable size (brute force does "
        "long before 1e6)");
    addSweepCommon(cmd, a->common, *o, "meshes");
    setExamples(cmd, {"hapto experiment meshes --quick",
                      "hapto experiment meshes --shape torus --max-triangles 1e6"});
    auto rates = std::make_shared<ListOption>();
    addRates(cmd, *rates, a->ratesHz, "e.g. 1000,4000");
    auto triangles = std::make_shared<ListOption>();
    addList(cmd, *triangles, "--triangles",
            "Triangle counts to run (1e2..1e7, instead of 1 and 3 per decade up to "
            "--max-triangles)",
            "");
    cmd->add_option("--shape", *shape, "sphere or torus")
        ->capture_default_str()
        ->check(CLI::IsMember({"sphere", "torus"}));
    cmd->add_option("--size", a->sizeM, "The mesh's extent along x (m)")
        ->capture_default_str()
        ->check(finiteRange(0.01, 10));
    auto* maxTriangles =
        cmd->add_option("--max-triangles", a->maxTriangles,
                        "Largest triangle count (1e2 .. 1e7); e.g. 1e7 if memory allows "
                        "(about 0.25 GB of mesh plus the index); --quick: 1000")
            ->capture_default_str()
            ->transform(wholeNumber(static_cast<double>(kMinGeneratedTriangles),
                                    static_cast<double>(kMaxGeneratedTriangles)));
    cmd->add_option("--grid-cells", a->gridCells, "The grid renderer's cells per side")
        ->capture_default_str()
        ->check(finiteRange(1, 1024));
    cmd->add_option("--octree-max", a->octreeMaxItems, "The octree renderer's items per leaf")
        ->capture_default_str()
        ->check(finiteRange(1, 1000));
    cmd->add_option("--octree-min-leaf", a->octreeMinLeafM,
                    "The octree renderer's smallest leaf (m)")
        ->capture_default_str()
        ->check(finiteRange(1e-6, 1));
    addSweepIndexLimit(cmd, a->maxIndexMb, "size");
    cmd->callback([a, o, shape, maxTriangles, rates, triangles] {
        a->verdict = applySweepCommon(a->common, *o);
        applyRates(*rates, a->ratesHz);
        if (triangles->given()) {
            a->triangles = countsOf<std::size_t>(*triangles, "--triangles",
                                                 static_cast<double>(kMinGeneratedTriangles),
                                                 static_cast<double>(kMaxGeneratedTriangles), true);
        }
        a->shape = *parseMeshShape(*shape); // CLI11 checked the name
        if (a->common.quick && maxTriangles->count() == 0) {
            a->maxTriangles = 1000;
        }
        exitOnFailure(runMeshes(*a));
    });
}

/// `hapto experiment scaling`: 1, 2, 4, ... hands over one World, then the cursor walk;
/// --quick: two devices at 1 kHz, N = 100 and 1000, 20000 walk steps.
void addScalingCommand(CLI::App* exp) {
    auto a = std::make_shared<DevicesArgs>();
    auto o = std::make_shared<CommonOptions>();
    auto noCursor = std::make_shared<bool>(false);
    auto* cmd = exp->add_subcommand(
        "scaling",
        "Load scaling: 1, 2, 4, ... simulated hands (distinct seeds, clear start points) "
        "over one scene and one World, one servo thread each, at several rates: per-device "
        "and total load, misses, verdict. Then the three octree cursor strategies (root, "
        "climb, neighbour links) along one hand-speed walk over K^3 lattices: mean steps "
        "per locate against N (the paper's section 2.2.4)");
    o->quickRepeats = 3; // a cell of 2 devices for 0.15 s: three cost half a second
    addCommon(cmd, a->common, *o, "scaling");
    setExamples(cmd, {"hapto experiment scaling --quick",
                      "hapto experiment scaling --max-devices 8 --rates 1000,4000 --no-cursor",
                      "hapto experiment scaling --counts 1-8 --repeats 9 --no-cursor"});
    auto* maxDevices = cmd->add_option("--max-devices", a->maxDevices,
                                       "Largest device count; counts 1, 2, 4, ... up to it "
                                       "(unless --counts); --quick: 2")
                           ->capture_default_str()
                           ->check(finiteRange(1, 60));
    auto counts = std::make_shared<ListOption>();
    addList(cmd, *counts, "--counts", "Device counts to run (1..60), e.g. 1-8", "");
    auto rates = std::make_shared<ListOption>();
    auto* ratesOpt = addRates(cmd, *rates, a->ratesHz, "--quick: 1000");
    cmd->add_option("--scene", a->scene, "Scene file (default: the embedded default scene)");
    cmd->add_option("--index", a->index,
                    "Spatial index: brute, grid:N, octree:M:MIN (MIN in m), optional :aabb; "
                    "the cursor part uses it when it is an octree, else " +
                        std::string(kDefaultIndexSpec))
        ->capture_default_str();
    cmd->add_option("--max-index-mb", a->maxIndexMb,
                    "Most memory an index build may take (MB); a larger index is refused")
        ->capture_default_str()
        ->check(finiteRange(1, kMaxIndexMbOption));
    cmd->add_option("--script", a->script,
                    "Hand script: walk (random hops through the scene) or slide (slide on "
                    "the nearest surface)")
        ->capture_default_str();
    auto objects = std::make_shared<ListOption>();
    std::string defaultObjects;
    for (const std::size_t n : a->cursorObjects) {
        defaultObjects += (defaultObjects.empty() ? "" : ",") + std::to_string(n);
    }
    auto* objectsOpt = addList(cmd, *objects, "--cursor-objects",
                               "Cursor part: N values (1..1e8 objects; a K^3 lattice with K = "
                               "round(cbrt N)); --quick: 100,1000",
                               defaultObjects);
    auto* stepsOpt = cmd->add_option("--walk-steps", a->walkSteps,
                                     "Cursor part: walk length (1 ms steps, <= 0.5 mm "
                                     "each), e.g. 2e5; --quick: 20000")
                         ->capture_default_str()
                         ->transform(wholeNumber(1, 4e9));
    cmd->add_flag("--no-cursor", *noCursor, "Skip the cursor part");
    cmd->callback([a, o, noCursor, maxDevices, ratesOpt, objectsOpt, stepsOpt, counts, rates,
                   objects] {
        applyQuick(a->common, *o);
        applyRates(*rates, a->ratesHz);
        if (counts->given()) {
            a->deviceCounts = countsOf<int>(*counts, "--counts", 1, 60, false);
        }
        if (objects->given()) {
            a->cursorObjects = countsOf<std::size_t>(*objects, "--cursor-objects", 1, 1e8, false);
        }
        if (a->common.quick) {
            if (maxDevices->count() == 0) {
                a->maxDevices = 2;
            }
            if (ratesOpt->count() == 0) {
                a->ratesHz = {1000.0};
            }
            if (objectsOpt->count() == 0) {
                a->cursorObjects = {100, 1000};
            }
            if (stepsOpt->count() == 0) {
                a->walkSteps = 20000;
            }
        }
        a->cursor = !*noCursor;
        exitOnFailure(runDevices(*a));
    });
}

} // namespace

void addExperimentCommands(CLI::App& app) {
    CLI::App* exp = app.add_subcommand(
        "experiment",
        "Run the paper's experiments and the load-scaling experiment through the real runtime "
        "(servo threads, absolute deadlines); write CSV, JSON, markdown tables and gnuplot "
        "figures");
    exp->require_subcommand(1);
    setExamples(exp, {"hapto experiment paper1 --quick", "hapto experiment scaling --quick"});
    addPaper1Command(exp);
    addPaper2Command(exp);
    addMeshesCommand(exp);
    addScalingCommand(exp);
    addGraspExperimentCommand(exp);
    // `devices` is the command that lists hardware; the experiment is named for what it does.
    addRenamedCommand(exp, "devices", "hapto experiment scaling");
}

} // namespace hapto::cli
