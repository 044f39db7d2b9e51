#pragma once
/// The `hapto experiment` runs, as functions of their parsed arguments.

#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/index/DefaultIndex.h"

#include "hapto/scenes/MeshGenerators.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hapto::experiments {

/// Settings every experiment takes.
struct CommonArgs {
    std::string out;        ///< Output folder.
    bool quick = false;     ///< Seconds, small sizes (explicit options still win).
    double durationS = 0.5; ///< Timed run per repeat (s).
    /// Runs per cell; the median and its order-statistic interval are reported (Stats.h).
    int repeats = 5;
    bool realtime = true; ///< Ask for SCHED_FIFO and pinning.
};

/// `hapto experiment paper1`: the paper's experiment 1 (lattices of K^3 cubes).
struct Paper1Args {
    CommonArgs common;                   ///< Options every experiment takes (--out, --quick, ...).
    std::vector<double> ratesHz{1000.0}; ///< Servo rates (Hz).
    int maxPerSide = 100;                ///< Largest K (sizes 2, 3, 4, 5, 6, 8, ... up to it).
    std::vector<int> perSide{};          ///< K values to run, ascending (empty: from maxPerSide).
    double maxIndexMb = 3000.0;          ///< Largest index the sweep builds (MB).
    Verdict verdict = Verdict::Design;   ///< What stops a renderer's growth.
};
/// Runs experiment 1; returns the process exit code. [control]
int runPaper1(const Paper1Args& args);

/// `hapto experiment paper2`: the paper's experiment 2 (random scenes, several seeds).
struct Paper2Args {
    CommonArgs common; ///< Options every experiment takes (--out, --quick, ...).
    std::vector<std::size_t> counts{10, 20, 50, 100, 200, 500}; ///< Objects per scene.
    int seeds = 5;                       ///< Scenes per count (seeds 1..seeds).
    std::vector<double> ratesHz{1000.0}; ///< Servo rates (Hz).
    double keepClearM = 0.03;            ///< Clear radius around the start at the centre (m).
    double maxIndexMb = 3000.0;          ///< Largest index the sweep builds (MB).
    Verdict verdict = Verdict::Design;   ///< What stops a renderer's growth.
};
/// Runs experiment 2; returns the process exit code. [control]
int runPaper2(const Paper2Args& args);

/// `hapto experiment meshes`: load against the triangle count of one generated closed mesh.
struct MeshesArgs {
    CommonArgs common;                    ///< Options every experiment takes (--out, --quick, ...).
    std::vector<double> ratesHz{1000.0};  ///< Servo rates (Hz).
    MeshShape shape = MeshShape::Sphere;  ///< Sphere or torus (closed: the hands press into it).
    double sizeM = 0.2;                   ///< The mesh's extent along x (m).
    std::uint64_t seed = 1;               ///< Generator seed.
    std::size_t maxTriangles = 1'000'000; ///< Largest triangle count (sizes 1, 3 per decade).
    std::vector<std::size_t> triangles{}; ///< Triangle counts to run (empty: from maxTriangles).
    int gridCells = 32;                   ///< The grid renderer's cells per side.
    int octreeMaxItems = 8;               ///< The octree renderer's items per leaf (M).
    double octreeMinLeafM = 0.0005;       ///< The octree renderer's smallest leaf (m).
    double maxIndexMb = 3000.0;           ///< Largest index the sweep builds (MB).
    Verdict verdict = Verdict::Design;    ///< What stops a renderer's growth.
};
/// Runs the mesh experiment; returns the process exit code. [control]
int runMeshes(const MeshesArgs& args);

/// `hapto experiment scaling`: load against device count, and cursor steps against N.
struct DevicesArgs {
    CommonArgs common; ///< Options every experiment takes (--out, --quick, ...).
    int maxDevices =
        8; ///< Largest device count (1, 2, 4, ... up to it) when deviceCounts is empty.
    std::vector<int> deviceCounts{}; ///< Device counts to run, in order (empty: from maxDevices).
    std::vector<double> ratesHz{1000.0, 4000.0}; ///< Servo rates (Hz).
    std::string scene;                           ///< Scene file; empty = the default scene.
    std::string index{kDefaultIndexSpec};        ///< Index spec.
    std::uint64_t maxIndexMb = 1024;             ///< Index memory limit (MB).
    std::string script = "walk";                 ///< Hand script: walk or slide.
    std::vector<std::size_t> cursorObjects{100, 1000, 10000, 100000, 1000000}; ///< N values.
    std::size_t walkSteps = 200000; ///< Cursor walk length (1 ms steps).
    bool cursor = true;             ///< Run the cursor part.
};
/// Runs the device-scaling and cursor experiments; returns the process exit code. [control]
int runDevices(const DevicesArgs& args);

} // namespace hapto::experiments
