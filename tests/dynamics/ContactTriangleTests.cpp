// The narrow phase against one triangle of a static mesh: spheres by face, edge and corner,
// boxes and hulls resting on a triangle, a small triangle under a box face, one-sided and
// two-sided behaviour (a one-sided triangle never pushes through its back), the margin, and
// randomised agreement with the exact point-triangle distance and the independent
// triangle-box separating-axis test (ShapeGeometry.h).

#include "ContactTestShapes.h"

#include "hapto/core/ClosestPoint.h"
#include "hapto/core/Random.h"

#include <catch2/catch.hpp>

#include <cmath>

using namespace hapto;
using namespace hapto::contact_test;

namespace {

// In the y = 0 plane, counter-clockwise seen from +y (its right-hand normal is +y).
const TriangleCorners kUnit{Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(1, 0, 0)};
const TriangleCorners kLarge{Vec3(-2, 0, -2), Vec3(-2, 0, 4), Vec3(4, 0, -2)};
const Vec3 kUp{0, 1, 0};

ConvexShape oneSided(const TriangleCorners& t) {
    return ConvexShape::triangleOf(t, kUp);
}
ConvexShape twoSided(const TriangleCorners& t) {
    return ConvexShape::triangleOf(t, Vec3(0.0));
}

} // namespace

TEST_CASE("Contact: sphere-triangle by face, edge and corner, one- and two-sided") {
    for (const ConvexShape& t : {oneSided(kUnit), twoSided(kUnit)}) {
        const auto face = collideOnce(ConvexShape::sphere({0.2, 0.05, 0.2}, 0.06), t, 0.0);
        REQUIRE(face.count == 1);
        CHECK(face.points[0].separation == Approx(-0.01));
        CHECK(near(face.points[0].normal, kUp));
        CHECK(near(face.points[0].position, {0.2, -0.005, 0.2}, 1e-12));
        const auto edge = collideOnce(ConvexShape::sphere({0.5, 0, -0.05}, 0.06), t, 0.0);
        REQUIRE(edge.count == 1);
        CHECK(edge.points[0].separation == Approx(-0.01));
        CHECK(near(edge.points[0].normal, {0, 0, -1}));
        const Vec3 out = glm::normalize(Vec3(-1, 1, -1));
        const auto corner = collideOnce(ConvexShape::sphere(out * 0.05, 0.06), t, 0.0);
        REQUIRE(corner.count == 1);
        CHECK(corner.points[0].separation == Approx(-0.01));
        CHECK(near(corner.points[0].normal, out));
        CHECK(collideOnce(ConvexShape::sphere({0.2, 0.1, 0.2}, 0.06), t, 0.03).count == 0);
    }
}

TEST_CASE("Contact: a sphere behind a triangle: two-sided pushes it back, one-sided out front") {
    const ConvexShape ball = ConvexShape::sphere({0.2, -0.05, 0.2}, 0.06);
    const auto two = collideOnce(ball, twoSided(kUnit), 0.0);
    REQUIRE(two.count == 1);
    CHECK(near(two.points[0].normal, -kUp));
    CHECK(two.points[0].separation == Approx(-0.01));
    const auto one = collideOnce(ball, oneSided(kUnit), 0.0);
    REQUIRE(one.count == 1);
    CHECK(near(one.points[0].normal, kUp));
    CHECK(one.points[0].separation == Approx(-0.11));
    // Wholly behind, or behind and beside the face: nothing from a one-sided triangle.
    CHECK(collideOnce(ConvexShape::sphere({0.2, -0.07, 0.2}, 0.06), oneSided(kUnit), 0.0).count ==
          0);
    CHECK(collideOnce(ConvexShape::sphere({0.5, -0.01, -0.03}, 0.06), oneSided(kUnit), 0.0).count ==
          0);
}

TEST_CASE("Contact: sphere-triangle agrees with the exact point-triangle distance") {
    Random rng(41);
    for (int trial = 0; trial < 2000; ++trial) {
        const TriangleCorners t{randomVec(rng, 0.1), randomVec(rng, 0.1), randomVec(rng, 0.1)};
        const Vec3 c = randomVec(rng, 0.15);
        const double r = rng.uniform(0.001, 0.05);
        const double exact = std::sqrt(triangleDistance2(c, t)) - r;
        const auto m = collideOnce(ConvexShape::sphere(c, r), twoSided(t), 0.02);
        if (exact > 0.02 + 1e-9) {
            CHECK(m.count == 0);
        } else if (exact < 0.02 - 1e-9) {
            REQUIRE(m.count == 1);
            CHECK(m.points[0].separation == Approx(exact).margin(1e-12));
        }
    }
}

