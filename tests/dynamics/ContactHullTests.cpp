// The narrow phase with convex hulls: a hull made of a box gives the box's contacts (sphere,
// box and hull partners, random poses); an octahedron's corner and edge on a box; hull-hull
// depth sign against point sampling; the manifold of two large faces keeps at most kMax points
// spanning it; the topology a hull derives once for the narrow phase.

#include "ContactTestShapes.h"

#include "hapto/core/Random.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

using namespace hapto;
using namespace hapto::contact_test;

namespace {

ConvexShape hullLike(const ConvexHull& hull, const ConvexShape& box) {
    return ConvexShape::hullAt(hull, box.center, box.axes);
}

} // namespace

TEST_CASE("Contact: a box's hull collides like the box (sphere, box and hull partners)") {
    Random rng(19);
    int touching = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const ConvexShape a = randomBox(rng);
        ConvexShape b = randomBox(rng);
        b.center = a.center + randomVec(rng, 0.2);
        const ConvexHull ha = boxHull(a.halfExtents);
        const ConvexHull hb = boxHull(b.halfExtents);
        const auto boxes = collideOnce(a, b, 0.01);
        for (const auto& m :
             {collideOnce(hullLike(ha, a), b, 0.01), collideOnce(a, hullLike(hb, b), 0.01),
              collideOnce(hullLike(ha, a), hullLike(hb, b), 0.01)}) {
            REQUIRE(m.count == boxes.count);
            if (m.count > 0) {
                CHECK(minSeparation(m) == Approx(minSeparation(boxes)).margin(1e-12));
                CHECK(near(m.points[0].normal, boxes.points[0].normal, 1e-9));
            }
        }
        touching += boxes.count > 0 ? 1 : 0;
        const ConvexShape ball = ConvexShape::sphere(b.center, rng.uniform(0.005, 0.05));
        const auto vsBox = collideOnce(ball, a, 0.01);
        const auto vsHull = collideOnce(ball, hullLike(ha, a), 0.01);
        REQUIRE(vsBox.count == vsHull.count);
        if (vsBox.count > 0) {
            CHECK(vsHull.points[0].separation == Approx(vsBox.points[0].separation).margin(1e-12));
            CHECK(near(vsHull.points[0].normal, vsBox.points[0].normal, 1e-9));
            CHECK(near(vsHull.points[0].position, vsBox.points[0].position, 1e-12));
        }
    }
    CHECK(touching > 50);
}

TEST_CASE("Contact: an octahedron's corner and edge on a box") {
    const double r = 0.05;
    const ConvexHull oct = octahedron(r);
    const ConvexShape floor = ConvexShape::box({0, -0.5, 0}, Mat3(1.0), {1, 0.5, 1});
    SECTION("corner down: one point under it") {
        const auto m =
            collideOnce(ConvexShape::hullAt(oct, {0.1, r - 0.002, 0.2}, Mat3(1.0)), floor, 0.0);
        REQUIRE(m.count == 1);
        CHECK(near(m.points[0].normal, {0, 1, 0}));
        CHECK(m.points[0].separation == Approx(-0.002));
        CHECK(near(m.points[0].position, {0.1, -0.001, 0.2}, 1e-12));
    }
    SECTION("edge down: its two ends") {
        // Turned 45 degrees about z, the edge between corners -y and -x lies lowest, along x.
        const double low = r / std::sqrt(2.0);
        const auto m = collideOnce(ConvexShape::hullAt(oct, {0, low - 0.001, 0},
                                                       rotation(std::numbers::pi / 4, {0, 0, 1})),
                                   floor, 0.0);
        REQUIRE(m.count == 2);
        for (int i = 0; i < 2; ++i) {
            const ContactPoint& p = m.points[static_cast<std::size_t>(i)];
            CHECK(near(p.normal, {0, 1, 0}));
            CHECK(p.separation == Approx(-0.001));
            CHECK(std::abs(p.position.x) == Approx(low));
            CHECK(p.position.z == Approx(0.0).margin(1e-15));
        }
    }
    SECTION("apart beyond the margin, and within it") {
        const ConvexShape above = ConvexShape::hullAt(oct, {0, r + 0.003, 0}, Mat3(1.0));
        CHECK(collideOnce(above, floor, 0.002).count == 0);
        const auto m = collideOnce(above, floor, 0.004);
        REQUIRE(m.count == 1);
        CHECK(m.points[0].separation == Approx(0.003));
    }
}

