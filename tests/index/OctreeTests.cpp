#include "IndexTestScenes.h"
#include "OneThreadBuilds.h"

#include "hapto/index/Octree.h"
#include "hapto/index/UniformGrid.h"

#include <catch2/catch.hpp>

using namespace hapto;
using namespace hapto::test;

namespace {

// The node a neighbour link should name, found independently: walk down from the root toward
// the cell (level, c) and stop at that level or at a leaf.
std::uint32_t expectedNode(const Octree& tree, int level, std::array<std::int64_t, 3> c) {
    for (int a = 0; a < 3; ++a) {
        if (c[a] < 0 || c[a] >= (std::int64_t(1) << level)) {
            return kNoNode;
        }
    }
    std::uint32_t node = 0;
    while (tree.nodes()[node].level() < level && !tree.nodes()[node].isLeaf()) {
        const int shift = level - tree.nodes()[node].level() - 1;
        std::uint32_t octant = 0;
        for (int a = 0; a < 3; ++a) {
            octant |= std::uint32_t((c[a] >> shift) & 1) << a;
        }
        node = tree.nodes()[node].firstChild() + octant;
    }
    return node;
}

} // namespace

TEST_CASE("neighbour links name the equal-size neighbour, else the smallest larger one") {
    hapto::test::buildOnOneThread();
    for (const auto& [name, scene] : testScenes()) {
        for (const IndexSpec& spec : {IndexSpec::octree(2, 0.005), IndexSpec::octree(1, 0.001)}) {
            INFO(name << " " << spec.toString());
            const auto tree = Octree::build(scene, spec);
            std::size_t wrong = 0, outside = 0, larger = 0;
            for (std::uint32_t i = 0; i < tree->nodes().size(); ++i) {
                const OctreeNode& n = tree->nodes()[i];
                for (int face = 0; face < 6; ++face) {
                    std::array<std::int64_t, 3> c{n.cell(0), n.cell(1), n.cell(2)};
                    c[face / 2] += (face % 2) ? 1 : -1;
                    const std::uint32_t want = expectedNode(*tree, n.level(), c);
                    const std::uint32_t got = tree->neighbour(i, static_cast<Face>(face));
                    wrong += got != want;
                    outside += want == kNoNode;
                    larger += want != kNoNode && tree->nodes()[want].level() < n.level();
                    if (got != kNoNode) {
                        // It covers the face: shares the plane, and spans the face.
                        const Aabb a = tree->nodeBounds(i), b = tree->nodeBounds(got);
                        const int ax = face / 2;
                        wrong += (face % 2 ? b.min[ax] != a.max[ax] : b.max[ax] != a.min[ax]);
                        for (int o = 0; o < 3; ++o) {
                            wrong += o != ax && (b.min[o] > a.min[o] || b.max[o] < a.max[o]);
                        }
                    }
                }
            }
            CHECK(wrong == 0);
            CHECK(outside > 0);
            CHECK(larger > 0); // the scenes do exercise "smallest larger node"
        }
    }
}

TEST_CASE("octree layout: breadth first, siblings together, leaves one contiguous run each",
          "[threads]") {
    const Scene scene = makeDegenerateScene();
    const auto tree = Octree::build(scene, IndexSpec::octree(2, 0.002));
    const auto nodes = tree->nodes();
    REQUIRE(tree->parent(0) == kNoNode);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> runs;
    for (std::uint32_t i = 0; i < nodes.size(); ++i) {
        const OctreeNode& n = nodes[i];
        if (i > 0) {
            const std::uint32_t parent = tree->parent(i);
            REQUIRE(parent < i);
            CHECK(nodes[i - 1].level() <= n.level());
            CHECK(nodes[parent].firstChild() <= i);
            CHECK(i < nodes[parent].firstChild() + 8);
            CHECK(n.level() == nodes[parent].level() + 1);
            for (int a = 0; a < 3; ++a) { // the cell is the parent's octant i - firstChild
                CHECK(n.cell(a) ==
                      2 * nodes[parent].cell(a) + (((i - nodes[parent].firstChild()) >> a) & 1));
            }
        }
        if (n.isLeaf()) {
            runs.emplace_back(n.firstSlot(), n.slotCount());
            const auto objs = tree->leafObjects(i);
            CHECK(std::is_sorted(objs.begin(), objs.end()));
            CHECK(std::adjacent_find(objs.begin(), objs.end()) == objs.end());
        } else {
            CHECK(n.slotCount() == 0);
            for (std::uint32_t o = 0; o < 8; ++o) {
                CHECK(tree->parent(n.firstChild() + o) == i);
            }
        }
    }
    std::sort(runs.begin(), runs.end());
    std::uint64_t at = 0;
    for (const auto& [first, count] : runs) {
        CHECK(first == at);
        at += count;
    }
    CHECK(at == tree->slots().size());
    // The same scene builds the same tree (thread count and scheduling do not matter).
    const auto again = Octree::build(scene, IndexSpec::octree(2, 0.002));
    CHECK(std::equal(tree->slots().begin(), tree->slots().end(), again->slots().begin(),
                     again->slots().end()));
    CHECK(tree->nodes().size() == again->nodes().size());
    // Every array is sized exactly: the heap bytes the stats count (capacities) are what the
    // nodes, one parent per eight siblings, the slots and the outside list need.
    const std::uint64_t exact =
        nodes.size() * sizeof(OctreeNode) +
        ((nodes.size() - 1) / 8 + tree->slots().size() + tree->outsideObjects().size()) *
            sizeof(std::uint32_t);
    CHECK(tree->stats().bytes == exact);
}

TEST_CASE("the paper's set-ups: octree leaves stay small on lattice and random scenes",
          "[threads]") {
    LatticeOptions l;
    l.perSide = 20; // 8000 cubes, the paper's largest experiment-1 scene
    const Scene lattice = makeLatticeScene(l);
    const auto tree = Octree::build(lattice, IndexSpec::octree(2, 0.005));
    CHECK(tree->stats().objects == 8000);
    CHECK(tree->stats().maxObjectsPerLeaf <= 8); // a leaf at a lattice corner touches 8 cubes
    const auto t5 = Octree::build(lattice, IndexSpec::octree(5, 0.005));
    CHECK(t5->stats().nodes < tree->stats().nodes);
}

TEST_CASE("bad octree and grid specs are refused when built directly") {
    const Scene scene;
    IndexSpec bad = IndexSpec::octree(0, 0.005);
    CHECK_THROWS(Octree::build(scene, bad));
    bad = IndexSpec::octree(2, 0.0);
    CHECK_THROWS(Octree::build(scene, bad));
    CHECK_THROWS(UniformGrid::build(scene, IndexSpec::grid(0)));
}
