#include "IndexTestScenes.h"
#include "OneThreadBuilds.h"

#include "hapto/index/Cursor.h"
#include "hapto/index/Octree.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <span>
#include <utility>
#include <vector>

using namespace hapto;
using namespace hapto::test;

namespace {

// A hand-speed random walk: steps up to `maxStep` (m) in random directions, wandering out of
// the bounds now and then; every `snapEvery` steps the point is snapped onto a cell plane of
// the octree so faces, edges and corners are crossed exactly.
std::vector<Vec3> randomWalk(const Aabb& b, std::uint64_t seed, int steps, double maxStep) {
    Random rng(seed);
    std::vector<Vec3> walk;
    Vec3 p = b.center() +
             0.3 * b.size() * Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    Vec3 drift(0.0);
    for (int i = 0; i < steps; ++i) {
        const Vec3 d(rng.normal(), rng.normal(), rng.normal());
        drift = 0.9 * drift + 0.1 * glm::normalize(d);
        const Vec3 dir = glm::length(drift) > 1e-12 ? glm::normalize(drift) : Vec3(1, 0, 0);
        p += dir * rng.uniform(0.0, maxStep);
        for (int a = 0; a < 3; ++a) { // wander up to 2 cm outside, then come back
            if (p[a] > b.max[a] + 0.02 || p[a] < b.min[a] - 0.02) {
                drift[a] = -drift[a];
                p[a] = std::clamp(p[a], b.min[a] - 0.02, b.max[a] + 0.02);
            }
        }
        Vec3 q = p;
        if (i % 7 == 0) {
            const int a = static_cast<int>(rng.below(3));
            const double cell = b.size()[a] / 64;
            q[a] = b.min[a] + std::round((q[a] - b.min[a]) / cell) * cell;
        }
        walk.push_back(q);
    }
    return walk;
}

/// Calls fn(index, a, e, n) for 200 seeded segments a -> e inside each test scene's bounds,
/// under an octree and a grid (n: the segment's number).
template <class Fn> void forSegmentsInScenes(std::uint64_t seed, Fn&& fn) {
    for (const auto& [name, scene] : testScenes()) {
        for (const IndexSpec& spec : {IndexSpec::octree(2, 0.005), IndexSpec::grid(7)}) {
            INFO(name << " " << spec.toString());
            const auto index = buildIndex(scene, spec);
            const Aabb b = scene.bounds();
            Random rng(seed);
            const auto inBounds = [&] {
                return b.center() +
                       0.45 * b.size() *
                           Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
            };
            for (int n = 0; n < 200; ++n) {
                const Vec3 a = inBounds();
                const Vec3 e = inBounds();
                fn(*index, a, e, n);
            }
        }
    }
}

} // namespace

TEST_CASE("a cursor on a long hand-speed walk lands where a fresh locate does, links never "
          "take more steps than climbing") {
    hapto::test::buildOnOneThread();
    for (const auto& [name, scene] : testScenes()) {
        for (const IndexSpec& spec :
             {IndexSpec::octree(2, 0.005), IndexSpec::octree(1, 0.001), IndexSpec::grid(5),
              IndexSpec::octree(3, 0.002, OverlapMode::Aabb), IndexSpec::brute()}) {
            INFO(name << " " << spec.toString());
            const auto index = buildIndex(scene, spec);
            Cursor links(*index, CursorStrategy::NeighbourLinks);
            Cursor climb(*index, CursorStrategy::Climb);
            Cursor root(*index, CursorStrategy::FromRoot);
            std::uint64_t linkSteps = 0, climbSteps = 0, rootSteps = 0, moves = 0, outside = 0;
            std::size_t wrong = 0, worse = 0;
            for (const Vec3& p : randomWalk(scene.bounds(), 17, 20000, 0.001)) {
                const LocateResult fresh = index->locate(p);
                const LocateResult a = links.locate(p), b = climb.locate(p), c = root.locate(p);
                wrong += a.leaf != fresh.leaf || b.leaf != fresh.leaf || c.leaf != fresh.leaf ||
                         a.outside != fresh.outside ||
                         a.candidates.data() != fresh.candidates.data() ||
                         a.candidates.size() != fresh.candidates.size();
                worse += a.steps > b.steps;
                linkSteps += a.steps;
                climbSteps += b.steps;
                rootSteps += c.steps;
                moves += a.steps > 0;
                outside += fresh.outside;
            }
            CHECK(wrong == 0);
            CHECK(worse == 0);
            CHECK(linkSteps <= climbSteps);
            CHECK(outside > 0); // the walk did leave the bounds, and came back
            if (spec.kind == IndexSpec::Kind::Octree) {
                CHECK(moves > 0);
                CHECK(climbSteps < rootSteps);
            } else {
                CHECK(linkSteps == 0);
            }
        }
    }
}

