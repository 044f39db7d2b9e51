// The default index rule (hapto/index/DefaultIndex.h): what a scene gets when no index is asked
// for, and a session's index from an optional spec text.

#include "hapto/index/DefaultIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/scenes/SceneObject.h"

#include <catch2/catch.hpp>

#include <cstdint>

#include <utility>
#include <vector>

using namespace hapto;

namespace {

/// A strip of `n` right triangles with legs `leg` (m): each one's longest edge is leg * sqrt 2.
SceneObject strip(ObjectId id, int n, double leg) {
    std::vector<Vec3> v;
    std::vector<TriangleIndices> t;
    for (int i = 0; i <= n; ++i) {
        v.push_back(Vec3(i * leg, 0, 0));
        v.push_back(Vec3(i * leg, leg, 0));
    }
    for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(n); ++i) {
        t.push_back(i % 2 == 0 ? TriangleIndices{i, i + 2, i + 1}
                               : TriangleIndices{i, i + 1, i + 2});
    }
    return makeMesh(id, Vec3(0.0), TriangleMesh::make(std::move(v), std::move(t), {}, "strip"));
}

} // namespace

TEST_CASE("the default index is the paper's octree over boxes and spheres, and over meshes an "
          "octree whose smallest leaf is the median triangle's longest edge") {
    const Aabb bounds{Vec3(-1.0), Vec3(1.0)};
    CHECK(defaultIndexSpec(Scene(bounds, {makeBox(1, Vec3(0.0), Vec3(0.01))})) ==
          kDefaultIndexSpec);
    CHECK(defaultIndexSpec(Scene()) == kDefaultIndexSpec);
    // Triangles whose longest edge is 0.3 mm x sqrt 2 = 0.424 mm (median of all of them: 40 of
    // them against 3 of 1 cm legs), with a box beside them.
    const Scene fine(bounds,
                     {makeBox(1, Vec3(0.5), Vec3(0.01)), strip(2, 40, 0.0003), strip(3, 3, 0.01)});
    CHECK(defaultIndexSpec(fine) == "octree:8:0.00042");
    // Clamped: within 0.1 mm and 5 mm.
    CHECK(defaultIndexSpec(Scene(bounds, {strip(1, 5, 1e-6)})) == "octree:8:0.0001");
    CHECK(defaultIndexSpec(Scene(bounds, {strip(1, 5, 0.1)})) == "octree:8:0.005");
    // A session's index: the given spec, or the default when none is given; with its limit.
    CHECK(sessionIndexSpec("", fine, 64).toString() == "octree:8:0.00042");
    CHECK(sessionIndexSpec("grid:4", fine, 64).toString() == "grid:4");
    CHECK(sessionIndexSpec("", fine, 64).maxBytes == 64u << 20);
    CHECK_THROWS_AS(sessionIndexSpec("kdtree:3", fine, 64), InputError);
}

TEST_CASE("the one default index spec is the paper's octree: 2 objects a leaf, 5 mm leaves") {
    CHECK(kDefaultIndexSpec == "octree:2:0.005");
    CHECK(IndexSpec::parse(kDefaultIndexSpec) == IndexSpec::octree(2, 0.005));
    CHECK(sessionIndexSpec("", Scene()) == IndexSpec::octree(2, 0.005));
}
