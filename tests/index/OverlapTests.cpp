#include "hapto/core/Random.h"
#include "hapto/index/Overlap.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

using namespace hapto;

namespace {

Mat3 rotation(double angle, Vec3 axis) {
    return glm::mat3_cast(glm::angleAxis(angle, glm::normalize(axis)));
}

Obb box(Vec3 center, Vec3 half, Mat3 axes = Mat3(1.0)) {
    return {center, half, axes};
}

// A cube rotated 45 degrees about z and one rotated 45 degrees about x, the second lifted along
// y: no face axis separates them; only the edge-edge axis z x x = y does, once the lift
// exceeds 2 * sqrt(2) * h (their ridges then pass each other with a gap of lift - 2 sqrt 2 h).
std::pair<Obb, Obb> crossedRidges(double h, double gap) {
    const double quarter = std::numbers::pi / 4;
    return {box(Vec3(0.0), Vec3(h), rotation(quarter, {0, 0, 1})),
            box(Vec3(0, 2 * std::sqrt(2.0) * h + gap, 0), Vec3(h), rotation(quarter, {1, 0, 0}))};
}

// The same pair seen from the first box's frame, so the first becomes an axis-aligned cell.
std::pair<Aabb, Obb> crossedRidgesAsCell(double h, double gap) {
    const auto [a, b] = crossedRidges(h, gap);
    const Mat3 toA = glm::transpose(a.axes);
    return {Aabb{Vec3(-h), Vec3(h)}, box(toA * b.center, b.halfExtents, toA * b.axes)};
}

} // namespace

TEST_CASE("SAT: boxes separated only along a cross-product axis") {
    for (const double h : {1.0, 0.001}) {
        const double gap = 1e-6 * h;
        CHECK_FALSE(overlapsObbObb(crossedRidges(h, gap).first, crossedRidges(h, gap).second));
        CHECK(overlapsObbObb(crossedRidges(h, -gap).first, crossedRidges(h, -gap).second));
        // Ridges exactly touching count as overlap.
        CHECK(overlapsObbObb(crossedRidges(h, 0.0).first, crossedRidges(h, 0.0).second));
        // The same through the cell test.
        CHECK_FALSE(
            overlapsObbAabb(crossedRidgesAsCell(h, gap).second, crossedRidgesAsCell(h, gap).first));
        CHECK(overlapsObbAabb(crossedRidgesAsCell(h, -gap).second,
                              crossedRidgesAsCell(h, -gap).first));
        // The AABBs overlap in every one of these cases: only the OBB test separates.
        const auto [cell, b] = crossedRidgesAsCell(h, gap);
        CHECK(cell.overlaps(b.aabb()));
    }
}

TEST_CASE("SAT: touching faces and corners count as overlap, a hair apart does not") {
    const Aabb cell{Vec3(0.0), Vec3(1.0)};
    CHECK(overlapsObbAabb(box({1.5, 0.5, 0.5}, Vec3(0.5)), cell));
    CHECK(overlapsObbAabb(box({1.5, 1.5, 1.5}, Vec3(0.5)), cell)); // corner to corner
    CHECK_FALSE(overlapsObbAabb(box({1.5 + 1e-6, 0.5, 0.5}, Vec3(0.5)), cell));
    // A diamond (cube rotated 45 degrees about z) whose tip touches the face x = 1.
    const double r = std::sqrt(2.0) * 0.25;
    const Mat3 diamond = rotation(std::numbers::pi / 4, {0, 0, 1});
    CHECK(overlapsObbAabb(box({1.0 + r, 0.5, 0.5}, Vec3(0.25), diamond), cell));
    CHECK_FALSE(overlapsObbAabb(box({1.0 + r + 1e-6, 0.5, 0.5}, Vec3(0.25), diamond), cell));
    // OBB against OBB, faces touching.
    CHECK(overlapsObbObb(box(Vec3(0.0), Vec3(0.5)), box({1.0, 0.2, 0.0}, Vec3(0.5))));
}

TEST_CASE("SAT: near-parallel edges never give a false separation") {
    // Identical boxes, the second turned by a tiny angle about a generic axis: their
    // edge-edge axes are nearly null and badly rounded.
    for (const double angle : {0.0, 1e-15, 1e-12, 1e-9, 1e-6}) {
        const Mat3 turn = rotation(angle, {1, 2, 3});
        const Obb a = box({0.01, 0.02, -0.03}, {0.005, 0.002, 0.0001}, rotation(0.3, {3, 1, 1}));
        Obb b = a;
        b.axes = turn * a.axes;
        CHECK(overlapsObbObb(a, b));
        // Slid along its own first axis until the faces just touch: still an overlap.
        b.center = a.center + a.axes[0] * (2.0 * a.halfExtents.x);
        CHECK(overlapsObbObb(a, b));
        // Well apart: separated.
        b.center = a.center + a.axes[0] * (2.0 * a.halfExtents.x + 1e-4);
        CHECK_FALSE(overlapsObbObb(a, b));
    }
    // Against a cell: a flat box almost aligned with the cell, touching its top face.
    for (const double angle : {0.0, 1e-14, 1e-10}) {
        const Aabb cell{Vec3(0.0), Vec3(0.01)};
        const Obb flat =
            box({0.005, 0.005, 0.01 + 1e-7}, {0.004, 0.004, 1e-7}, rotation(angle, {1, 1, 0}));
        CHECK(overlapsObbAabb(flat, cell));
    }
}

