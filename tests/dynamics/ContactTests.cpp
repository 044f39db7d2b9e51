// The narrow phase (Contact.h): every pair separated, touching and penetrating with known
// depths and normals; a box resting on a box; edge-edge; symmetry; the margin; randomised
// agreement with independent distance and overlap tests (ShapeGeometry.h's exact box SDF and
// separating-axis overlap test, and point sampling).

#include "ContactTestShapes.h"

#include "hapto/core/Random.h"
#include "hapto/core/ShapeGeometry.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

using namespace hapto;
using namespace hapto::contact_test;

TEST_CASE("Contact: sphere-sphere separated, touching and penetrating") {
    const ConvexShape b = ConvexShape::sphere(Vec3(0.0), 0.1);
    SECTION("beyond the margin: nothing") {
        const auto m = collideOnce(ConvexShape::sphere({0.35, 0, 0}, 0.2), b, 0.01);
        CHECK(m.count == 0);
    }
    SECTION("within the margin: a speculative point") {
        const auto m = collideOnce(ConvexShape::sphere({0.305, 0, 0}, 0.2), b, 0.01);
        REQUIRE(m.count == 1);
        CHECK(m.points[0].separation == Approx(0.005).margin(1e-12));
        CHECK(near(m.points[0].normal, {1, 0, 0}));
        CHECK(near(m.points[0].position, {0.1025, 0, 0}));
    }
    SECTION("touching") {
        const auto m = collideOnce(ConvexShape::sphere({0, 0.3, 0}, 0.2), b, 0.0);
        REQUIRE(m.count == 1);
        CHECK(m.points[0].separation == Approx(0.0).margin(1e-15));
        CHECK(near(m.points[0].normal, {0, 1, 0}));
    }
    SECTION("penetrating") {
        const auto m = collideOnce(ConvexShape::sphere({0, 0, -0.25}, 0.2), b, 0.0);
        REQUIRE(m.count == 1);
        CHECK(m.points[0].separation == Approx(-0.05));
        CHECK(near(m.points[0].normal, {0, 0, -1}));
        CHECK(near(m.points[0].position, {0, 0, -0.075}));
    }
}

TEST_CASE("Contact: sphere-box by face, edge, corner and centre inside, rotated") {
    const Mat3 r = rotation(0.4, {1, 2, 3});
    const ConvexShape b = ConvexShape::box({0.1, 0.2, 0.3}, r, {0.1, 0.2, 0.3});
    const auto world = [&](Vec3 local) { return b.center + r * local; };
    SECTION("face") {
        const auto m = collideOnce(ConvexShape::sphere(world({0, 0.25, 0}), 0.06), b, 0.0);
        REQUIRE(m.count == 1);
        CHECK(m.points[0].separation == Approx(-0.01));
        CHECK(near(m.points[0].normal, r[1]));
    }
    SECTION("edge") {
        const Vec3 out = glm::normalize(Vec3(1, 1, 0));
        const Vec3 c = world(Vec3(0.1, 0.2, 0.05) + out * 0.03);
        const auto m = collideOnce(ConvexShape::sphere(c, 0.02), b, 0.02);
        REQUIRE(m.count == 1);
        CHECK(m.points[0].separation == Approx(0.01));
        CHECK(near(m.points[0].normal, r * out));
    }
    SECTION("corner") {
        const Vec3 out = glm::normalize(Vec3(-1, 1, -1));
        const Vec3 c = world(Vec3(-0.1, 0.2, -0.3) + out * 0.01);
        const auto m = collideOnce(ConvexShape::sphere(c, 0.02), b, 0.0);
        REQUIRE(m.count == 1);
        CHECK(m.points[0].separation == Approx(-0.01));
        CHECK(near(m.points[0].normal, r * out));
    }
    SECTION("centre inside: out through the nearest face") {
        const auto m = collideOnce(ConvexShape::sphere(world({0.08, 0, 0}), 0.01), b, 0.0);
        REQUIRE(m.count == 1);
        CHECK(m.points[0].separation == Approx(-0.03));
        CHECK(near(m.points[0].normal, r[0]));
    }
    SECTION("apart") {
        CHECK(collideOnce(ConvexShape::sphere(world({0, 0, 0.5}), 0.1), b, 0.05).count == 0);
    }
}

TEST_CASE("Contact: sphere-box agrees with the box's exact signed distance") {
    Random rng(37);
    for (int trial = 0; trial < 2000; ++trial) {
        const ConvexShape b = randomBox(rng);
        const Vec3 c = b.center + randomVec(rng, 0.3);
        const double radius = rng.uniform(0.001, 0.1);
        const double exact = boxSignedDistance(Obb{b.center, b.halfExtents, b.axes}, c) - radius;
        const auto m = collideOnce(ConvexShape::sphere(c, radius), b, 0.05);
        if (exact > 0.05 + 1e-9) {
            CHECK(m.count == 0);
        } else if (exact <= 0.05 - 1e-9) {
            REQUIRE(m.count == 1);
            CHECK(m.points[0].separation == Approx(exact).margin(1e-12));
            // The point moved by -separation along the normal touches the box's surface.
            const Vec3 onBox = m.points[0].position - m.points[0].normal * (0.5 * exact);
            CHECK(std::abs(boxSignedDistance(Obb{b.center, b.halfExtents, b.axes}, onBox)) < 1e-9);
        }
    }
}

