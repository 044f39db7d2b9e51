#include "IndexTestScenes.h"

#include "hapto/index/BruteForce.h"
#include "hapto/index/Cursor.h"
#include "hapto/index/Octree.h"
#include "hapto/index/UniformGrid.h"

#include <catch2/catch.hpp>

#include <numeric>

using namespace hapto;
using namespace hapto::test;

TEST_CASE("every object holding the query point is a candidate: every index, mode, strategy") {
    for (const auto& [name, scene] : testScenes()) {
        const std::vector<Vec3> points = queryPoints(scene, 3, 1500);
        const Containment containing(scene);
        std::vector<std::vector<std::uint32_t>> truth;
        for (const Vec3& p : points) {
            truth.push_back(containing(p));
        }
        for (const IndexSpec& spec : testSpecs()) {
            const auto index = buildIndex(scene, spec);
            std::vector<Vec3> all = points;
            // This index's own cell faces, edges and corners (a spread of leaves).
            const std::uint64_t nodes = index->stats().nodes;
            for (std::uint64_t k = 0; k < std::min<std::uint64_t>(nodes, 300); ++k) {
                addBoxPoints(index->leafBounds(static_cast<std::uint32_t>(k * nodes / 300)), all);
            }
            std::vector<std::vector<std::uint32_t>> want = truth;
            for (std::size_t i = points.size(); i < all.size(); ++i) {
                want.push_back(containing(all[i]));
            }
            for (const CursorStrategy strategy : {CursorStrategy::FromRoot, CursorStrategy::Climb,
                                                  CursorStrategy::NeighbourLinks}) {
                Cursor cursor(*index, strategy);
                std::size_t failures = 0;
                for (std::size_t i = 0; i < all.size(); ++i) {
                    const Vec3& p = all[i];
                    const LocateResult fresh = index->locate(p);
                    const LocateResult r = cursor.locate(p);
                    const bool in = index->inBounds(p);
                    bool ok = r.outside == !in && fresh.outside == !in && r.leaf == fresh.leaf &&
                              std::is_sorted(r.candidates.begin(), r.candidates.end());
                    if (scene.bounds().contains(p)) {
                        ok = ok && in;
                    }
                    if (in) {
                        ok = ok && includesAll(r.candidates, want[i]) &&
                             includesAll(fresh.candidates, want[i]);
                    } else if (spec.kind == IndexSpec::Kind::BruteForce) {
                        // The standard renderer tests every object, in the bounds or not.
                        ok = ok && r.candidates.size() == scene.size() && r.leaf == kNoLeaf;
                    } else {
                        ok = ok && r.candidates.empty() && r.leaf == kNoLeaf;
                    }
                    if (!ok && ++failures <= 3) {
                        INFO(name << " " << spec.toString() << " strategy " << int(strategy)
                                  << " point " << i << " (" << p.x << ", " << p.y << ", " << p.z
                                  << ")");
                        CHECK(ok);
                    }
                }
                CHECK(failures == 0);
            }
        }
    }
}

TEST_CASE("a grid cell holds exactly the objects overlapping it (brute-force check)") {
    for (const auto& [name, scene] : testScenes()) {
        std::vector<OverlapShape> shapes;
        for (const SceneObject& o : scene.objects()) {
            shapes.push_back(OverlapShape::of(o));
        }
        for (const IndexSpec& spec : {IndexSpec::grid(1), IndexSpec::grid(7),
                                      IndexSpec::grid(7, OverlapMode::Aabb), IndexSpec::grid(16)}) {
            INFO(name << " " << spec.toString());
            const auto grid = UniformGrid::build(scene, spec);
            std::size_t mismatches = 0;
            for (std::uint32_t cell = 0; cell < grid->cellCount(); ++cell) {
                const Aabb box = grid->leafBounds(cell);
                std::vector<std::uint32_t> want;
                for (std::uint32_t s = 0; s < scene.size(); ++s) {
                    if (overlaps(shapes[s], box, spec.mode)) {
                        want.push_back(s);
                    }
                }
                const auto got = grid->leafObjects(cell);
                mismatches += !std::equal(got.begin(), got.end(), want.begin(), want.end());
            }
            CHECK(mismatches == 0);
            // The cells tile the bounds exactly: shared faces are the same doubles.
            const int n = grid->cellsPerSide();
            CHECK(grid->leafBounds(grid->cellId(0, 0, 0)).min == grid->bounds().min);
            CHECK(grid->leafBounds(grid->cellId(n - 1, n - 1, n - 1)).max == grid->bounds().max);
            CHECK(grid->bounds().max.x >= scene.bounds().max.x);
            if (n > 1) {
                CHECK(grid->leafBounds(grid->cellId(0, 0, 0)).max.x ==
                      grid->leafBounds(grid->cellId(1, 0, 0)).min.x);
            }
        }
    }
}

