#include "hapto/core/ClosestPoint.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <random>

using namespace hapto;

namespace {

/// The unit right triangle in z = 0, counter-clockwise seen from +z.
const TriangleCorners kTri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
const Vec3 kUp(0, 0, 1);

bool near(const Vec3& a, const Vec3& b, double tol = 1e-12) {
    return glm::length(a - b) <= tol;
}

struct HalfSpace {
    Vec3 normal{0.0};
    double offset = 0.0;
};

} // namespace

TEST_CASE("closest point on a triangle: each Voronoi region") {
    // Corners.
    CHECK(near(closestPointOnTriangle(Vec3(-1, -1, 0.5), kTri), kTri[0]));
    CHECK(near(closestPointOnTriangle(Vec3(2, -0.5, -1), kTri), kTri[1]));
    CHECK(near(closestPointOnTriangle(Vec3(-0.5, 2, 0), kTri), kTri[2]));
    // Edges.
    CHECK(near(closestPointOnTriangle(Vec3(0.5, -1, 0.3), kTri), Vec3(0.5, 0, 0)));
    CHECK(near(closestPointOnTriangle(Vec3(-1, 0.25, 0), kTri), Vec3(0, 0.25, 0)));
    CHECK(near(closestPointOnTriangle(Vec3(1, 1, 2), kTri), Vec3(0.5, 0.5, 0)));
    // The face.
    CHECK(near(closestPointOnTriangle(Vec3(0.2, 0.3, 5), kTri), Vec3(0.2, 0.3, 0)));
    CHECK(near(closestPointOnTriangle(Vec3(0.2, 0.3, -5), kTri), Vec3(0.2, 0.3, 0)));
    CHECK(triangleDistance2(Vec3(0.2, 0.3, -5), kTri) == Approx(25.0));
    CHECK(triangleDistance2(Vec3(1, 1, 0), kTri) == Approx(0.5));
}

TEST_CASE("closest point on a triangle: no point of the triangle is nearer") {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::uniform_real_distribution<double> w(0.0, 1.0);
    for (int n = 0; n < 500; ++n) {
        const TriangleCorners t{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)),
                                Vec3(u(rng), u(rng), u(rng))};
        const Vec3 p(2 * u(rng), 2 * u(rng), 2 * u(rng));
        const Vec3 c = closestPointOnTriangle(p, t);
        const double d2 = triangleDistance2(p, t);
        INFO("case " << n);
        REQUIRE(glm::dot(p - c, p - c) == Approx(d2).margin(1e-15));
        for (int k = 0; k < 50; ++k) {
            double a = w(rng);
            double b = w(rng);
            if (a + b > 1.0) {
                a = 1.0 - a;
                b = 1.0 - b;
            }
            const Vec3 q = t[0] + a * (t[1] - t[0]) + b * (t[2] - t[0]);
            REQUIRE(glm::dot(p - q, p - q) >= d2 - 1e-12);
        }
    }
}

TEST_CASE("triangle edges point inward, as long as the edges") {
    const TriangleEdges e = triangleEdges(kTri, kUp);
    const Vec3 centroid = (kTri[0] + kTri[1] + kTri[2]) / 3.0;
    for (int i = 0; i < 3; ++i) {
        const Vec3 edge = kTri[(i + 1) % 3] - kTri[i];
        CHECK(glm::dot(e.inward[i], centroid - kTri[i]) > 0.0);
        CHECK(glm::dot(e.inward[i], edge) == Approx(0.0).margin(1e-15));
        CHECK(e.length2[i] == Approx(glm::dot(edge, edge)));
    }
    CHECK(outsideTriangleEdges(Vec3(0.5, -0.25, 7), kTri, e) == Approx(0.25));
    CHECK(outsideTriangleEdges(Vec3(-0.25, 0.5, 0), kTri, e) == Approx(0.25));
    CHECK(outsideTriangleEdges(Vec3(0.75, 0.75, 0), kTri, e) == Approx(std::sqrt(0.125)));
    CHECK(outsideTriangleEdges(centroid, kTri, e) < 0.0);
}

TEST_CASE("over a grown triangle: square across the edges, a sliver's sharp corner cut") {
    const TriangleEdges e = triangleEdges(kTri, kUp);
    // Across an edge: within the margin, at any height.
    CHECK(overGrownTriangle(Vec3(0.5, -0.09, 3), kTri, kUp, e, 0.1));
    CHECK_FALSE(overGrownTriangle(Vec3(0.5, -0.11, 3), kTri, kUp, e, 0.1));
    // The right-angled corner: square (0.14 from the corner, under 1.5 x margin).
    CHECK(overGrownTriangle(Vec3(-0.099, -0.099, 0), kTri, kUp, e, 0.1));
    CHECK(overGrownTriangle(Vec3(-0.099, -0.099, 0), kTri, kUp, 0.1));
    // A sliver (5.7 degrees at its first corner): a point 0.5 beyond that corner is within the
    // margin of both edge lines there, but 3.3 margins from the triangle: not over it.
    const TriangleCorners sliver{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 0.1, 0)};
    const TriangleEdges se = triangleEdges(sliver, kUp);
    const Vec3 beyond(-0.5, -0.04, 0);
    REQUIRE(outsideTriangleEdges(beyond, sliver, se) <= 0.1);
    CHECK_FALSE(overGrownTriangle(beyond, sliver, kUp, se, 0.1));
    CHECK(overGrownTriangle(Vec3(-0.14, -0.01, 0), sliver, kUp, se, 0.1));
}