TEST_CASE("Contact: box resting flat on a box gives its 4 bottom corners") {
    const double pen = 0.001;
    const ConvexShape floor = ConvexShape::box({0, -0.5, 0}, Mat3(1.0), {1, 0.5, 1});
    for (const double yaw : {0.0, 0.3, std::numbers::pi / 4}) {
        const Mat3 r = rotation(yaw, {0, 1, 0});
        const ConvexShape top = ConvexShape::box({0.2, 0.05 - pen, -0.1}, r, {0.1, 0.05, 0.07});
        const auto m = collideOnce(top, floor, 0.0);
        REQUIRE(m.count == 4);
        for (int i = 0; i < m.count; ++i) {
            const ContactPoint& p = m.points[static_cast<std::size_t>(i)];
            CHECK(near(p.normal, {0, 1, 0}));
            CHECK(p.separation == Approx(-pen));
            CHECK(p.position.y == Approx(-pen / 2));
        }
        // The points are the top box's bottom corners (in x, z).
        for (const double sx : {-1.0, 1.0}) {
            for (const double sz : {-1.0, 1.0}) {
                const Vec3 corner = top.center + r * Vec3(0.1 * sx, -0.05, 0.07 * sz);
                CHECK(hasPointAt(m, {corner.x, -pen / 2, corner.z}, 1e-12));
            }
        }
    }
}

TEST_CASE(
    "Contact: a small box on a large one's face, either as a or b, is clipped to the small face") {
    const ConvexShape big = ConvexShape::box({0, 0, 0}, Mat3(1.0), {0.5, 0.5, 0.5});
    const ConvexShape small =
        ConvexShape::box({0.1, 0.55, 0}, rotation(0.2, {0, 1, 0}), {0.05, 0.06, 0.05});
    const auto ab = collideOnce(small, big, 0.0);
    const auto ba = collideOnce(big, small, 0.0);
    REQUIRE(ab.count == 4);
    REQUIRE(ba.count == 4);
    for (int i = 0; i < 4; ++i) {
        const auto k = static_cast<std::size_t>(i);
        CHECK(near(ab.points[k].normal, {0, 1, 0}));
        CHECK(near(ba.points[k].normal, {0, -1, 0}));
        CHECK(ab.points[k].separation == Approx(-0.01));
        CHECK(ba.points[k].separation == Approx(-0.01));
        CHECK(hasPointAt(ba, ab.points[k].position, 1e-12));
    }
}

TEST_CASE("Contact: box-box speculative points within the margin, none beyond") {
    const ConvexShape floor = ConvexShape::box({0, -0.5, 0}, Mat3(1.0), {1, 0.5, 1});
    const ConvexShape top = ConvexShape::box({0, 0.053, 0}, Mat3(1.0), {0.1, 0.05, 0.1});
    const auto within = collideOnce(top, floor, 0.005);
    REQUIRE(within.count == 4);
    for (int i = 0; i < 4; ++i) {
        CHECK(within.points[static_cast<std::size_t>(i)].separation == Approx(0.003));
    }
    CHECK(collideOnce(top, floor, 0.002).count == 0);
    // Touching exactly counts at margin 0.
    const ConvexShape touching = ConvexShape::box({0, 0.05, 0}, Mat3(1.0), {0.1, 0.05, 0.1});
    CHECK(collideOnce(touching, floor, 0.0).count == 4);
}

TEST_CASE("Contact: box-box edge on edge gives one point on the crossing ridges") {
    // A cube turned 45 degrees about z (ridge along z on top) under a cube turned 45 degrees
    // about x (ridge along x below): the ridges cross at x = z = 0.
    const double h = 0.05;
    const double ridge = std::sqrt(2.0) * h;
    const double pen = 0.002;
    const ConvexShape lower =
        ConvexShape::box(Vec3(0.0), rotation(std::numbers::pi / 4, {0, 0, 1}), Vec3(h));
    const ConvexShape upper = ConvexShape::box({0, 2 * ridge - pen, 0},
                                               rotation(std::numbers::pi / 4, {1, 0, 0}), Vec3(h));
    const auto m = collideOnce(upper, lower, 0.0);
    REQUIRE(m.count == 1);
    CHECK(near(m.points[0].normal, {0, 1, 0}));
    CHECK(m.points[0].separation == Approx(-pen));
    CHECK(near(m.points[0].position, {0, ridge - pen / 2, 0}, 1e-12));
    const auto gap =
        collideOnce(ConvexShape::box({0, 2 * ridge + 0.001, 0}, upper.axes, Vec3(h)), lower, 0.002);
    REQUIRE(gap.count == 1);
    CHECK(gap.points[0].separation == Approx(0.001));
}

