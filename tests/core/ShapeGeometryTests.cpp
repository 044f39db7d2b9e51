#include "hapto/core/ShapeGeometry.h"

#include <catch2/catch.hpp>

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <random>

using namespace hapto;

namespace {

/// Random boxes and points from one seeded generator, so every run tests the same cases.
struct Cases {
    std::mt19937_64 rng{20240611};
    double uniform(double lo, double hi) { return std::uniform_real_distribution<>(lo, hi)(rng); }
    Vec3 point(double r) { return Vec3(uniform(-r, r), uniform(-r, r), uniform(-r, r)); }
    Obb box() {
        const Quat q =
            glm::normalize(Quat(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)));
        return {point(0.1), Vec3(uniform(0.005, 0.05), uniform(0.005, 0.05), uniform(0.005, 0.05)),
                glm::mat3_cast(q)};
    }
};

} // namespace

TEST_CASE("shape geometry: the sign of the signed distance is the inside test") {
    Cases c;
    for (int n = 0; n < 2000; ++n) {
        const Obb box = c.box();
        const Vec3 p = c.point(0.2);
        const double inflate = n % 2 ? 0.0 : 0.01;
        const double d = boxSignedDistance(box, p, inflate);
        INFO("case " << n << ": d = " << d);
        REQUIRE((d < 0.0) == boxStrictlyContains(box, p, inflate));
        if (inflate == 0.0 && std::abs(d) > 1e-12) {
            REQUIRE((d <= 0.0) == box.contains(p));
        }
        REQUIRE(boxDistanceOutside(box, p, inflate) == Approx(std::max(d, 0.0)).margin(1e-12));
        const Vec3 center = c.point(0.1);
        const double r = c.uniform(0.001, 0.1);
        const double s = sphereSignedDistance(center, r, p);
        if (std::abs(s) > 1e-12) {
            REQUIRE((s < 0.0) == sphereStrictlyContains(center, r, p));
            REQUIRE((s <= 0.0) == sphereContains(center, r, p));
        }
    }
}

TEST_CASE("shape geometry: an axis-aligned box's tests on p - centre are its rotated tests, bit "
          "for bit") {
    // The renderer skips the rotation by the identity (RenderBody::toLocal); the answers must
    // be the ones of the Obb path exactly (docs/DESIGN.md, "The render copy"): random points,
    // and points on the faces, edges and corners and on the centre's own planes (zero local
    // components, whose sign the product may change).
    Cases c;
    for (int n = 0; n < 4000; ++n) {
        const Vec3 center = c.point(0.1);
        const Vec3 half(c.uniform(0.005, 0.05), c.uniform(0.005, 0.05), c.uniform(0.005, 0.05));
        const Obb box{center, half, Mat3(1.0)};
        Vec3 local = c.point(0.1);
        for (int a = 0; a < 3; ++a) {
            const int pick = (n >> (2 * a)) % 4; // 0: random, 1: on the centre's plane, 2/3: faces
            local[a] = pick == 1 ? 0.0 : pick == 2 ? half[a] : pick == 3 ? -half[a] : local[a];
        }
        const Vec3 p = center + local;
        for (const double inflate : {0.0, 1e-4 - 1e-9, 0.01}) {
            INFO("case " << n << ", inflate " << inflate);
            REQUIRE(boxStrictlyContainsLocal(half, p - center, inflate) ==
                    boxStrictlyContains(box, p, inflate));
            REQUIRE(boxDistanceOutsideLocal(half, p - center, inflate) ==
                    boxDistanceOutside(box, p, inflate));
        }
    }
}

TEST_CASE("shape geometry: the signed distance is the distance to the nearest surface point") {
    const Obb box{Vec3(0.0), Vec3(0.1, 0.2, 0.3), Mat3(1.0)};
    CHECK(boxSignedDistance(box, Vec3(0.0)) == Approx(-0.1));             // nearest face: x
    CHECK(boxSignedDistance(box, Vec3(0.15, 0.0, 0.0)) == Approx(0.05));  // beyond a face
    CHECK(boxSignedDistance(box, Vec3(0.13, 0.24, 0.3)) == Approx(0.05)); // beyond an edge
    CHECK(boxSignedDistance(box, Vec3(0.1, 0.0, 0.0)) == Approx(0.0).margin(1e-15));
    CHECK(dominantFaceAxis(Vec3(0.0, 0.19, 0.0), box.halfExtents) == 1); // 1 cm from the y face
    CHECK(dominantFaceAxis(Vec3(0.0, 0.0, 0.35), box.halfExtents) == 2);
    CHECK(sphereSignedDistance(Vec3(1.0, 0.0, 0.0), 0.5, Vec3(1.0, 2.0, 0.0)) == Approx(1.5));
}

