#include "IndexTestScenes.h"
#include "OneThreadBuilds.h"

#include "hapto/index/BruteForce.h"
#include "hapto/index/Cursor.h"
#include "hapto/index/Octree.h"
#include "hapto/index/UniformGrid.h"
#include "hapto/scenes/MeshGenerators.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <numbers>
#include <numeric>
#include <regex>

using namespace hapto;
using namespace hapto::test;

TEST_CASE("every item holding the query point is a candidate: every index, mode, strategy") {
    hapto::test::buildOnOneThread();
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
                        // The standard renderer tests every item, in the bounds or not.
                        ok = ok && r.candidates.size() == index->itemCount() && r.leaf == kNoLeaf;
                    } else {
                        // Outside: the objects reaching outside the bounds, which include every
                        // object holding the point (index ⊇ brute force out here too).
                        const auto outside = index->outsideObjects();
                        ok = ok && r.leaf == kNoLeaf && includesAll(r.candidates, want[i]) &&
                             includesAll(fresh.candidates, want[i]) &&
                             std::equal(r.candidates.begin(), r.candidates.end(), outside.begin(),
                                        outside.end());
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

TEST_CASE("a grid cell holds exactly the items overlapping it (brute-force check)", "[threads]") {
    for (const auto& [name, scene] : testScenes()) {
        const auto shapes = itemShapes(scene);
        for (const IndexSpec& spec : {IndexSpec::grid(1), IndexSpec::grid(7),
                                      IndexSpec::grid(7, OverlapMode::Aabb), IndexSpec::grid(16)}) {
            INFO(name << " " << spec.toString());
            const auto grid = UniformGrid::build(scene, spec);
            std::size_t mismatches = 0;
            for (std::uint32_t cell = 0; cell < grid->cellCount(); ++cell) {
                // The cell prepared once for every item (overlaps(shape, Aabb) prepares it per
                // call: most of this reference's time under the sanitizers).
                const OverlapCell box = OverlapCell::of(grid->leafBounds(cell));
                std::vector<std::uint32_t> want;
                for (const auto& [item, shape] : shapes) {
                    if (overlaps(shape, box, spec.mode)) {
                        want.push_back(item);
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

TEST_CASE("octree leaves hold at most M items unless at minimum size, exactly the overlapping") {
    hapto::test::buildOnOneThread();
    for (const auto& [name, scene] : testScenes()) {
        const auto shapes = itemShapes(scene);
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
                pairs += n.slotCount();
                const Aabb box = tree->nodeBounds(i);
                const double edge = std::max({box.size().x, box.size().y, box.size().z});
                // At minimum size exactly when halving would go below MIN.
                const bool atMinimumSize = tree->atMinimumSize(i);
                wrongSize += atMinimumSize != (edge / 2 < spec.minLeafSize * (1 - 1e-12));
                atMin += atMinimumSize;
                if (!atMinimumSize && n.slotCount() > static_cast<std::uint32_t>(spec.maxObjects)) {
                    ++overfull;
                }
                const OverlapCell cell = OverlapCell::of(box); // once for every item
                std::vector<std::uint32_t> want;
                for (const auto& [item, shape] : shapes) {
                    if (overlaps(shape, cell, spec.mode)) {
                        want.push_back(item);
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

TEST_CASE("OBB placement never gives more object-cell pairs than AABB placement", "[threads]") {
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

TEST_CASE("stats add up, brute force lists everything, an empty scene works") {
    hapto::test::buildOnOneThread();
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

TEST_CASE("a point outside the bounds but inside an object that reaches out gets that object",
          "[threads]") {
    // Bounds +-0.1 m; object 7 straddles the +x face, 9 lies wholly outside, 8 wholly inside.
    const Scene scene({Vec3(-0.1), Vec3(0.1)},
                      {makeBox(7, {0.1, 0.0, 0.0}, Vec3(0.02)), makeBox(8, Vec3(0.0), Vec3(0.01)),
                       makeSphere(9, {0.0, -0.2, 0.0}, 0.03),
                       makeBox(10, {-0.05, 0.05, 0.0}, Vec3(0.01, 0.01, 0.01),
                               glm::angleAxis(0.6, glm::normalize(Vec3(1, 2, 3))))});
    const Vec3 outsideIn7(0.11, 0.005, -0.005);
    const Vec3 outsideIn9(0.0, -0.21, 0.01);
    REQUIRE(scene.object(0).contains(outsideIn7));
    REQUIRE(scene.object(2).contains(outsideIn9));
    for (const IndexSpec& spec :
         {IndexSpec::grid(4), IndexSpec::grid(1), IndexSpec::octree(1, 0.01),
          IndexSpec::octree(2, 0.005, OverlapMode::Aabb)}) {
        INFO(spec.toString());
        const auto index = buildIndex(scene, spec);
        const std::vector<std::uint32_t> reaching{0, 2}; // slots of ids 7 and 9
        CHECK(std::vector<std::uint32_t>(index->outsideObjects().begin(),
                                         index->outsideObjects().end()) == reaching);
        CHECK(index->stats().outsideObjects == 2);
        for (const CursorStrategy strategy :
             {CursorStrategy::FromRoot, CursorStrategy::Climb, CursorStrategy::NeighbourLinks}) {
            Cursor cursor(*index, strategy);
            // Inside first, so the cursor has a cached leaf when the point leaves the bounds.
            const LocateResult inside = cursor.locate({0.095, 0.0, 0.0});
            CHECK_FALSE(inside.outside);
            CHECK(includesAll(inside.candidates, {0}));
            const LocateResult out = cursor.locate(outsideIn7);
            CHECK(out.outside);
            CHECK(out.leaf == kNoLeaf);
            CHECK(includesAll(out.candidates, {0}));
            CHECK(includesAll(cursor.locate(outsideIn9).candidates, {2}));
            // Back inside: the leaf's own candidates again, same as a fresh locate.
            const LocateResult back = cursor.locate(Vec3(0.0));
            CHECK_FALSE(back.outside);
            CHECK(back.leaf == index->locate(Vec3(0.0)).leaf);
            CHECK(includesAll(back.candidates, {1}));
        }
    }
}

TEST_CASE("an index that would exceed its memory limit is refused before it is built") {
    hapto::test::buildOnOneThread();
    // Three boxes filling the bounds: every one of them in every cell of a fine grid.
    const Scene scene({Vec3(-0.1), Vec3(0.1)},
                      {makeBox(1, Vec3(0.0), Vec3(0.1)), makeBox(2, Vec3(0.0), Vec3(0.099)),
                       makeBox(3, Vec3(0.001), Vec3(0.098))});
    IndexSpec fine = IndexSpec::grid(256);
    // 2 * 256^3 cell offsets and counters of 4 bytes and nearly 3 * 256^3 pairs of 8 bytes:
    // about 530 MB.
    const std::uint64_t need = estimateIndexBytes(scene, fine);
    CHECK(need >= (2ull * 4 + 2 * 8) * 256 * 256 * 256);
    CHECK(need < 600ull << 20);
    fine.maxBytes = 256ull << 20;
    CHECK_THROWS_AS(buildIndex(scene, fine), IndexTooLargeError);
    CHECK_THROWS_AS(buildIndex(scene, fine), InputError); // reported as bad input (exit 2)
    CHECK_THROWS_WITH(buildIndex(scene, fine),
                      Catch::StartsWith("index grid:256 would need about ") &&
                          Catch::Contains("more than the 256 MB limit") &&
                          Catch::Contains("--max-index-mb"));

    // Identical objects never separate, so M = 1 would split them down to MIN: the estimate's
    // floor (every cell inside the boxes lists all four) refuses it before building anything.
    std::vector<SceneObject> same;
    for (ObjectId id = 0; id < 4; ++id) {
        same.push_back(makeBox(id, Vec3(0.0123), Vec3(0.03)));
    }
    const Scene stacked({Vec3(-0.1), Vec3(0.1)}, std::move(same));
    IndexSpec deep = IndexSpec::octree(1, 1e-9);
    deep.maxBytes = 8ull << 20;
    CHECK(estimateIndexMemory(stacked, deep).atLeastBytes > deep.maxBytes);
    CHECK_THROWS_WITH(buildIndex(stacked, deep),
                      Catch::StartsWith("index octree:1:1e-09 would need more than ") &&
                          Catch::Contains("at least ") && Catch::Contains("nodes over 4 items") &&
                          Catch::Contains("--max-index-mb"));

    // Within the limit, the estimate bounds what the index really holds, the octree's from
    // both sides.
    for (const auto& [name, s] : testScenes()) {
        for (const IndexSpec& spec : testSpecs()) {
            const auto index = buildIndex(s, spec);
            const IndexMemoryEstimate e = estimateIndexMemory(s, spec);
            INFO(name << " " << spec.toString());
            CHECK(index->stats().bytes <= e.atMostBytes);
            CHECK(e.atLeastBytes <= e.atMostBytes);
            CHECK(e.atMostBytes == estimateIndexBytes(s, spec));
            if (spec.kind == IndexSpec::Kind::Octree) {
                CHECK(e.nodesAtLeast <= index->stats().nodes);
                CHECK(e.atLeastBytes <= index->stats().buildPeakBytes);
                CHECK(index->stats().buildPeakBytes <= e.atMostBytes);
            }
        }
    }
}

namespace {

/// Five boxes, each over most of the bounds, each a little offset: every cell deep inside
/// lists all five, so a small M splits them down to MIN.
Scene fiveLargeBoxes() {
    std::vector<SceneObject> o;
    const Vec3 offsets[5] = {Vec3(0.0), Vec3(0.005, 0, 0), Vec3(0, 0.005, 0), Vec3(0, 0, 0.005),
                             Vec3(-0.005, 0, 0)};
    for (ObjectId id = 0; id < 5; ++id) {
        o.push_back(makeBox(id, offsets[id], Vec3(0.04)));
    }
    return Scene({Vec3(-0.05), Vec3(0.05)}, std::move(o));
}

} // namespace

TEST_CASE("an octree's memory floor refuses a spec at once and never refuses what fits",
          "[threads]") {
    const Scene five = fiveLargeBoxes();
    // Issue 39: building this one level by level took 14 s and 1.4 GB before its refusal.
    const IndexSpec huge = IndexSpec::octree(1, 1e-9);
    const IndexMemoryEstimate e = estimateIndexMemory(five, huge);
    CHECK(e.atLeastBytes > huge.maxBytes);
    CHECK(e.nodesAtLeast > (std::uint64_t(1) << 26)); // more than Octree::kMaxNodes
    CHECK_THROWS_AS(buildIndex(five, huge), IndexTooLargeError);
    // A coarser spec whose tree has some 10^7 nodes by depth 8: refused by the floor (its cell
    // counts and the level's check it bounds), not by the build after the levels that fit.
    const IndexSpec deep = IndexSpec::octree(1, 0.0002);
    CHECK(estimateIndexMemory(five, deep).atLeastBytes > deep.maxBytes);
    CHECK_THROWS_WITH(buildIndex(five, deep), Catch::Contains("nodes over 5 items"));

    // Specs that fit: the build passes with its limit at its own peak accounting, and is
    // refused one byte below it (by the floor or by the check before a level's allocation,
    // whose message names the level's nodes once).
    RandomOptions r;
    r.count = 2000;
    r.seed = 11;
    r.cubeSize = 0.01;
    r.rotate = true;
    const std::pair<std::string, Scene> scenes[] = {{"five boxes", fiveLargeBoxes()},
                                                    {"random", makeRandomScene(r)}};
    for (const auto& [name, scene] : scenes) {
        for (const IndexSpec& base :
             {IndexSpec::octree(1, 0.004), IndexSpec::octree(2, 0.002), IndexSpec::octree(8, 0.001),
              IndexSpec::octree(1, 0.004, OverlapMode::Aabb)}) {
            INFO(name << " " << base.toString());
            const auto index = buildIndex(scene, base);
            const IndexStats& st = index->stats();
            const IndexMemoryEstimate bound = estimateIndexMemory(scene, base);
            CHECK(bound.nodesAtLeast <= st.nodes);
            CHECK(bound.atLeastBytes <= st.buildPeakBytes);
            CHECK(st.bytes <= bound.atMostBytes);
            CHECK(st.buildPeakBytes <= bound.atMostBytes);
            IndexSpec exact = base;
            exact.maxBytes = st.buildPeakBytes;
            CHECK(buildIndex(scene, exact)->stats().nodes == st.nodes);
            exact.maxBytes = st.buildPeakBytes - 1;
            try {
                (void)buildIndex(scene, exact);
                FAIL("built above its limit");
            } catch (const IndexTooLargeError& err) {
                const std::string what = err.what();
                const auto at = what.find(" nodes by depth ");
                if (at != std::string::npos) { // the level check: at most the tree's nodes
                    const auto from = what.rfind('(', at) + 1;
                    CHECK(std::stoull(what.substr(from, at - from)) <= st.nodes);
                } else {
                    CHECK_THAT(what, Catch::Contains("nodes over"));
                }
            }
        }
    }
}

TEST_CASE("the octree floor counts cells shared by overlapping items and stays a floor") {
    hapto::test::buildOnOneThread();
    // Items that overlap only here and there: the global count finds nothing, the pairs do.
    RandomOptions r;
    r.count = 3000;
    r.seed = 3;
    r.cubeSize = 0.01;
    const Scene sparse = makeRandomScene(r);
    IndexSpec deep = IndexSpec::octree(1, 1e-9);
    deep.maxBytes = 64ull << 20;
    CHECK(estimateIndexMemory(sparse, deep).atLeastBytes > deep.maxBytes);
    CHECK_THROWS_WITH(buildIndex(sparse, deep), Catch::Contains("nodes over 3000 items"));

    // Apart by more than MIN, M = 1 fits however small MIN: the floor must not refuse it.
    LatticeOptions apart;
    apart.perSide = 8;
    apart.cubeSize = 0.01;
    apart.gap = 0.004;
    const Scene lattice = makeLatticeScene(apart);
    IndexSpec fine = IndexSpec::octree(1, 1e-9);
    const auto tree = buildIndex(lattice, fine);
    fine.maxBytes = 1;
    CHECK(estimateIndexMemory(lattice, fine).nodesAtLeast <= tree->stats().nodes);

    // Items that do not overlap but sit closer than a level's cells: every cell spanning a gap
    // lists two cubes, few per pair, so the largest group says little; the pairs' distinct
    // cells add up, and the spec is refused by the floor before anything is built.
    LatticeOptions gaps;
    gaps.perSide = 24;
    gaps.cubeSize = 0.01;
    gaps.gap = 0.001;
    const Scene near = makeLatticeScene(gaps);
    CHECK_THROWS_WITH(buildIndex(near, deep), Catch::Contains("nodes over 13824 items"));
    // With M = 2 a split cell spans two gaps (a lattice's corner, four cubes): the near groups
    // find them where no three cubes share any volume.
    IndexSpec corners = IndexSpec::octree(2, 1e-9);
    corners.maxBytes = 1;
    corners.maxBytes = estimateIndexMemory(near, corners).atLeastBytes;
    const std::uint64_t cornersFloor = estimateIndexMemory(near, corners).nodesAtLeast;
    corners.maxBytes = 4ull << 30;
    const std::uint64_t cornersReal = buildIndex(near, corners)->stats().nodes;
    CHECK(cornersFloor > 10000);
    CHECK(cornersFloor <= cornersReal);
    // When the groups' cells still fit, every shallow cell's cubes are counted: at M = 2 and 3
    // the lattice splits only where a cell spans gaps (no cell under 1 mm does), so the counts
    // find a large part of the real tree (here over 40 %), not a few corners (6 %).
    for (const int m : {2, 3}) {
        INFO("M = " << m);
        IndexSpec counted = IndexSpec::octree(m, 1e-9);
        counted.maxBytes = 4ull << 30;
        const std::uint64_t real = m == 2 ? cornersReal : buildIndex(near, counted)->stats().nodes;
        counted.maxBytes = 1;
        counted.maxBytes = estimateIndexMemory(near, counted).atMostBytes - 1;
        const std::uint64_t floor = estimateIndexMemory(near, counted).nodesAtLeast;
        CHECK(floor <= real);
        CHECK(floor >= real / 3);
    }
    // At M = 4 and 6 only cells spanning gaps in all three axes split: few nodes, but the
    // levels the build starts are wide and their lists long. The build's own check as it starts
    // a level, bounded from the split floor and the counted tiles' lists and slots, takes the
    // floor in bytes to within 5 % of the real peak (99 %; 90 % without the tiles, which leave
    // the leaf slots out; the finished tree's nodes and items alone are about a third of it).
    for (const int m : {4, 6}) {
        INFO("M = " << m);
        IndexSpec wide = IndexSpec::octree(m, 1e-9);
        wide.maxBytes = 4ull << 30;
        const std::uint64_t peak = buildIndex(near, wide)->stats().buildPeakBytes;
        wide.maxBytes = 1;
        wide.maxBytes = estimateIndexMemory(near, wide).atMostBytes - 1;
        const std::uint64_t floor = estimateIndexMemory(near, wide).atLeastBytes;
        CHECK(floor <= peak);
        CHECK(floor >= peak - peak / 20);
    }

    // Against real builds: scenes that overlap densely, here and there, touch or nearly touch,
    // at specs down to the smallest MIN that still fits.
    std::vector<std::pair<std::string, Scene>> scenes = testScenes();
    scenes.emplace_back("sparse", sparse);
    r.count = 1000;
    r.rotate = true;
    r.cubeSize = 0.015;
    scenes.emplace_back("dense rotated", makeRandomScene(r));
    apart.gap = 1e-6;
    scenes.emplace_back("lattice nearly touching", makeLatticeScene(apart));
    apart.gap = 0.001;
    scenes.emplace_back("lattice 1 mm apart", makeLatticeScene(apart));
    for (const auto& [name, scene] : scenes) {
        for (const IndexSpec& spec :
             {IndexSpec::octree(1, 0.004), IndexSpec::octree(1, 0.0005),
              IndexSpec::octree(2, 0.001), IndexSpec::octree(3, 0.0005),
              IndexSpec::octree(1, 0.001, OverlapMode::Aabb), IndexSpec::octree(8, 0.0005)}) {
            INFO(name << " " << spec.toString());
            IndexSpec tight = spec; // a ceiling above the limit: the groups are looked for
            tight.maxBytes = 1;
            const IndexMemoryEstimate e = estimateIndexMemory(scene, tight);
            // At the largest group's floor the limit is not passed yet: the groups' distinct
            // cells are counted too.
            tight.maxBytes = e.atLeastBytes;
            const IndexMemoryEstimate distinct = estimateIndexMemory(scene, tight);
            CHECK(distinct.nodesAtLeast >= e.nodesAtLeast);
            // Below the ceiling every stage of the floor runs (the cells' counts last).
            tight.maxBytes = e.atMostBytes - 1;
            const IndexMemoryEstimate all = estimateIndexMemory(scene, tight);
            CHECK(all.nodesAtLeast >= distinct.nodesAtLeast);
            IndexSpec roomy = spec;
            roomy.maxBytes = 4ull << 30;
            std::unique_ptr<SpatialIndex> index;
            try {
                index = buildIndex(scene, roomy);
            } catch (const InputError&) { // more than kMaxNodes: nothing to compare
                continue;
            }
            CHECK(all.nodesAtLeast <= index->stats().nodes);
            CHECK(all.atLeastBytes <= index->stats().buildPeakBytes);
        }
    }
}

TEST_CASE("a mesh vertex shared by more than M triangles splits every cell around it - the "
          "octree floor counts those cells and stays a floor") {
    hapto::test::buildOnOneThread();
    MeshOptions sphere;
    sphere.triangles = 2000; // a geodesic sphere: five or six triangles at every vertex
    const Scene scene = makeMeshScene(sphere);
    // Down to 1e-9 every cell around a vertex splits to the deepest level: refused by the
    // floor, before anything is built, not by the build's check some levels down.
    IndexSpec deep = IndexSpec::octree(4, 1e-9);
    deep.maxBytes = 8ull << 20;
    // Over its triangles: the mesh object's own slot is not an item of the index.
    REQUIRE(scene.triangleCount() == 2000);
    CHECK_THROWS_WITH(buildIndex(scene, deep),
                      Catch::Contains("at least ") && Catch::Contains("nodes over 2000 items"));
    // Just over the limit, the message tells the need from the limit.
    deep.maxBytes = estimateIndexMemory(scene, deep).atLeastBytes - 1024;
    try {
        (void)buildIndex(scene, deep);
        FAIL("not refused");
    } catch (const IndexTooLargeError& e) {
        const std::string what = e.what();
        std::smatch m;
        REQUIRE(std::regex_search(what, m,
                                  std::regex("more than ([0-9.]+) MB .* the ([0-9.]+) MB limit")));
        CHECK(m[1].str() != m[2].str());
    }
    // Against real builds: the floor stays at or under the nodes and the peak accounting; at
    // M = 4 the shared vertices give over half the real tree (its deep levels are the cells
    // around the vertices; 77 %), at M = 2 a quarter (cells along the edges split too; 34 %),
    // at M = 8 none (no vertex has more than six triangles).
    for (const IndexSpec& spec :
         {IndexSpec::octree(2, 0.0002), IndexSpec::octree(4, 0.0002),
          IndexSpec::octree(4, 0.0002, OverlapMode::Aabb), IndexSpec::octree(8, 0.0002)}) {
        INFO(spec.toString());
        IndexSpec roomy = spec;
        roomy.maxBytes = 4ull << 30;
        const auto index = buildIndex(scene, roomy);
        IndexSpec tight = spec;
        tight.maxBytes = 1;
        tight.maxBytes = estimateIndexMemory(scene, tight).atMostBytes - 1; // every stage runs
        const IndexMemoryEstimate e = estimateIndexMemory(scene, tight);
        CHECK(e.nodesAtLeast <= index->stats().nodes);
        CHECK(e.atLeastBytes <= index->stats().buildPeakBytes);
        if (spec.maxObjects < 8) {
            CHECK(e.nodesAtLeast >= index->stats().nodes / (spec.maxObjects == 2 ? 4 : 2));
        }
    }
}

TEST_CASE("a mesh's triangles, not the mesh object, are the index's items", "[threads]") {
    const Scene scene = makeMeshScene();
    std::vector<std::uint32_t> indexed;
    std::uint32_t meshes = 0;
    for (std::uint32_t i = 0; i < scene.itemCount(); ++i) {
        if (scene.isIndexed(scene.item(i))) {
            indexed.push_back(scene.item(i));
        }
        meshes += i < scene.size() && scene.object(i).shape == Shape::Mesh;
    }
    REQUIRE(meshes == 3);
    REQUIRE(indexed.size() == scene.itemCount() - meshes);
    const auto brute = buildIndex(scene, IndexSpec::brute());
    const auto all = brute->locate(Vec3(0.0)).candidates;
    CHECK(std::vector<std::uint32_t>(all.begin(), all.end()) == indexed);
    for (const IndexSpec& spec : testSpecs()) {
        INFO(spec.toString());
        const auto index = buildIndex(scene, spec);
        CHECK(index->itemCount() == indexed.size());
        CHECK(index->stats().objects == indexed.size());
        // No mesh slot in any leaf; every triangle in some leaf (they all lie in the bounds
        // but the small sphere's, which may be listed outside only).
        std::vector<std::uint8_t> seen(scene.itemCount(), 0);
        const auto mark = [&](std::span<const std::uint32_t> items) {
            for (const std::uint32_t item : items) {
                CHECK(scene.isIndexed(item));
                seen[isTriangleItem(item) ? scene.size() + (item & ~kTriangleItemBit) : item] = 1;
            }
        };
        for (std::uint64_t leaf = 0; leaf < index->stats().nodes; ++leaf) {
            if (spec.kind != IndexSpec::Kind::Octree ||
                static_cast<const Octree&>(*index).nodes()[leaf].isLeaf()) {
                mark(index->leafObjects(static_cast<std::uint32_t>(leaf)));
            }
        }
        mark(index->outsideObjects());
        std::size_t missing = 0;
        for (const std::uint32_t item : indexed) {
            missing +=
                !seen[isTriangleItem(item) ? scene.size() + (item & ~kTriangleItemBit) : item];
        }
        CHECK(missing == 0);
        // A point on a triangle finds that triangle; the item names its mesh and triangle.
        for (std::uint32_t n = 0; n < scene.triangleCount(); n += 97) {
            const std::uint32_t item = kTriangleItemBit | n;
            const auto [a, b, c] = scene.triangleCorners(item);
            const LocateResult r = index->locate((a + b + c) / 3.0);
            CHECK(std::binary_search(r.candidates.begin(), r.candidates.end(), item));
            CHECK(scene.object(scene.objectSlotOf(item)).shape == Shape::Mesh);
        }
    }
}

namespace {

// Axis-aligned boxes at random (some flat), half-turned (exact signed axes), quarter-turned,
// rotated, with faces on grid cell faces (touching cells exactly) and a hair off them, a
// sphere and a mesh's triangles, all in one scene.
Scene makeMixedAlignmentScene() {
    std::vector<SceneObject> o;
    Random rng(31);
    ObjectId id = 1;
    const Quat quarter = glm::angleAxis(std::numbers::pi / 2, Vec3(0, 0, 1));
    for (int i = 0; i < 400; ++i) {
        const Vec3 c(rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12));
        const Vec3 h(rng.uniform(0.001, 0.01), rng.uniform(0.001, 0.01), rng.uniform(0.0, 0.01));
        const Quat r = i % 4 == 0 ? glm::angleAxis(rng.uniform(0, 3), glm::normalize(Vec3(1, 2, 3)))
                       : i % 4 == 1 ? Quat(0.0, 0.0, 0.0, 1.0) // a half turn: exact signed axes
                       : i % 4 == 2 ? quarter // its matrix is not exact: the full test
                                    : Quat(1.0, 0.0, 0.0, 0.0);
        o.push_back(makeBox(id++, c, h, r));
    }
    // Faces on the faces of 8- and 16-cell grids over the +-0.125 m bounds, and a hair off.
    for (int i = -3; i <= 3; ++i) {
        o.push_back(makeBox(id++, Vec3(i * 0.03125, 0.0, 0.01), Vec3(0.015625)));
        o.push_back(makeBox(id++, Vec3(0.0, i * 0.03125 + 1e-12, -0.02), Vec3(0.015625)));
    }
    o.push_back(makeMesh(id++, Vec3(0.03, 0.0, 0.0), test::makeIcosphere(2, 0.05)));
    o.push_back(makeSphere(id++, Vec3(0.0625), 0.01));
    return Scene({Vec3(-0.125), Vec3(0.125)}, std::move(o));
}

// The bounds placed by the full separating-axis test, as before axis-aligned boxes stopped at
// their AABB test.
std::vector<std::pair<std::uint32_t, OverlapShape>> fullSatShapes(const Scene& scene) {
    auto shapes = itemShapes(scene);
    for (auto& [item, shape] : shapes) {
        shape.axisAligned = false;
    }
    return shapes;
}

std::vector<std::uint32_t>
placedBy(const std::vector<std::pair<std::uint32_t, OverlapShape>>& shapes, const Aabb& cell,
         OverlapMode mode) {
    const OverlapCell prepared = OverlapCell::of(cell); // once for every item
    std::vector<std::uint32_t> want;
    for (const auto& [item, shape] : shapes) {
        if (overlaps(shape, prepared, mode)) {
            want.push_back(item);
        }
    }
    return want;
}

} // namespace

TEST_CASE("axis-aligned boxes by their box, the rest by the full test: the same cells as before") {
    hapto::test::buildOnOneThread();
    std::vector<std::pair<std::string, Scene>> scenes;
    scenes.emplace_back("mixed alignment", makeMixedAlignmentScene());
    RandomOptions r;
    r.count = 2000;
    r.seed = 3;
    r.cubeSize = 0.01;
    scenes.emplace_back("random axis-aligned", makeRandomScene(r));
    ClusterOptions c;
    c.count = 2000;
    c.clusters = 4;
    c.cubeSize = 0.002;
    c.spread = 0.005;
    c.seed = 4;
    scenes.emplace_back("clustered axis-aligned", makeClusterScene(c));
    LatticeOptions l;
    l.perSide = 8;
    l.cubeSize = 0.03125;
    l.gap = 0.0;
    scenes.emplace_back("lattice on cell faces", makeLatticeScene(l));
    scenes.emplace_back("meshes", makeMeshScene());
    for (const auto& [name, scene] : scenes) {
        const auto reference = fullSatShapes(scene);
        std::size_t aligned = 0;
        for (const auto& [item, shape] : itemShapes(scene)) {
            aligned += shape.axisAligned;
        }
        INFO(name);
        CHECK((name == "meshes" ? aligned > 0 : aligned >= scene.size() / 2));
        for (const IndexSpec& spec :
             {IndexSpec::grid(8), IndexSpec::grid(16), IndexSpec::grid(13, OverlapMode::Aabb)}) {
            INFO(spec.toString());
            const auto grid = UniformGrid::build(scene, spec);
            std::size_t mismatches = 0;
            for (std::uint32_t cell = 0; cell < grid->cellCount(); ++cell) {
                const auto want = placedBy(reference, grid->leafBounds(cell), spec.mode);
                const auto got = grid->leafObjects(cell);
                mismatches += !std::equal(got.begin(), got.end(), want.begin(), want.end());
            }
            CHECK(mismatches == 0);
        }
        for (const IndexSpec& spec : {IndexSpec::octree(2, 0.005), IndexSpec::octree(8, 0.001)}) {
            INFO(spec.toString());
            const auto tree = Octree::build(scene, spec);
            std::size_t mismatches = 0;
            for (std::uint32_t i = 0; i < tree->nodes().size(); ++i) {
                if (tree->nodes()[i].isLeaf()) {
                    const auto want = placedBy(reference, tree->nodeBounds(i), spec.mode);
                    const auto got = tree->leafObjects(i);
                    mismatches += !std::equal(got.begin(), got.end(), want.begin(), want.end());
                }
            }
            CHECK(mismatches == 0);
        }
    }
}