TEST_CASE("SAT: degenerate boxes (zero thickness, a point) still overlap what they touch") {
    const Aabb cell{Vec3(0.0), Vec3(1.0)};
    CHECK(overlapsObbAabb(box({0.5, 0.5, 1.0}, {0.3, 0.3, 0.0}), cell)); // a sheet on a face
    CHECK(overlapsObbAabb(box({1.0, 1.0, 1.0}, Vec3(0.0)), cell));       // a point at a corner
    CHECK_FALSE(overlapsObbAabb(box({1.0, 1.0, 1.0 + 1e-6}, Vec3(0.0)), cell));
    // A needle through the cell along the diagonal, thinner than anything.
    const Mat3 diag =
        rotation(std::acos(1 / std::sqrt(3.0)), glm::cross(Vec3(1, 0, 0), Vec3(1, 1, 1)));
    CHECK(overlapsObbAabb(box(Vec3(0.5), {5.0, 0.0, 0.0}, diag), cell));
}

TEST_CASE("spheres: exact distance test, AABB mode keeps the cube's corners") {
    const Aabb cell{Vec3(0.0), Vec3(1.0)};
    const double a = 0.1, r = std::sqrt(3.0) * a;
    CHECK(overlapsSphereAabb(Vec3(1 + a), r, cell));
    CHECK_FALSE(overlapsSphereAabb(Vec3(1 + a), r - 1e-6, cell));
    const OverlapShape s = OverlapShape::of(makeSphere(0, Vec3(1 + a), r - 1e-6));
    CHECK_FALSE(overlaps(s, cell, OverlapMode::Obb));
    CHECK(overlaps(s, cell, OverlapMode::Aabb));           // its cube reaches the corner
    CHECK(overlapsSphereAabb({0.5, 0.5, 1.2}, 0.2, cell)); // touching a face
}

TEST_CASE("SAT never misses an overlap that sampled points prove (random boxes)") {
    Random rng(7);
    int overlapping = 0, separated = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        const Aabb cell{Vec3(rng.uniform(-1, 0), rng.uniform(-1, 0), rng.uniform(-1, 0)),
                        Vec3(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1))};
        const Quat q = glm::normalize(
            Quat(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)));
        const Obb b = box(Vec3(rng.uniform(-2, 2), rng.uniform(-2, 2), rng.uniform(-2, 2)),
                          Vec3(rng.uniform(0, 0.8), rng.uniform(0, 0.8), rng.uniform(0, 0.02)),
                          glm::mat3_cast(q));
        bool witness = false;
        for (int k = 0; k < 200 && !witness; ++k) {
            const Vec3 local(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
            witness = cell.contains(b.center + b.axes * (local * b.halfExtents));
        }
        const bool sat = overlapsObbAabb(b, cell);
        if (witness) {
            CHECK(sat);
        }
        // The OBB-OBB test agrees with the cell test on a cell written as an OBB.
        const Obb cellBox{cell.center(), cell.halfExtents(), Mat3(1.0)};
        CHECK(overlapsObbObb(cellBox, b) == sat);
        // And an OBB never overlaps a cell its AABB misses.
        if (sat) {
            CHECK(overlapsAabbAabb(b.aabb(), cell));
        }
        (sat ? overlapping : separated) += 1;
    }
    CHECK(overlapping > 100);
    CHECK(separated > 300);
}

TEST_CASE("an axis-aligned box stops at its AABB test, with the full test's answer") {
    const auto shapeOf = [](const Quat& r, const Vec3& c, const Vec3& h) {
        SceneObject o;
        o.shape = Shape::Box;
        o.center = c;
        o.halfExtents = h;
        o.rotation = r;
        return OverlapShape::of(o);
    };
    CHECK(shapeOf(Quat(1, 0, 0, 0), Vec3(0.1), Vec3(0.01)).axisAligned);
    CHECK(shapeOf(Quat(0, 1, 0, 0), Vec3(0.1), Vec3(0.01)).axisAligned); // half turn about x
    CHECK_FALSE(shapeOf(glm::angleAxis(0.3, Vec3(0, 0, 1)), Vec3(0.1), Vec3(0.01)).axisAligned);
    SceneObject ball;
    ball.shape = Shape::Sphere;
    ball.halfExtents = Vec3(0.01);
    CHECK_FALSE(OverlapShape::of(ball).axisAligned);

    // Random boxes against cells of a 1/16 lattice, placed to touch, nearly touch (within and
    // beyond the tolerance) and overlap: the short path agrees with the 15-axis test.
    Random rng(17);
    const double step = 1.0 / 16;
    std::size_t disagree = 0, overlapping = 0, apart = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 h(rng.uniform(0.0, 0.05), rng.uniform(0.0, 0.05), rng.uniform(0.0, 0.05));
        Vec3 c(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5));
        const int a = i % 3;
        const double face = std::round(c[a] / step) * step;
        const double offsets[] = {0.0, 1e-12, -1e-12, 1e-9, 1e-6, rng.uniform(-0.01, 0.01)};
        c[a] = face + h[a] + offsets[i % 6]; // the box's lower face on a cell face, or near it
        const OverlapShape fast =
            shapeOf(i % 2 ? Quat(1, 0, 0, 0) : Quat(0, 0, 1, 0), c, h); // identity, half turn
        REQUIRE(fast.axisAligned);
        OverlapShape full = fast;
        full.axisAligned = false;
        for (int dx = -1; dx <= 1; ++dx) {
            Vec3 lo = glm::floor(c / step) * step;
            lo[a] = face - step;
            lo[(a + 1) % 3] += dx * step;
            const Aabb cell{lo, lo + Vec3(step)};
            for (const OverlapMode mode : {OverlapMode::Obb, OverlapMode::Aabb}) {
                const bool got = overlaps(fast, cell, mode);
                disagree += got != overlaps(full, cell, mode);
                overlapping += got;
                apart += !got;
            }
        }
    }
    CHECK(disagree == 0);
    CHECK(overlapping > 1000);
    CHECK(apart > 1000);
}