TEST_CASE("shape geometry: separating-axis overlap never misses an overlap that sampling finds, "
          "and separated boxes far apart are separated") {
    Cases c;
    int overlapping = 0;
    for (int n = 0; n < 400; ++n) {
        const Obb a = c.box();
        const Obb b = c.box();
        const Aabb cell{a.center - a.halfExtents, a.center + a.halfExtents};
        // Sample points of b; any that is inside a (or the cell) proves an overlap.
        bool sampledObb = false;
        bool sampledCell = false;
        for (int s = 0; s < 400; ++s) {
            const Vec3 local(c.uniform(-1, 1) * b.halfExtents.x, c.uniform(-1, 1) * b.halfExtents.y,
                             c.uniform(-1, 1) * b.halfExtents.z);
            const Vec3 p = b.center + b.axes * local;
            sampledObb = sampledObb || a.contains(p);
            sampledCell = sampledCell || cell.contains(p);
        }
        INFO("case " << n);
        if (sampledObb) {
            ++overlapping;
            REQUIRE(overlapsObbObb(a, b));
            REQUIRE(overlapsObbObb(b, a));
        }
        if (sampledCell) {
            REQUIRE(overlapsObbAabb(b, cell));
        }
        // Bounding spheres apart by a clear gap: no test may call that an overlap.
        const double gap = glm::length(b.center - a.center) - glm::length(a.halfExtents) -
                           glm::length(b.halfExtents);
        if (gap > 1e-6) {
            REQUIRE_FALSE(overlapsObbObb(a, b));
        }
    }
    CHECK(overlapping > 20); // the random cases do exercise overlaps
    const Aabb unit{Vec3(0.0), Vec3(1.0)};
    CHECK(overlapsAabbAabb(unit, Aabb{Vec3(1.0), Vec3(2.0)})); // touching counts
    CHECK_FALSE(overlapsAabbAabb(unit, Aabb{Vec3(1.001), Vec3(2.0)}));
    CHECK(overlapsSphereAabb(Vec3(1.5, 0.5, 0.5), 0.5, unit));
    CHECK_FALSE(overlapsSphereAabb(Vec3(1.6, 0.5, 0.5), 0.5, unit));
}

namespace {

/// The smallest distance (m) from a grid of barycentric samples on the triangle to the box:
/// within maxEdge / steps of the true distance, 0 when a sample lies in the box.
double sampledDistance(const TriangleCorners& t, const Aabb& box, int steps) {
    const Obb obb{box.center(), box.halfExtents(), Mat3(1.0)};
    double best = 1e300;
    for (int i = 0; i <= steps; ++i) {
        for (int j = 0; i + j <= steps; ++j) {
            const double u = double(i) / steps, v = double(j) / steps;
            const Vec3 p = t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]);
            best = std::min(best, boxDistanceOutside(obb, p));
        }
    }
    return best;
}

double longestEdge(const TriangleCorners& t) {
    return std::max({glm::length(t[1] - t[0]), glm::length(t[2] - t[1]), glm::length(t[0] - t[2])});
}

} // namespace

TEST_CASE("shape geometry: the triangle/box test agrees with sampling the triangle") {
    Cases c;
    constexpr int kSteps = 40;
    int overlapsSeen = 0, separatedSeen = 0;
    for (int n = 0; n < 3000; ++n) {
        const Vec3 lo = c.point(0.1);
        const Aabb box{
            lo, lo + Vec3(c.uniform(0.001, 0.08), c.uniform(0.001, 0.08), c.uniform(0.001, 0.08))};
        const Vec3 at = box.center() + c.point(0.08);
        const double size = c.uniform(0.002, 0.1);
        const TriangleCorners t{at + c.point(size), at + c.point(size), at + c.point(size)};
        const bool sat = overlapsTriangleAabb(t, box);
        const double d = sampledDistance(t, box, kSteps);
        INFO("case " << n << ": sampled distance " << d);
        if (d == 0.0) {
            REQUIRE(sat); // a sample lies in the box: never "separated"
        }
        if (sat) {
            // Exact up to the tolerance: some point of the triangle touches the box, and every
            // point of it is within longestEdge / steps of a sample.
            REQUIRE(d <= longestEdge(t) / kSteps + 1e-12);
        }
        overlapsSeen += sat;
        separatedSeen += !sat;
    }
    // Both answers were exercised (the cases are fixed by the seed).
    CHECK(overlapsSeen > 200);
    CHECK(separatedSeen > 200);
}