TEST_CASE("octree leaves hold at most M objects unless at minimum size, exactly the overlapping") {
    for (const auto& [name, scene] : testScenes()) {
        std::vector<OverlapShape> shapes;
        for (const SceneObject& o : scene.objects()) {
            shapes.push_back(OverlapShape::of(o));
        }
        for (const IndexSpec& spec : {IndexSpec::octree(2, 0.005), IndexSpec::octree(1, 0.001),
                                      IndexSpec::octree(5, 0.005, OverlapMode::Aabb)}) {
            INFO(name << " " << spec.toString());
            const auto tree = Octree::build(scene, spec);
            std::size_t overfull = 0, wrongSize = 0, mismatches = 0, leaves = 0, atMin = 0;
            std::uint64_t pairs = 0;
            for (std::uint32_t i = 0; i < tree->nodes().size(); ++i) {
                const OctreeNode& n = tree->nodes()[i];
                if (!n.isLeaf()) {
                    continue;
                }
                ++leaves;
                pairs += n.slotCount;
                const Aabb box = tree->nodeBounds(i);
                const double edge = std::max({box.size().x, box.size().y, box.size().z});
                // At minimum size exactly when halving would go below MIN.
                wrongSize += (n.atMinimumSize != 0) != (edge / 2 < spec.minLeafSize * (1 - 1e-12));
                atMin += n.atMinimumSize;
                if (!n.atMinimumSize && n.slotCount > static_cast<std::uint32_t>(spec.maxObjects)) {
                    ++overfull;
                }
                std::vector<std::uint32_t> want;
                for (std::uint32_t s = 0; s < scene.size(); ++s) {
                    if (overlaps(shapes[s], box, spec.mode)) {
                        want.push_back(s);
                    }
                }
                const auto got = tree->leafObjects(i);
                mismatches += !std::equal(got.begin(), got.end(), want.begin(), want.end());
            }
            CHECK(overfull == 0);
            CHECK(wrongSize == 0);
            CHECK(mismatches == 0);
            CHECK(tree->stats().leaves == leaves);
            CHECK(tree->stats().leavesAtMinimumSize == atMin);
            CHECK(tree->stats().objectCellPairs == pairs);
            CHECK(tree->stats().nodes == tree->nodes().size());
        }
    }
}

TEST_CASE("OBB placement never gives more object-cell pairs than AABB placement") {
    for (const auto& [name, scene] : testScenes()) {
        for (const auto& [obb, aabb] :
             {std::pair{IndexSpec::grid(5), IndexSpec::grid(5, OverlapMode::Aabb)},
              std::pair{IndexSpec::grid(16), IndexSpec::grid(16, OverlapMode::Aabb)},
              std::pair{IndexSpec::octree(2, 0.005),
                        IndexSpec::octree(2, 0.005, OverlapMode::Aabb)},
              std::pair{IndexSpec::octree(8, 0.002),
                        IndexSpec::octree(8, 0.002, OverlapMode::Aabb)}}) {
            INFO(name << " " << obb.toString());
            const auto a = buildIndex(scene, obb);
            const auto b = buildIndex(scene, aabb);
            CHECK(a->stats().objectCellPairs <= b->stats().objectCellPairs);
            if (obb.kind == IndexSpec::Kind::Grid) { // cell by cell, a subset
                for (std::uint32_t c = 0; c < a->stats().leaves; ++c) {
                    const auto x = a->leafObjects(c), y = b->leafObjects(c);
                    CHECK(std::includes(y.begin(), y.end(), x.begin(), x.end()));
                }
            }
        }
    }
    // On rotated cubes the tighter fit shows (the paper's Fig. 2).
    RandomOptions r;
    r.count = 500;
    r.rotate = true;
    r.cubeSize = 0.02;
    const Scene s = makeRandomScene(r);
    CHECK(buildIndex(s, IndexSpec::grid(16))->stats().objectCellPairs <
          buildIndex(s, IndexSpec::grid(16, OverlapMode::Aabb))->stats().objectCellPairs);
}

TEST_CASE("stats add up; brute force lists everything; an empty scene works") {
    const Scene scene = makeDegenerateScene();
    const auto brute = buildIndex(scene, IndexSpec::brute());
    CHECK(brute->stats().leaves == 1);
    CHECK(brute->stats().objectCellPairs == scene.size());
    CHECK(brute->locate(Vec3(0.0)).candidates.size() == scene.size());
    CHECK(brute->locate(Vec3(1.0)).outside);
    for (const IndexSpec& spec : testSpecs()) {
        const auto index = buildIndex(scene, spec);
        const IndexStats& s = index->stats();
        INFO(spec.toString());
        CHECK(s.index == spec.toString());
        CHECK(s.objects == scene.size());
        std::uint64_t binned = 0;
        for (const IndexStats::Bin& b : s.objectsPerLeaf) {
            binned += b.leaves;
            CHECK(b.minObjects <= b.maxObjects);
        }
        CHECK(binned == s.leaves);
        CHECK(s.bytes > 0);
        CHECK(s.buildSeconds >= 0.0);
        CHECK(s.meanObjectsPerLeaf == Approx(double(s.objectCellPairs) / double(s.leaves)));
    }
    const Scene empty;
    for (const IndexSpec& spec : testSpecs()) {
        const auto index = buildIndex(empty, spec);
        const LocateResult r = index->locate(Vec3(0.0));
        CHECK_FALSE(r.outside);
        CHECK(r.candidates.empty());
    }
}
