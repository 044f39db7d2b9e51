// `hapto experiment meshes`: haptic load against the triangle count of one generated mesh.

#include "hapto/experiments/Experiments.h"
#include "hapto/experiments/Sweep.h"

#include "hapto/io/InputError.h"
#include "hapto/scenes/MeshGenerators.h"

#include <algorithm>
#include <string>
#include <vector>

namespace hapto::experiments {
namespace {

constexpr double kMeshStandOffM = 0.02; // start this far outside the mesh, on its +z side

/// The sizes: 1 and 3 per decade from 10^2 up to `maxTriangles` (which is always included).
std::vector<std::size_t> triangleSweep(std::size_t maxTriangles) {
    std::vector<std::size_t> sizes;
    for (std::size_t decade = 100; decade <= kMaxGeneratedTriangles; decade *= 10) {
        for (const std::size_t n : {decade, 3 * decade}) {
            if (n < maxTriangles) {
                sizes.push_back(n);
            }
        }
    }
    sizes.push_back(maxTriangles);
    return sizes;
}

MeshOptions meshOptions(const MeshesArgs& args, std::size_t triangles) {
    MeshOptions o;
    o.shape = args.shape;
    o.triangles = triangles;
    o.size = args.sizeM;
    o.seed = args.seed;
    return o;
}

/// On the z axis, kMeshStandOffM beyond the mesh's bounds. The touch and slide scripts press into
/// the mesh from there (the sphere's pole, the torus's outer equator) and slide along x; the
/// free walk moves in the padding around the mesh.
Vec3 meshStart(const Scene& scene) {
    return Vec3(0.0, 0.0, scene.object(0).aabb().max.z + kMeshStandOffM);
}

} // namespace

int runMeshes(const MeshesArgs& args) {
    if (args.shape == MeshShape::Terrain) {
        throw InputError("experiment meshes: --shape terrain is not measured: the touch and "
                         "slide hands need a closed mesh to press into (use sphere or torus)");
    }
    if (args.maxTriangles < kMinGeneratedTriangles || args.maxTriangles > kMaxGeneratedTriangles) {
        throw InputError("experiment meshes: --max-triangles must be in [" +
                         std::to_string(kMinGeneratedTriangles) + ", " +
                         std::to_string(kMaxGeneratedTriangles) + "], got " +
                         std::to_string(args.maxTriangles));
    }
    const std::filesystem::path out = prepareOutDir(args.common.out);
    const std::string gridName = "grid " + std::to_string(args.gridCells) + "^3";
    const std::string octreeName = "octree M=" + std::to_string(args.octreeMaxItems);
    const std::vector<SweepRenderer> renderers = {
        {"standard", IndexSpec::brute(), "-"},
        {gridName, IndexSpec::grid(args.gridCells), "-"},
        {octreeName, IndexSpec::octree(args.octreeMaxItems, args.octreeMinLeafM), "-"},
    };
    std::vector<SweepStep> steps;
    for (const std::size_t n :
         args.triangles.empty() ? triangleSweep(args.maxTriangles) : args.triangles) {
        const MeshOptions options = meshOptions(args, n);
        SweepStep step;
        step.objects = generatedTriangleCount(options);
        step.size = static_cast<int>(n);
        step.scenes.push_back({args.seed, [options] { return makeMeshScene(options); },
                               [](const Scene& scene, Condition) { return meshStart(scene); }});
        steps.push_back(std::move(step));
    }
    const SweepOptions options = sweepOptionsOf("meshes", args);

    Progress progress("meshes", renderers.size() * args.ratesHz.size() * steps.size() * 3);
    const std::vector<SweepRow> rows = runSweep(renderers, steps, options, progress);

    const auto plots = writeSweepFiles(out, "meshes",
                                       Json{{"shape", meshShapeName(args.shape)},
                                            {"size_m", args.sizeM},
                                            {"seed", args.seed},
                                            {"max_triangles", args.maxTriangles},
                                            {"grid_cells", args.gridCells},
                                            {"octree_max_items", args.octreeMaxItems},
                                            {"octree_min_leaf_m", args.octreeMinLeafM},
                                            {"stand_off_m", kMeshStandOffM}},
                                       args.common, args.maxIndexMb, renderers, args.ratesHz, rows,
                                       args.verdict, "triangles_asked", progress);

    std::string md =
        "## Load against triangle count: one " + std::string(meshShapeName(args.shape)) + " of " +
        fmt(args.sizeM, 3) + " m\n\n" +
        sweepSmokeHeader(args.common, args.verdict, steps.empty() ? 0 : steps.back().objects,
                         "where each renderer stops being stable") +
        loadNote(args.common, options.servo.tail, ": p50 / p99.9 / max,", "") +
        " A renderer stops growing after its first unstable size, and a cell whose "
        "probed tick takes more than 10 periods is skipped: that is what caps brute "
        "force.\n";
    md += "\n" + platformNote(rows, args.verdict);
    const auto lines = [&](const SweepRenderer& r, double rate) {
        std::vector<std::vector<std::string>> table;
        for (const SweepStep& step : steps) {
            std::vector<std::string> line{std::to_string(step.objects)};
            std::string build = "-";
            bool any = false;
            for (const Condition c : kConditions) {
                const SweepRow* row = findSweepRow(rows, r.name, rate, step.size, args.seed, c);
                line.push_back(row ? loadCell(*row) : "-");
                if (row && !row->skipped) {
                    build = fmt(row->buildS, 3) + " s, " + fmt(row->indexMb, 1) + " MB";
                }
                any = any || row;
            }
            line.push_back(build);
            if (any) {
                table.push_back(line);
            }
        }
        return table;
    };
    for (const double rate : args.ratesHz) {
        md += rendererTables(renderers, rate,
                             {"# triangles", "no touch", "touch", "sliding", "index build, memory"},
                             "", lines);
    }
    md += "\n### Max stable triangles per renderer\n\n" +
          limitsTable(renderers, args.ratesHz, rows, args.verdict, "triangles asked");
    progress.finish();
    finishSweepReport(out, "meshes", md, plots);
    return 0;
}

} // namespace hapto::experiments