TEST_CASE("shape geometry: a triangle in a face plane, touching an edge or a corner overlaps") {
    const Aabb box{Vec3(0.0), Vec3(1.0)};
    const double hair = 1e-6; // far above the tolerance (~1e-9 m here)
    SECTION("in the plane of the upper z face, inside it and beside it") {
        const TriangleCorners in{Vec3(0.2, 0.2, 1.0), Vec3(0.8, 0.2, 1.0), Vec3(0.5, 0.8, 1.0)};
        CHECK(overlapsTriangleAabb(in, box));
        TriangleCorners above = in;
        for (Vec3& v : above) {
            v.z += hair;
        }
        CHECK_FALSE(overlapsTriangleAabb(above, box));
        TriangleCorners rounding = in;
        for (Vec3& v : rounding) {
            v.z += 1e-12; // below the tolerance: still touching
        }
        CHECK(overlapsTriangleAabb(rounding, box));
        // Coplanar with the face but beside it, only an edge of the triangle on the box's edge.
        const TriangleCorners beside{Vec3(1.0, 0.2, 1.0), Vec3(2.0, 0.2, 1.0), Vec3(1.5, 0.8, 1.0)};
        CHECK(overlapsTriangleAabb(beside, box));
        TriangleCorners besideApart = beside;
        for (Vec3& v : besideApart) {
            v.x += hair;
        }
        CHECK_FALSE(overlapsTriangleAabb(besideApart, box));
    }
    SECTION("an edge crossing a box edge: only an edge cross product separates when moved") {
        // The edge (2,0)-(0,2) at z = 0.5 touches the box's edge x = y = 1.
        const TriangleCorners touch{Vec3(2.0, 0.0, 0.5), Vec3(0.0, 2.0, 0.5), Vec3(2.0, 2.0, 0.5)};
        CHECK(overlapsTriangleAabb(touch, box));
        TriangleCorners apart = touch;
        for (Vec3& v : apart) {
            v += Vec3(hair, hair, 0.0);
        }
        // The AABBs still overlap and the triangle's plane cuts the box: the face normals and
        // the triangle normal do not separate, the axis z x (1, -1, 0) does.
        CHECK(overlapsAabbAabb(triangleAabb(apart), box));
        CHECK_FALSE(overlapsTriangleAabb(apart, box));
    }
    SECTION("a corner touching a box corner") {
        const TriangleCorners touch{Vec3(1.0), Vec3(2.0, 1.5, 1.2), Vec3(1.4, 2.0, 1.9)};
        CHECK(overlapsTriangleAabb(touch, box));
        TriangleCorners apart = touch;
        for (Vec3& v : apart) {
            v += Vec3(hair);
        }
        CHECK_FALSE(overlapsTriangleAabb(apart, box));
    }
    SECTION("edges parallel to box axes (null cross products) never separate by rounding") {
        // Every edge axis with the x axis is exactly null for the first edge.
        const TriangleCorners t{Vec3(-0.5, 0.5, 0.5), Vec3(1.5, 0.5, 0.5), Vec3(0.5, 0.5, 2.0)};
        CHECK(overlapsTriangleAabb(t, box));
        // A triangle lying along the box's edge x = y = 1, in the plane y = 1.
        const TriangleCorners onEdge{Vec3(1.0, 1.0, 0.2), Vec3(1.0, 1.0, 0.8), Vec3(1.5, 1.0, 0.5)};
        CHECK(overlapsTriangleAabb(onEdge, box));
    }
    SECTION("a degenerate (collinear) triangle is tested as its segment") {
        const TriangleCorners segment{Vec3(2.0, 0.0, 0.5), Vec3(0.0, 2.0, 0.5),
                                      Vec3(1.0, 1.0, 0.5)};
        CHECK(overlapsTriangleAabb(segment, box));
        TriangleCorners apart = segment;
        for (Vec3& v : apart) {
            v += Vec3(0.25, 0.25, 0.0);
        }
        CHECK_FALSE(overlapsTriangleAabb(apart, box));
        const TriangleCorners point{Vec3(0.5), Vec3(0.5), Vec3(0.5)};
        CHECK(overlapsTriangleAabb(point, box));
    }
    SECTION("the tolerance scales with the distance from the origin") {
        const Aabb far{Vec3(1000.0), Vec3(1001.0)};
        const TriangleCorners t{Vec3(1001.0 + 1e-7, 1000.5, 1000.5), Vec3(1002.0, 1000.2, 1000.5),
                                Vec3(1002.0, 1000.8, 1000.5)};
        CHECK(overlapsTriangleAabb(t, far)); // 1e-7 m apart, below 1e-9 * ~2000 m
        TriangleCorners apart = t;
        for (Vec3& v : apart) {
            v.x += 1e-5;
        }
        CHECK_FALSE(overlapsTriangleAabb(apart, far));
    }
}
