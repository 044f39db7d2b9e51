// The narrow phase and the index's box query allocate nothing: every pair kind through
// collide(), and visitLeaves on an octree, a grid and brute force, counted by the program-wide
// operator new of CountingNew.h (this is the one source of dynamics_contact_tests that
// includes it).

#include "ContactTestShapes.h"
#include "CountingNew.h"

#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <vector>

using namespace hapto;
using namespace hapto::contact_test;

TEST_CASE("Contact: collide() allocates nothing, for every pair kind") {
    const ConvexHull oct = octahedron(0.05);
    const ConvexHull cube = boxHull(Vec3(0.04));
    const TriangleCorners tri{Vec3(-1, 0, -1), Vec3(-1, 0, 2), Vec3(2, 0, -1)};
    const std::vector<ConvexShape> bodies{
        ConvexShape::sphere({0, 0.03, 0}, 0.04),
        ConvexShape::box({0.01, 0.02, 0}, rotation(0.3, {1, 1, 0}), {0.05, 0.03, 0.04}),
        ConvexShape::hullAt(oct, {0, 0.04, 0.01}, rotation(0.2, {0, 1, 1})),
        ConvexShape::hullAt(cube, {0.02, 0.03, 0}, rotation(0.5, {1, 0, 1}))};
    std::vector<ConvexShape> partners = bodies;
    partners.push_back(ConvexShape::triangleOf(tri, {0, 1, 0}));
    partners.push_back(ConvexShape::triangleOf(tri, Vec3(0.0)));
    ContactManifold m;
    int contacts = 0;
    const std::uint64_t before = test::gAllocations.load();
    for (const ConvexShape& a : bodies) {
        for (const ConvexShape& b : partners) {
            collide(a, b, 0.01, m);
            contacts += m.count;
            collide(b, a, 0.01, m);
            contacts += m.count;
        }
    }
    const std::uint64_t after = test::gAllocations.load();
    CHECK(after == before);
    CHECK(contacts > 0);
}

TEST_CASE("Box query: visitLeaves allocates nothing (octree, grid, brute force)", "[threads]") {
    RandomOptions r;
    r.count = 200;
    r.seed = 3;
    r.cubeSize = 0.02;
    const Scene scene = makeRandomScene(r);
    for (const IndexSpec& spec :
         {IndexSpec::octree(2, 0.005), IndexSpec::grid(8), IndexSpec::brute()}) {
        const auto index = buildIndex(scene, spec);
        std::uint64_t items = 0;
        auto count = [&](std::uint32_t leaf) {
            items += index->leafObjects(leaf).size();
            return true;
        };
        const Aabb box{scene.bounds().center() - Vec3(0.03), scene.bounds().center() + Vec3(0.03)};
        const std::uint64_t before = test::gAllocations.load();
        CHECK(index->visitLeavesWith(box, count));
        const bool outside = index->reachesOutside(box);
        const std::uint64_t after = test::gAllocations.load();
        CHECK(after == before);
        CHECK(items > 0);
        CHECK_FALSE(outside);
    }
}