TEST_CASE("distance to a triangle's skin") {
    int fetched = 0;
    const auto geometry = [&] {
        ++fetched;
        return TriangleGeometry{kTri, triangleEdges(kTri, kUp)};
    };
    // Over the face: the height less the skin; beside an edge: the way out less the skin, in
    // both directions at once.
    CHECK(triangleSkinDistance(kUp, 0.0, geometry, Vec3(0.2, 0.2, 1.0), 0.1) == Approx(0.9));
    CHECK(triangleSkinDistance(kUp, 0.0, geometry, Vec3(0.2, 0.2, -1.0), 0.1) == Approx(0.9));
    CHECK(triangleSkinDistance(kUp, 0.0, geometry, Vec3(0.5, -0.5, 0.0), 0.1) == Approx(0.4));
    CHECK(triangleSkinDistance(kUp, 0.0, geometry, Vec3(0.5, -0.4, 0.4), 0.1) ==
          Approx(std::sqrt(0.18)));
    CHECK(triangleSkinDistance(kUp, 0.0, geometry, Vec3(0.2, 0.2, 0.05), 0.1) == 0.0);
    CHECK(fetched == 5);
    // No normal (a degenerate triangle): never near, its corners never read.
    CHECK(std::isinf(triangleSkinDistance(Vec3(0.0), 0.0, geometry, Vec3(0.2), 0.1)));
    CHECK(fetched == 5);
}

TEST_CASE("nearest surface point of a sphere and of a box from inside") {
    CHECK(near(sphereSurfacePointNearest(Vec3(1, 0, 0), 2.0, Vec3(1, 0.5, 0)), Vec3(1, 2, 0)));
    CHECK(near(sphereSurfacePointNearest(Vec3(1, 0, 0), 2.0, Vec3(1, 0, 0)), Vec3(1, 0, 2)));
    const Vec3 half(1.0, 2.0, 3.0);
    CHECK(near(boxSurfacePointNearestLocal(Vec3(0.8, 0.5, 0.5), half), Vec3(1.0, 0.5, 0.5)));
    CHECK(near(boxSurfacePointNearestLocal(Vec3(0.1, -1.9, 0.5), half), Vec3(0.1, -2.0, 0.5)));
    CHECK(near(boxSurfacePointNearestLocal(Vec3(0.1, 0.2, -2.95), half), Vec3(0.1, 0.2, -3.0)));
}

TEST_CASE("closest point in half-spaces: face, edge, corner, and a feasible goal") {
    const std::array<HalfSpace, 3> planes{HalfSpace{Vec3(1, 0, 0), 0.0},
                                          HalfSpace{Vec3(0, 1, 0), 0.0},
                                          HalfSpace{Vec3(0, 0, 1), 0.0}};
    const Vec3 fallback(1, 1, 1);
    CHECK(near(closestPointInHalfSpaces(planes.data(), 1, Vec3(-2, 3, 4), fallback, 0.0),
               Vec3(0, 3, 4)));
    CHECK(near(closestPointInHalfSpaces(planes.data(), 2, Vec3(-2, -3, 4), fallback, 0.0),
               Vec3(0, 0, 4)));
    CHECK(near(closestPointInHalfSpaces(planes.data(), 3, Vec3(-2, -3, -4), fallback, 0.0),
               Vec3(0, 0, 0)));
    CHECK(near(closestPointInHalfSpaces(planes.data(), 3, Vec3(2, -3, 4), fallback, 0.0),
               Vec3(2, 0, 4)));
    CHECK(near(closestPointInHalfSpaces(planes.data(), 3, Vec3(2, 3, 4), fallback, 0.0),
               Vec3(2, 3, 4)));
    CHECK(near(closestPointInHalfSpaces(planes.data(), 0, Vec3(-2, 3, 4), fallback, 0.0),
               Vec3(-2, 3, 4)));
    // Two opposed planes with no common point: nothing is feasible, the fallback is kept.
    const std::array<HalfSpace, 2> apart{HalfSpace{Vec3(1, 0, 0), 1.0},
                                         HalfSpace{Vec3(-1, 0, 0), 1.0}};
    CHECK(near(closestPointInHalfSpaces(apart.data(), 2, Vec3(0.0), fallback, 0.0), fallback));
}

TEST_CASE("closest point in half-spaces: feasible, and no sampled feasible point is nearer") {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int n = 0; n < 300; ++n) {
        std::array<HalfSpace, 3> planes{};
        for (HalfSpace& h : planes) {
            h.normal = glm::normalize(Vec3(u(rng), u(rng), u(rng)));
            h.offset = glm::dot(h.normal, Vec3(0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng)));
        }
        const Vec3 goal(u(rng), u(rng), u(rng));
        const Vec3 r = closestPointInHalfSpaces(planes.data(), 3, goal, Vec3(1e9), 1e-12);
        INFO("case " << n);
        REQUIRE(r != Vec3(1e9));
        for (const HalfSpace& h : planes) {
            REQUIRE(glm::dot(h.normal, r) >= h.offset - 1e-9);
        }
        const double best = glm::length(r - goal);
        for (int k = 0; k < 200; ++k) {
            const Vec3 q = r + 0.5 * Vec3(u(rng), u(rng), u(rng));
            bool feasible = true;
            for (const HalfSpace& h : planes) {
                feasible = feasible && glm::dot(h.normal, q) >= h.offset;
            }
            if (feasible) {
                REQUIRE(glm::length(q - goal) >= best - 1e-9);
            }
        }
    }
}