TEST_CASE("cursor: unbound, outside and back, reset to another index, FromRoot steps = depth",
          "[threads]") {
    Cursor unbound;
    CHECK(unbound.locate(Vec3(0.0)).outside);
    CHECK(unbound.locate(Vec3(0.0)).candidates.empty());

    const Scene scene = makeDegenerateScene();
    const auto tree = Octree::build(scene, IndexSpec::octree(2, 0.005));
    Cursor cursor(*tree);
    CHECK(cursor.strategy() == CursorStrategy::NeighbourLinks);
    const LocateResult first = cursor.locate({0.01, 0.01, 0.01});
    CHECK_FALSE(first.outside);
    CHECK(cursor.leaf() == first.leaf);
    const LocateResult same = cursor.locate({0.01, 0.01, 0.01});
    CHECK(same.steps == 0);
    const LocateResult out = cursor.locate({1.0, 0.0, 0.0});
    CHECK(out.outside);
    CHECK(out.candidates.data() == tree->outsideObjects().data());
    CHECK(out.candidates.size() == tree->outsideObjects().size());
    CHECK(out.leaf == kNoLeaf);
    const LocateResult back = cursor.locate({0.0101, 0.01, 0.01});
    CHECK_FALSE(back.outside);
    CHECK(back.leaf == tree->locate({0.0101, 0.01, 0.01}).leaf);

    const auto grid = buildIndex(scene, IndexSpec::grid(4));
    cursor.reset(*grid);
    CHECK(cursor.leaf() == kNoLeaf);
    CHECK(cursor.index() == grid.get());
    CHECK(cursor.locate({0.01, 0.01, 0.01}).leaf == grid->locate({0.01, 0.01, 0.01}).leaf);

    Cursor fromRoot(*tree, CursorStrategy::FromRoot);
    for (const Vec3& p : queryPoints(scene, 4, 200)) {
        const LocateResult r = fromRoot.locate(p);
        if (!r.outside) {
            CHECK(r.steps == static_cast<std::uint32_t>(tree->nodes()[r.leaf].level()));
        }
    }
    // The upper faces of the bounds are inside (closed), one ulp beyond is not.
    const Vec3 top = tree->bounds().max;
    CHECK_FALSE(cursor.locate(top).outside);
    CHECK(cursor.locate({std::nextafter(top.x, 1.0), top.y, top.z}).outside);
    CHECK_FALSE(cursor.locate(top).outside);
    CHECK(cursor.locate({-0.125, -0.125, -0.125}).leaf ==
          grid->locate({-0.125, -0.125, -0.125}).leaf);
}

