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