TEST_CASE("Contact: a box resting on a large triangle gives its 4 corners, one- or two-sided") {
    for (const ConvexShape& t : {oneSided(kLarge), twoSided(kLarge)}) {
        const Mat3 r = rotation(0.5, {0, 1, 0});
        const ConvexShape box = ConvexShape::box({0.3, 0.049, -0.2}, r, {0.1, 0.05, 0.07});
        const ConvexHull hull = boxHull(box.halfExtents);
        for (const auto& m : {collideOnce(box, t, 0.0),
                              collideOnce(ConvexShape::hullAt(hull, box.center, r), t, 0.0)}) {
            REQUIRE(m.count == 4);
            for (int i = 0; i < 4; ++i) {
                CHECK(near(m.points[static_cast<std::size_t>(i)].normal, kUp));
                CHECK(m.points[static_cast<std::size_t>(i)].separation == Approx(-0.001));
            }
            for (const double sx : {-1.0, 1.0}) {
                for (const double sz : {-1.0, 1.0}) {
                    const Vec3 corner = box.center + r * Vec3(0.1 * sx, -0.05, 0.07 * sz);
                    CHECK(hasPointAt(m, {corner.x, -0.0005, corner.z}, 1e-12));
                }
            }
        }
        // The margin: 3 mm above, reported within a 5 mm margin and not within 2 mm.
        const ConvexShape above = ConvexShape::box({0.3, 0.053, -0.2}, r, {0.1, 0.05, 0.07});
        const auto spec = collideOnce(above, t, 0.005);
        REQUIRE(spec.count == 4);
        CHECK(spec.points[0].separation == Approx(0.003));
        CHECK(collideOnce(above, t, 0.002).count == 0);
    }
}

TEST_CASE("Contact: a small triangle under a box face gives the triangle's corners") {
    const TriangleCorners small{Vec3(0.01, 0, 0.01), Vec3(0.01, 0, 0.03), Vec3(0.03, 0, 0.01)};
    const ConvexShape box = ConvexShape::box({0, 0.049, 0}, Mat3(1.0), {0.1, 0.05, 0.1});
    const auto m = collideOnce(box, oneSided(small), 0.0);
    REQUIRE(m.count == 3);
    for (const Vec3& corner : small) {
        CHECK(hasPointAt(m, corner - kUp * 0.0005, 1e-12));
    }
    CHECK(minSeparation(m) == Approx(-0.001));
    // Asked the other way round, the same points with the normal turned.
    const auto turned = collideOnce(oneSided(small), box, 0.0);
    REQUIRE(turned.count == 3);
    for (int i = 0; i < 3; ++i) {
        CHECK(near(turned.points[static_cast<std::size_t>(i)].normal, -kUp));
        CHECK(hasPointAt(m, turned.points[static_cast<std::size_t>(i)].position, 1e-15));
    }
}

TEST_CASE("Contact: a box behind a one-sided triangle is pushed out front or left alone") {
    const ConvexShape below = ConvexShape::box({0.3, -0.049, -0.2}, Mat3(1.0), {0.1, 0.05, 0.07});
    const auto two = collideOnce(below, twoSided(kLarge), 0.0);
    REQUIRE(two.count == 4);
    CHECK(near(two.points[0].normal, -kUp));
    CHECK(two.points[0].separation == Approx(-0.001));
    const auto one = collideOnce(below, oneSided(kLarge), 0.0);
    REQUIRE(one.count > 0);
    CHECK(near(one.points[0].normal, kUp));
    CHECK(minSeparation(one) == Approx(-0.099));
    const ConvexShape wholly = ConvexShape::box({0.3, -0.2, -0.2}, Mat3(1.0), {0.1, 0.05, 0.07});
    CHECK(collideOnce(wholly, oneSided(kLarge), 0.01).count == 0);
    CHECK(collideOnce(wholly, twoSided(kLarge), 0.01).count == 0);
}

TEST_CASE("Contact: box-triangle agrees with the triangle-box SAT, one-sided never pulls back") {
    Random rng(43);
    int overlapping = 0;
    for (int trial = 0; trial < 1000; ++trial) {
        const ConvexShape box = randomBox(rng);
        TriangleCorners t{};
        for (Vec3& v : t) {
            v = box.center + randomVec(rng, 0.15);
        }
        const Vec3 n = glm::cross(t[1] - t[0], t[2] - t[0]);
        if (glm::length(n) < 1e-4) {
            continue;
        }
        TriangleCorners local{};
        for (int i = 0; i < 3; ++i) {
            local[static_cast<std::size_t>(i)] =
                glm::transpose(box.axes) * (t[static_cast<std::size_t>(i)] - box.center);
        }
        const bool overlap = overlapsTriangleAabb(local, {-box.halfExtents, box.halfExtents});
        const auto two = collideOnce(box, twoSided(t), 0.0);
        CHECK((two.count > 0) == overlap);
        overlapping += overlap ? 1 : 0;
        if (two.count > 0) {
            // No sampled point of the triangle lies deeper in the box than the depth found.
            const Obb obb{box.center, box.halfExtents, box.axes};
            double deepest = -1.0;
            for (int u = 0; u <= 8; ++u) {
                for (int v = 0; u + v <= 8; ++v) {
                    const Vec3 p = t[0] + (t[1] - t[0]) * (u / 8.0) + (t[2] - t[0]) * (v / 8.0);
                    deepest = std::max(deepest, -boxSignedDistance(obb, p));
                }
            }
            CHECK(deepest <= -minSeparation(two) + 1e-9);
        }
        const Vec3 front = glm::normalize(n);
        const auto one = collideOnce(box, ConvexShape::triangleOf(t, front), 0.01);
        for (int i = 0; i < one.count; ++i) {
            CHECK(glm::dot(one.points[static_cast<std::size_t>(i)].normal, front) >= -1e-9);
        }
    }
    CHECK(overlapping > 100);
}