TEST_CASE("cursor walk: the first unlisted leaf along a segment, every leaf a sampled point is "
          "in found, the cursor itself unmoved",
          "[threads]") {
    forSegmentsInScenes(23, [](const SpatialIndex& index, const Vec3& a, const Vec3& e, int n) {
        Cursor cursor(index);
        const std::uint32_t startLeaf = cursor.locate(a).leaf;
        // List the leaves one walk at a time: each is found where the segment enters it, and
        // the first is a's own.
        std::vector<std::uint32_t> listed;
        SegmentWalk walk;
        for (int k = 0; k < 200; ++k) {
            walk = cursor.firstLeafNotIn(a, e, listed);
            if (walk.at.leaf == kNoLeaf || walk.unknown) {
                break;
            }
            INFO("segment " << n << ", walk " << k << " at t = " << walk.t);
            REQUIRE(walk.t >= 0.0);
            REQUIRE(walk.t <= 1.0);
            REQUIRE(index.locate(a + walk.t * (e - a)).leaf == walk.at.leaf);
            REQUIRE((k > 0 || (walk.t == 0.0 && walk.at.leaf == startLeaf)));
            listed.push_back(walk.at.leaf);
        }
        REQUIRE(walk.covered());
        REQUIRE(cursor.leaf() == startLeaf);
        // The walk saw every leaf a point of the segment lies in, and ended in e's.
        for (int k = 0; k <= 400; ++k) {
            const std::uint32_t leaf = index.locate(a + (k / 400.0) * (e - a)).leaf;
            REQUIRE(std::find(listed.begin(), listed.end(), leaf) != listed.end());
        }
        REQUIRE((walk.endBox.isEmpty() || walk.endBox.contains(e)));
    });
}

TEST_CASE("cursor walk: one walker that walks on from where the segment enters each leaf it "
          "found lists the leaves fresh walks from the start list, in the same order, and ends "
          "in the last leaf it located",
          "[threads]") {
    forSegmentsInScenes(29, [](const SpatialIndex& index, const Vec3& a, const Vec3& e, int n) {
        Cursor cursor(index);
        cursor.locate(a);
        std::vector<std::uint32_t> fresh;
        for (SegmentWalk w = cursor.firstLeafNotIn(a, e, fresh); w.at.leaf != kNoLeaf && !w.unknown;
             w = cursor.firstLeafNotIn(a, e, fresh)) {
            fresh.push_back(w.at.leaf);
        }
        Cursor walker = cursor;
        std::vector<std::uint32_t> walked;
        Vec3 from = a;
        SegmentWalk w = walker.walkToFirstLeafNotIn(from, e, walked);
        for (; w.at.leaf != kNoLeaf && !w.unknown;
             w = walker.walkToFirstLeafNotIn(from, e, walked)) {
            INFO("segment " << n << ", leaf " << walked.size());
            REQUIRE(walker.leaf() == w.at.leaf);
            walked.push_back(w.at.leaf);
            from += w.t * (e - from);
        }
        INFO("segment " << n);
        REQUIRE(w.covered());
        REQUIRE(walked == fresh);
        REQUIRE(walker.leaf() == index.locate(e).leaf);
    });
}

TEST_CASE("cursor walk: outside the bounds, zero length, and an unbound cursor find nothing",
          "[threads]") {
    const Scene scene = makeDegenerateScene();
    const auto tree = Octree::build(scene, IndexSpec::octree(2, 0.005));
    const Cursor cursor(*tree);
    const Vec3 top = tree->bounds().max;
    // Entirely outside: no indexed item there, nothing to list.
    const SegmentWalk out = cursor.firstLeafNotIn(top + Vec3(0.1), top + Vec3(0.2), {});
    CHECK(out.at.leaf == kNoLeaf);
    CHECK(out.covered());
    // A point: its leaf, listed or not.
    const Vec3 p(0.01, 0.01, 0.01);
    const std::uint32_t leaf = tree->locate(p).leaf;
    CHECK(cursor.firstLeafNotIn(p, p, {}).at.leaf == leaf);
    const std::vector<std::uint32_t> listed{leaf};
    CHECK(cursor.firstLeafNotIn(p, p, listed).covered());
    // Inside one listed leaf: covered, and the walk gives that leaf's box.
    const Aabb box = tree->leafBounds(leaf);
    const SegmentWalk inside = cursor.firstLeafNotIn(box.center(), p, listed);
    CHECK(inside.covered());
    CHECK(inside.endBox.min == box.min);
    CHECK(inside.endBox.max == box.max);
    CHECK(Cursor().firstLeafNotIn(p, p, {}).covered());
}

