// The local BVH of a mesh: its queries equal a linear scan, and they never allocate. This
// binary replaces the global operator new to count allocations (tests/support/CountingNew.h),
// so it is a test binary of its own.

#include "CountingNew.h"
#include "TestMeshes.h"

#include "hapto/core/Random.h"
#include "hapto/scenes/TriangleMesh.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

using hapto::test::gAllocations;

using namespace hapto;

namespace {

/// The triangles whose local AABB overlaps the closed box, by a linear scan, ascending.
std::vector<std::uint32_t> linearScan(const TriangleMesh& mesh, const Aabb& q) {
    std::vector<std::uint32_t> out;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const auto [a, b, c] = mesh.corners(t);
        const Aabb box{glm::min(glm::min(a, b), c), glm::max(glm::max(a, b), c)};
        if (box.overlaps(q)) {
            out.push_back(t);
        }
    }
    return out;
}

/// A random query box around the mesh: sizes from a point to a quarter of the mesh.
Aabb randomBox(Random& rng, const Aabb& around) {
    const Vec3 size = around.size();
    Vec3 lo(0.0);
    for (int a = 0; a < 3; ++a) {
        lo[a] = rng.uniform(around.min[a] - 0.1 * size[a], around.max[a] + 0.1 * size[a]);
    }
    const double edge = rng.uniform() < 0.2 ? 0.0 : rng.uniform(0.0, 0.25) * size.x;
    return {lo, lo + Vec3(edge, rng.uniform(0.0, 1.0) * edge, rng.uniform(0.0, 1.0) * edge)};
}

} // namespace

TEST_CASE("a mesh's BVH finds exactly the triangles a linear scan finds") {
    const auto sphere = test::makeIcosphere(4, 0.05);      // 5120 triangles, closed
    const auto sheet = test::makeWavySheet(40, 0.2, 0.02); // 3200, open, flat-ish
    const auto tiny = test::makeWavySheet(1, 0.1, 0.0);    // 2 triangles: one leaf
    for (const auto* mesh : {sphere.get(), sheet.get(), tiny.get()}) {
        INFO(mesh->triangleCount() << " triangles");
        Random rng(mesh->triangleCount());
        std::size_t wrong = 0, nonEmpty = 0;
        for (int n = 0; n < 2000; ++n) {
            Aabb q = randomBox(rng, mesh->localBounds());
            if (n % 5 == 0) { // exactly a vertex: boxes touching it must be found
                const Vec3 v = mesh->vertices()[rng.below(mesh->vertices().size())];
                q = {v, v};
            }
            std::vector<std::uint32_t> got;
            mesh->forEachTriangleNear(q, [&](std::uint32_t t) { got.push_back(t); });
            std::sort(got.begin(), got.end());
            const std::vector<std::uint32_t> want = linearScan(*mesh, q);
            wrong += got != want; // also catches a triangle reported twice
            nonEmpty += !want.empty();
        }
        CHECK(wrong == 0);
        CHECK(nonEmpty > 100);
        // The whole bounds find every triangle; the sphere overload is the box around it.
        std::uint32_t all = 0;
        mesh->forEachTriangleNear(mesh->localBounds(), [&](std::uint32_t) { ++all; });
        CHECK(all == mesh->triangleCount());
        std::vector<std::uint32_t> bySphere;
        const Vec3 c = mesh->vertices()[0];
        mesh->forEachTriangleNear(c, 0.01, [&](std::uint32_t t) { bySphere.push_back(t); });
        std::sort(bySphere.begin(), bySphere.end());
        CHECK(bySphere == linearScan(*mesh, {c - Vec3(0.01), c + Vec3(0.01)}));
    }
}

TEST_CASE("a mesh's BVH is balanced, compact, and its nodes hold their triangles") {
    const auto mesh = test::makeIcosphere(5, 0.1); // 20480 triangles
    const auto nodes = mesh->bvhNodes();
    // Median splits: depth ceil(log2(20480 / 4)) = 13.
    CHECK(mesh->bvhDepth() <= 13);
    CHECK(mesh->bvhDepth() <= TriangleMesh::kBvhMaxDepth);
    const double perTriangle = double(mesh->bvhBytes()) / mesh->triangleCount();
    CHECK(perTriangle < 24.0); // 32-byte nodes for ~1/2 node per triangle, + 4 bytes order
    // Leaves cover every triangle once (through the query of the whole bounds).
    std::vector<int> seen(mesh->triangleCount(), 0);
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const MeshBvhNode& n = nodes[i];
        if (n.count == 0) {
            CHECK(n.first > i + 1); // the right child follows the left subtree
            continue;
        }
        CHECK(n.count <= TriangleMesh::kBvhLeafTriangles);
    }
    mesh->forEachTriangleNear(mesh->localBounds(), [&](std::uint32_t t) { ++seen[t]; });
    CHECK(std::all_of(seen.begin(), seen.end(), [](int c) { return c == 1; }));
}

TEST_CASE("a BVH query makes no heap allocation") {
    const auto mesh = test::makeIcosphere(5, 0.1);
    Random rng(5);
    std::vector<Aabb> boxes;
    for (int n = 0; n < 5000; ++n) {
        boxes.push_back(randomBox(rng, mesh->localBounds()));
    }
    std::uint64_t found = 0;
    const std::uint64_t before = gAllocations.load();
    for (const Aabb& q : boxes) {
        mesh->forEachTriangleNear(q, [&](std::uint32_t t) { found += t + 1; });
        mesh->forEachTriangleNear(q.center(), 0.003, [&](std::uint32_t) { ++found; });
    }
    const std::uint64_t during = gAllocations.load() - before;
    CHECK(during == 0);
    CHECK(found > 0);
    const auto another = test::makeWavySheet(2, 0.1, 0.0); // the counter is live
    CHECK(another->triangleCount() == 8);
    CHECK(gAllocations.load() > before);
}
