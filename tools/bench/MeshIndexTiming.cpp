// Times indexing one big mesh (a timing program beside the benchmarks, never a test). Builds an
// icosphere of 20 * 4^S triangles in C++ (TriangleMesh::make, which also builds the mesh's local
// BVH), puts it in a scene, and builds the grid and the octree over its triangles, printing the
// build time and bytes per triangle of each, and the BVH's.
//
//   index_mesh_timing [SUBDIVISIONS=8] [GRID_N=64] [OCTREE=octree:8:0.0005]

#include "TestMeshes.h"

#include "hapto/index/IndexSpec.h"
#include "hapto/index/SpatialIndex.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace hapto;

int main(int argc, char** argv) {
    const int subdivisions = argc > 1 ? std::atoi(argv[1]) : 8;
    const int gridN = argc > 2 ? std::atoi(argv[2]) : 64;
    const std::string octree = argc > 3 ? argv[3] : "octree:8:0.0005";
    using Clock = std::chrono::steady_clock;
    const auto seconds = [](Clock::time_point a, Clock::time_point b) {
        return std::chrono::duration<double>(b - a).count();
    };

    const auto t0 = Clock::now();
    const auto mesh = test::makeIcosphere(subdivisions, 0.1);
    const auto t1 = Clock::now();
    const std::uint32_t n = mesh->triangleCount();
    std::printf("icosphere: %u triangles, radius 0.1 m; generated + TriangleMesh::make (with "
                "BVH) %.3f s; BVH %zu nodes, depth %d, %.1f bytes/triangle\n",
                n, seconds(t0, t1), mesh->bvhNodes().size(), mesh->bvhDepth(),
                double(mesh->bvhBytes()) / n);
    const Scene scene(Scene::defaultBounds(std::vector<SceneObject>{makeMesh(1, Vec3(0.0), mesh)}),
                      {makeMesh(1, Vec3(0.0), mesh)});
    for (const std::string& text : {"grid:" + std::to_string(gridN), octree}) {
        IndexSpec spec = IndexSpec::parse(text);
        spec.maxBytes = ~std::uint64_t(0);
        const auto a = Clock::now();
        const auto index = buildIndex(scene, spec);
        const auto b = Clock::now();
        const IndexStats& s = index->stats();
        std::printf("%-18s build %.3f s (stats: %.3f s wall, %.3f s CPU), %llu nodes, depth %u, "
                    "%.2f items/leaf (max %u), %.1f bytes/triangle\n",
                    text.c_str(), seconds(a, b), s.buildSeconds, s.buildCpuSeconds,
                    static_cast<unsigned long long>(s.nodes), s.depth, s.meanObjectsPerLeaf,
                    s.maxObjectsPerLeaf, s.bytesPerObject);
    }
    return 0;
}
