// The index's box query (SpatialIndex::visitLeaves), the dynamics' broad phase, against brute
// force on random boxes: every item whose shape reaches into the box is in a visited leaf (or,
// outside the bounds, in outsideObjects()), each leaf overlapping the box is visited exactly
// once and no other, a visitor can stop the walk, and an empty or NaN box visits nothing.

#include "IndexTestScenes.h"
#include "OneThreadBuilds.h"

#include "hapto/index/Octree.h"
#include "hapto/index/Overlap.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <limits>
#include <set>
#include <vector>

using namespace hapto;
using namespace hapto::test;

namespace {

// A random box around and beyond the scene's bounds, from a point to a quarter of them wide.
Aabb randomBox(Random& rng, const Aabb& bounds) {
    const Vec3 size = bounds.size();
    Vec3 lo{0.0};
    Vec3 hi{0.0};
    for (int a = 0; a < 3; ++a) {
        const double c = rng.uniform(bounds.min[a] - 0.1 * size[a], bounds.max[a] + 0.1 * size[a]);
        const double half = rng.uniform() < 0.1 ? 0.0 : rng.uniform(0.0, 0.125 * size[a]);
        lo[a] = c - half;
        hi[a] = c + half;
    }
    return {lo, hi};
}

std::vector<std::uint32_t> visitedLeaves(const SpatialIndex& index, const Aabb& box) {
    std::vector<std::uint32_t> leaves;
    auto collect = [&](std::uint32_t leaf) {
        leaves.push_back(leaf);
        return true;
    };
    CHECK(index.visitLeavesWith(box, collect));
    return leaves;
}

// Every leaf of the index (octree: its leaf nodes; grid: its cells; brute force: 0).
std::vector<std::uint32_t> allLeaves(const SpatialIndex& index) {
    std::vector<std::uint32_t> leaves;
    const auto* octree = dynamic_cast<const Octree*>(&index);
    for (std::uint32_t n = 0; n < index.stats().nodes; ++n) {
        if (octree == nullptr || octree->nodes()[n].isLeaf()) {
            leaves.push_back(n);
        }
    }
    return leaves;
}

} // namespace

TEST_CASE("Box query: every item reaching into the box is found, every index and scene") {
    hapto::test::buildOnOneThread();
    Random rng(37);
    for (const auto& [name, scene] : testScenes()) {
        const auto shapes = itemShapes(scene);
        for (const IndexSpec& spec : testSpecs()) {
            const auto index = buildIndex(scene, spec);
            INFO(name << ", " << spec.toString());
            std::size_t missed = 0;
            std::size_t found = 0;
            for (int trial = 0; trial < 60; ++trial) {
                const Aabb box = randomBox(rng, scene.bounds());
                std::set<std::uint32_t> candidates;
                for (const std::uint32_t leaf : visitedLeaves(*index, box)) {
                    const auto items = index->leafObjects(leaf);
                    candidates.insert(items.begin(), items.end());
                }
                if (index->reachesOutside(box)) {
                    const auto outside = index->outsideObjects();
                    candidates.insert(outside.begin(), outside.end());
                }
                // The box shrunk by far more than the overlap tests' tolerance: an item the
                // exact test says overlaps it really reaches into the box.
                const Aabb inner{box.min + Vec3(1e-7), box.max - Vec3(1e-7)};
                for (const auto& [item, shape] : shapes) {
                    if (!inner.isEmpty() && overlaps(shape, inner, OverlapMode::Obb)) {
                        ++found;
                        missed += candidates.count(item) == 0 ? 1 : 0;
                    }
                }
            }
            CHECK(missed == 0);
            CHECK(found > 0);
        }
    }
}

TEST_CASE("Box query: exactly the leaves overlapping the box, each once") {
    hapto::test::buildOnOneThread();
    Random rng(5);
    const Scene scene = makeDegenerateScene();
    for (const IndexSpec& spec : testSpecs()) {
        const auto index = buildIndex(scene, spec);
        INFO(spec.toString());
        const std::vector<std::uint32_t> leaves = allLeaves(*index);
        for (int trial = 0; trial < 100; ++trial) {
            const Aabb box = randomBox(rng, scene.bounds());
            std::vector<std::uint32_t> visited = visitedLeaves(*index, box);
            std::sort(visited.begin(), visited.end());
            CHECK(std::adjacent_find(visited.begin(), visited.end()) == visited.end());
            std::vector<std::uint32_t> want;
            if (spec.kind == IndexSpec::Kind::BruteForce) {
                want.push_back(0); // every item everywhere
            } else {
                for (const std::uint32_t leaf : leaves) {
                    if (index->leafBounds(leaf).overlaps(box)) {
                        want.push_back(leaf);
                    }
                }
            }
            CHECK(visited == want);
        }
    }
}

TEST_CASE("Box query: a visitor stops the walk, and empty or NaN boxes visit nothing") {
    hapto::test::buildOnOneThread();
    const Scene scene = makeDegenerateScene();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const IndexSpec& spec : testSpecs()) {
        const auto index = buildIndex(scene, spec);
        INFO(spec.toString());
        int calls = 0;
        auto stopAtOnce = [&](std::uint32_t) {
            ++calls;
            return false;
        };
        CHECK_FALSE(index->visitLeavesWith(scene.bounds(), stopAtOnce));
        CHECK(calls == 1);
        calls = 0;
        auto count = [&](std::uint32_t) {
            ++calls;
            return true;
        };
        CHECK(index->visitLeavesWith(Aabb::empty(), count));
        CHECK(index->visitLeavesWith(Aabb{Vec3(nan), Vec3(0.1)}, count));
        CHECK(calls == 0);
        CHECK_FALSE(index->reachesOutside(Aabb::empty()));
        CHECK_FALSE(index->reachesOutside(scene.bounds()));
        CHECK(index->reachesOutside({scene.bounds().min, scene.bounds().max + Vec3(0.01)}));
    }
}