TEST_CASE("Contact: hull-hull depth sign agrees with point sampling, and is symmetric") {
    Random rng(23);
    const ConvexHull oct = octahedron(0.06);
    const ConvexHull box = boxHull({0.05, 0.02, 0.04});
    int overlapping = 0;
    for (int trial = 0; trial < 400; ++trial) {
        const ConvexShape a = ConvexShape::hullAt(oct, randomVec(rng, 0.05), randomRotation(rng));
        const ConvexShape b = ConvexShape::hullAt(box, randomVec(rng, 0.05), randomRotation(rng));
        const auto ab = collideOnce(a, b, 0.0);
        const auto ba = collideOnce(b, a, 0.0);
        REQUIRE(ab.count == ba.count);
        // Points of a (its corners and points between them and its centre) inside b.
        double deepest = -1.0;
        for (const Vec3& v : oct.vertices) {
            for (const double t : {1.0, 0.75, 0.5, 0.25, 0.0}) {
                deepest = std::max(deepest, hullDepth(b, a.center + a.axes * (v * t)));
            }
        }
        if (ab.count == 0) {
            CHECK(deepest <= 0.0);
            continue;
        }
        ++overlapping;
        CHECK(deepest <= -minSeparation(ab) + 1e-9);
        CHECK(minSeparation(ab) == Approx(minSeparation(ba)).margin(1e-12));
        CHECK(near(ab.points[0].normal, -ba.points[0].normal, 1e-9));
    }
    CHECK(overlapping > 100);
}

TEST_CASE("Contact: two large polygon faces keep at most kMax points spanning the patch") {
    // Two 12-sided prisms, one resting on the other turned by 15 degrees: the clipped patch
    // has 24 corners; the manifold keeps 8, the deepest first, spread round the patch.
    std::vector<Vec3> corners;
    for (int i = 0; i < 12; ++i) {
        const double t = 2 * std::numbers::pi * i / 12;
        corners.push_back({0.1 * std::cos(t), -0.02, 0.1 * std::sin(t)});
        corners.push_back({0.1 * std::cos(t), 0.02, 0.1 * std::sin(t)});
    }
    const ConvexHull prism = hullOfPoints(corners);
    const ConvexShape lower = ConvexShape::hullAt(prism, Vec3(0.0), Mat3(1.0));
    const ConvexShape upper =
        ConvexShape::hullAt(prism, {0, 0.039, 0}, rotation(std::numbers::pi / 12, {0, 1, 0}));
    const auto m = collideOnce(upper, lower, 0.0);
    REQUIRE(m.count == ContactManifold::kMax);
    double spread = 0.0;
    for (int i = 0; i < m.count; ++i) {
        const ContactPoint& p = m.points[static_cast<std::size_t>(i)];
        CHECK(near(p.normal, {0, 1, 0}));
        CHECK(p.separation == Approx(-0.001));
        spread = std::max(spread, std::hypot(p.position.x, p.position.z));
    }
    CHECK(spread > 0.09); // on the rim, not bunched
}

TEST_CASE("Contact: a hull's derived topology lists each face's corners around it and each "
          "edge's two faces") {
    // What collide() reads instead of recomputing (ConvexHull::deriveTopology): every corner of
    // a face lies on its plane and every vertex on the plane is a corner; going around the
    // corners turns one way only (angular order about the normal); an edge's two faces both
    // hold its ends, and they are the first two in face order that do.
    Random rng(23);
    for (int trial = 0; trial < 20; ++trial) {
        std::vector<Vec3> points;
        for (int k = 0; k < 6 + trial; ++k) {
            points.push_back(glm::normalize(randomVec(rng, 1.0) + Vec3(1e-3)) * 0.02);
        }
        const ConvexHull h = hullOfPoints(points);
        REQUIRE(h.hasTopology());
        const double tol = ConvexHull::kOnFaceTolerance * h.radiusM;
        for (std::size_t f = 0; f < h.faces.size(); ++f) {
            const ConvexHull::Face& face = h.faces[f];
            const std::uint32_t b = h.faceCornerBegin[f], e = h.faceCornerBegin[f + 1];
            std::size_t onPlane = 0;
            for (const Vec3& v : h.vertices) {
                onPlane += std::abs(glm::dot(face.normal, v) - face.offset) <= tol ? 1 : 0;
            }
            REQUIRE(e - b == onPlane);
            REQUIRE(e - b >= 3);
            double turn = 0.0;
            for (std::uint32_t c = b; c < e; ++c) {
                const Vec3& p = h.vertices[h.faceCorners[c]];
                const Vec3& q = h.vertices[h.faceCorners[b + (c - b + 1) % (e - b)]];
                const Vec3& r = h.vertices[h.faceCorners[b + (c - b + 2) % (e - b)]];
                const double t = glm::dot(glm::cross(q - p, r - q), face.normal);
                REQUIRE(t * turn >= 0.0); // never turns back
                turn = t != 0.0 ? t : turn;
            }
        }
        for (std::size_t k = 0; k < h.edges.size(); ++k) {
            const auto& faces = h.edgeFaces[k];
            REQUIRE(faces[0] != ConvexHull::kNoFace);
            REQUIRE(faces[0] < faces[1]);
            for (const std::uint32_t f : faces) {
                for (const std::uint32_t v : h.edges[k]) {
                    CHECK(std::abs(glm::dot(h.faces[f].normal, h.vertices[v]) -
                                   h.faces[f].offset) <= tol);
                }
            }
        }
    }
}