TEST_CASE("a leaf stream along an axis-aligned walk hands out the items of every leaf the walk "
          "enters before it enters it, and nothing new at rest, outside or over brute force") {
    hapto::test::buildOnOneThread();
    std::size_t enteredInAll = 0;
    for (const auto& [name, scene] : testScenes()) {
        for (const IndexSpec& spec : {IndexSpec::octree(2, 0.005), IndexSpec::octree(1, 0.001),
                                      IndexSpec::grid(7), IndexSpec::brute()}) {
            INFO(name << " " << spec.toString());
            const auto index = buildIndex(scene, spec);
            const Aabb b = index->bounds();
            Random rng(23);
            std::size_t entered = 0, early = 0, handedOut = 0;
            for (int n = 0; n < 60; ++n) {
                const int axis = n % 3;
                Vec3 dir(0.0);
                dir[axis] = (n / 3) % 2 == 0 ? 1.0 : -1.0;
                Vec3 p = b.center() +
                         0.4 * b.size() *
                             Vec3(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
                Cursor cursor(*index);
                LeafStream stream;
                std::vector<std::span<const std::uint32_t>> handed;
                std::uint32_t last = cursor.locate(p).leaf;
                bool first = true; // the start may lie too near the first leaf's far face
                for (int k = 0; k < 8000 && index->inBounds(p); ++k) {
                    const LocateResult at = cursor.locate(p);
                    if (at.leaf != last && std::exchange(first, false)) {
                        // not counted
                    } else if (at.leaf != last && !at.candidates.empty()) {
                        ++entered;
                        // The stream handed the leaf's own items out (the same span).
                        early += std::any_of(handed.begin(), handed.end(), [&](const auto& h) {
                            return h.data() == at.candidates.data() &&
                                   h.size() == at.candidates.size();
                        });
                    }
                    last = at.leaf;
                    index->streamAhead(stream, at.leaf, p, dir);
                    handed.push_back(stream.items);
                    handedOut += !stream.items.empty();
                    // A sixteenth of the leaf's smallest side a step: time for the stream to
                    // go down to a finer neighbour, a level a step.
                    const Vec3 side = index->leafBounds(at.leaf).size();
                    p += dir * (std::min({side.x, side.y, side.z}) / 16);
                }
            }
            if (spec.kind == IndexSpec::Kind::BruteForce) {
                CHECK(handedOut == 0);
                continue;
            }
            CHECK(entered > 0);
            CHECK(early == entered);
            enteredInAll += entered;

            // At rest (no direction) and outside the bounds, nothing is asked for, and what
            // was pending drains in a step a level.
            LeafStream stream;
            const Vec3 c = b.center();
            const std::uint32_t leaf = index->locate(c).leaf;
            index->streamAhead(stream, leaf, c, Vec3(1.0, 0.0, 0.0));
            for (int k = 0; k < 30; ++k) {
                index->streamAhead(stream, k % 2 == 0 ? leaf : kNoLeaf, c, Vec3(0.0));
            }
            CHECK(stream.items.empty());
            CHECK(stream.pending == kNoLeaf);
        }
    }
    CHECK(enteredInAll > 1000);
}

TEST_CASE("a leaf stream's face ahead is on the axis moved most along, -1 at rest or for NaN") {
    CHECK(LeafStream::faceAhead(Vec3(1.0, 0.5, -0.5)) == 1);
    CHECK(LeafStream::faceAhead(Vec3(-1.0, 0.5, -0.5)) == 0);
    CHECK(LeafStream::faceAhead(Vec3(0.1, -0.3, 0.2)) == 2);
    CHECK(LeafStream::faceAhead(Vec3(0.1, 0.2, -0.3)) == 4);
    CHECK(LeafStream::faceAhead(Vec3(0.0, 0.0, 1e-9)) == 5);
    CHECK(LeafStream::faceAhead(Vec3(0.5, 0.5, 0.0)) == 1); // a tie: the first axis
    CHECK(LeafStream::faceAhead(Vec3(0.0)) == -1);
    CHECK(LeafStream::faceAhead(Vec3(std::nan(""), 0.0, 0.0)) == -1);
}