TEST_CASE("Contact: box-box is symmetric (normals opposite, same depths) on random pairs") {
    Random rng(7);
    int compared = 0;
    for (int trial = 0; trial < 500; ++trial) {
        const ConvexShape a = randomBox(rng);
        ConvexShape b = randomBox(rng);
        b.center = a.center + randomVec(rng, 0.2);
        const auto ab = collideOnce(a, b, 0.01);
        const auto ba = collideOnce(b, a, 0.01);
        REQUIRE(ab.count == ba.count);
        if (ab.count == 0) {
            continue;
        }
        ++compared;
        CHECK(near(ab.points[0].normal, -ba.points[0].normal, 1e-9));
        CHECK(minSeparation(ab) == Approx(minSeparation(ba)).margin(1e-12));
    }
    CHECK(compared > 100);
}

TEST_CASE("Contact: box-box depth sign agrees with the independent SAT and with sampling") {
    Random rng(11);
    for (int trial = 0; trial < 1000; ++trial) {
        const ConvexShape a = randomBox(rng);
        ConvexShape b = randomBox(rng);
        b.center = a.center + randomVec(rng, 0.25);
        const auto m = collideOnce(a, b, 0.0);
        const Obb oa{a.center, a.halfExtents, a.axes};
        const Obb ob{b.center, b.halfExtents, b.axes};
        const bool overlap = overlapsObbObb(oa, ob);
        CHECK((m.count > 0) == overlap);
        if (m.count > 0) {
            const double depth = -minSeparation(m);
            CHECK(depth >= -1e-9);
            // Sampled corners and points of a inside b never lie deeper than the depth found.
            CHECK(deepestSampleInside(a, ob) <= depth + 1e-9);
        } else {
            // Apart: no sample of a lies inside b.
            CHECK(deepestSampleInside(a, ob) <= 0.0);
        }
    }
}

TEST_CASE("Contact: a resting box keeps its features when it moves a hair") {
    const ConvexShape floor = ConvexShape::box({0, -0.5, 0}, Mat3(1.0), {1, 0.5, 1});
    const Mat3 r = rotation(0.3, {0, 1, 0});
    const auto m0 = collideOnce(ConvexShape::box({0, 0.049, 0}, r, {0.1, 0.05, 0.1}), floor, 0.0);
    const auto m1 = collideOnce(
        ConvexShape::box({1e-5, 0.0491, -2e-5}, rotation(0.3001, {0, 1, 0}), {0.1, 0.05, 0.1}),
        floor, 0.0);
    REQUIRE(m0.count == 4);
    REQUIRE(m1.count == 4);
    for (int i = 0; i < 4; ++i) {
        const auto k = static_cast<std::size_t>(i);
        CHECK(m0.points[k].feature == m1.points[k].feature);
        CHECK(glm::length(m0.points[k].position - m1.points[k].position) < 1e-3);
    }
    // The four features differ from each other.
    for (int i = 0; i < 4; ++i) {
        for (int j = i + 1; j < 4; ++j) {
            CHECK(m0.points[static_cast<std::size_t>(i)].feature !=
                  m0.points[static_cast<std::size_t>(j)].feature);
        }
    }
}

TEST_CASE("Contact: a sphere as b against a box as a turns the normal") {
    const ConvexShape box = ConvexShape::box(Vec3(0.0), Mat3(1.0), Vec3(0.1));
    const ConvexShape ball = ConvexShape::sphere({0, 0.15, 0}, 0.06);
    const auto ab = collideOnce(box, ball, 0.0);
    const auto ba = collideOnce(ball, box, 0.0);
    REQUIRE(ab.count == 1);
    REQUIRE(ba.count == 1);
    CHECK(near(ab.points[0].normal, {0, -1, 0}));
    CHECK(near(ba.points[0].normal, {0, 1, 0}));
    CHECK(ab.points[0].separation == Approx(-0.01));
    CHECK(near(ab.points[0].position, ba.points[0].position));
}

TEST_CASE("Contact: identical inputs give identical manifolds, bit for bit") {
    Random rng(3);
    for (int trial = 0; trial < 100; ++trial) {
        const ConvexShape a = randomBox(rng);
        ConvexShape b = randomBox(rng);
        b.center = a.center + randomVec(rng, 0.2);
        const auto m1 = collideOnce(a, b, 0.01);
        const auto m2 = collideOnce(a, b, 0.01);
        REQUIRE(m1.count == m2.count);
        CHECK(std::equal(m1.points.begin(), m1.points.begin() + m1.count, m2.points.begin(),
                         [](const ContactPoint& x, const ContactPoint& y) {
                             return x.position == y.position && x.normal == y.normal &&
                                    x.separation == y.separation && x.feature == y.feature;
                         }));
    }
}
