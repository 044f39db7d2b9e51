#pragma once
/// Closest points and distances for the renderer's shapes: the point of a triangle nearest a
/// point, a triangle's in-plane edges, the "over a triangle grown by a margin" test, the
/// distance to a triangle's skin, the nearest surface point of a box or sphere for a point
/// inside it, and the point nearest a goal inside at most three half-spaces (SI units, m).
///
/// Pure geometry in the frame the caller works in: no scene, no allocation, no exception. The
/// renderer (runtime/src/GodObjectRenderer*.cpp) keeps its proxy outside skins grown around
/// objects with these; the swept tests beside them are in SweptShapes.h.

#include "hapto/core/Geometry.h"
#include "hapto/core/ShapeGeometry.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace hapto {

/// The point of triangle t closest to p (Ericson, Real-Time Collision Detection, 5.1.5: the
/// Voronoi regions of the corners, then of the edges, then the face). [servo]
Vec3 closestPointOnTriangle(const Vec3& p, const TriangleCorners& t) noexcept;
/// Squared distance (m^2) from p to triangle t. [servo]
double triangleDistance2(const Vec3& p, const TriangleCorners& t) noexcept;

/// A triangle's edges in its plane: inward[i] is perpendicular to the edge t[i] -> t[i+1] (the
/// unit normal crossed with it), points into a counter-clockwise triangle and is as long as
/// the edge; length2[i] is its squared length (m^2).
struct TriangleEdges {
    std::array<Vec3, 3> inward{};    ///< Edge i's inward vector, as long as the edge (m).
    std::array<double, 3> length2{}; ///< Edge i's squared length (m^2).
};
/// The edges of triangle t with unit normal `normal`. [servo]
TriangleEdges triangleEdges(const TriangleCorners& t, const Vec3& normal) noexcept;
/// A triangle's corners and in-plane edges, as the tests below read them.
struct TriangleGeometry {
    TriangleCorners corners{}; ///< The corners, counter-clockwise seen from outside (m).
    TriangleEdges edges;       ///< The in-plane edges, from triangleEdges().
};

/// How far (m) p's projection onto the plane of triangle t lies outside the farthest of its
/// three edge lines; <= 0 over the triangle. [servo]
double outsideTriangleEdges(const Vec3& p, const TriangleCorners& t,
                            const TriangleEdges& edges) noexcept;
/// True when p projects into triangle t (unit normal `normal`) grown by `marginM` across each
/// edge, as a box face's skin grows across its edges (square corners), with a sliver's sharp
/// corners cut at 1.5 x marginM from the triangle. Compares squares (no square root) edge by
/// edge. [servo]
bool overGrownTriangle(const Vec3& p, const TriangleCorners& t, const Vec3& normal,
                       const TriangleEdges& edges, double marginM) noexcept;
/// The same, the edges made on the spot. [servo]
bool overGrownTriangle(const Vec3& p, const TriangleCorners& t, const Vec3& normal,
                       double marginM) noexcept;

/// Distance (m) from p to a one-sided triangle's skin, 0 inside it: the skin is the points
/// within `skinM` of the plane {x : dot(normal, x) = offset} over the triangle grown by `skinM`
/// across its edges (a box face's skin). `geometry()` gives the triangle's TriangleGeometry
/// (or anything with `corners` and `edges`); it is called only for a triangle with a normal
/// (a zero normal: infinitely far). [servo]
template <class GeometryFn>
double triangleSkinDistance(const Vec3& normal, double offset, GeometryFn&& geometry, const Vec3& p,
                            double skinM) noexcept {
    if (normal == Vec3(0.0)) {
        return std::numeric_limits<double>::infinity();
    }
    const double up = std::max(0.0, std::abs(glm::dot(normal, p) - offset) - skinM);
    const auto& g = geometry();
    const double out = std::max(0.0, outsideTriangleEdges(p, g.corners, g.edges) - skinM);
    return std::sqrt(up * up + out * out);
}

/// The point of the sphere's surface nearest p (p inside it; the centre goes to +z). [servo]
Vec3 sphereSurfacePointNearest(const Vec3& center, double radius, const Vec3& p) noexcept;
/// The point of a box's surface nearest `local` (box frame; `local` inside it): its nearest
/// face's (dominantFaceAxis) point straight out. [servo]
Vec3 boxSurfacePointNearestLocal(const Vec3& local, const Vec3& halfExtents) noexcept;

/// The point nearest `goal` in {x : dot(planes[i].normal, x) >= planes[i].offset - slackM, i <
/// count} (count <= 3; PlaneT has `normal` (unit) and `offset` (m)): the best feasible
/// projection of the goal onto the planes of each subset (8 subsets for 3 planes; a subset
/// of parallel planes is covered by its single planes). `fallback` (a point known to be
/// feasible) when no subset gives a feasible point (degenerate planes). [servo]
template <class PlaneT>
Vec3 closestPointInHalfSpaces(const PlaneT* planes, std::uint32_t count, const Vec3& goal,
                              const Vec3& fallback, double slackM) noexcept {
    Vec3 best = fallback;
    double bestD = std::numeric_limits<double>::infinity();
    for (std::uint32_t mask = 0; mask < (1u << count); ++mask) {
        std::uint32_t idx[3];
        std::uint32_t k = 0;
        for (std::uint32_t i = 0; i < count; ++i) {
            if (mask & (1u << i)) {
                idx[k++] = i;
            }
        }
        Vec3 c = goal;
        if (k == 1) {
            const PlaneT& p = planes[idx[0]];
            c = goal - (glm::dot(p.normal, goal) - p.offset) * p.normal;
        } else if (k == 2) {
            const PlaneT& p1 = planes[idx[0]];
            const PlaneT& p2 = planes[idx[1]];
            const double a = glm::dot(p1.normal, p2.normal);
            const double det = 1.0 - a * a;
            if (det < 1e-10) {
                continue; // (anti)parallel: a single-plane subset covers it
            }
            const double r1 = glm::dot(p1.normal, goal) - p1.offset;
            const double r2 = glm::dot(p2.normal, goal) - p2.offset;
            const double l1 = (r1 - a * r2) / det;
            const double l2 = (r2 - a * r1) / det;
            c = goal - l1 * p1.normal - l2 * p2.normal;
        } else if (k == 3) {
            const PlaneT& p1 = planes[idx[0]];
            const PlaneT& p2 = planes[idx[1]];
            const PlaneT& p3 = planes[idx[2]];
            const Vec3 c23 = glm::cross(p2.normal, p3.normal);
            const double det = glm::dot(p1.normal, c23);
            if (std::abs(det) < 1e-8) {
                continue;
            }
            c = (p1.offset * c23 + p2.offset * glm::cross(p3.normal, p1.normal) +
                 p3.offset * glm::cross(p1.normal, p2.normal)) /
                det;
        }
        bool feasible = true;
        for (std::uint32_t i = 0; i < count && feasible; ++i) {
            feasible = glm::dot(planes[i].normal, c) >= planes[i].offset - slackM;
        }
        const Vec3 away = c - goal;
        const double d = glm::dot(away, away);
        if (feasible && d < bestD) {
            bestD = d;
            best = c;
        }
    }
    return best;
}

} // namespace hapto
