#pragma once
/// Shape geometry every module shares: signed distances and inside tests for boxes and spheres,
/// the face a point lies beyond, and conservative separating-axis overlap tests (SI units, m).
///
/// The index places objects into cells with the overlap tests, the renderer keeps its proxy out
/// of skins grown around objects with the distance and inside tests, and the simulated hands
/// plan with signed distances: one implementation each, here.
///
/// Overlap tests may say "overlap" for a pair that is separated by a hair (a tolerance scaled to
/// the sizes and positions involved), and never say "separated" for a pair that overlaps: a
/// missed overlap is a hole the pointer falls through, a spurious one costs one more candidate.
/// Touching counts as overlap.

#include "hapto/core/Geometry.h"

#include <array>

namespace hapto {

/// Relative tolerance of every overlap test: separation must exceed this times the sizes and
/// distances from the origin involved (m), so rounding never hides an overlap.
inline constexpr double kOverlapTolerance = 1e-9;

/// Added to every |cos| between box axes, so near-parallel edges (whose cross product is a
/// nearly null, badly rounded axis) never produce a false separation (Gottschalk et al. 1996).
inline constexpr double kParallelEpsilon = 1e-9;

/// Signed distance (m) from p to the surface of `box` grown by `inflateM` on every side: < 0
/// inside, 0 on it, > 0 outside. Exact (the box SDF in the box's frame). [servo]
double boxSignedDistance(const Obb& box, const Vec3& p, double inflateM = 0.0) noexcept;
/// Signed distance (m) from p to a sphere's surface: |p - center| - radius. [servo]
double sphereSignedDistance(const Vec3& center, double radius, const Vec3& p) noexcept;
/// Distance (m) from p to the box grown by `inflateM`; 0 inside or on it. [servo]
double boxDistanceOutside(const Obb& box, const Vec3& p, double inflateM = 0.0) noexcept;
/// True when p lies strictly inside the box grown by `inflateM`. [servo]
bool boxStrictlyContains(const Obb& box, const Vec3& p, double inflateM = 0.0) noexcept;
/// boxDistanceOutside for a point already in the box's frame (`local`: Obb::toLocal's, or a
/// caller's own that skips the rotation of an axis-aligned box). Inline: the renderer calls it
/// once per plane and pass. [servo]
inline double boxDistanceOutsideLocal(const Vec3& halfExtents, const Vec3& local,
                                      double inflateM) noexcept {
    const Vec3 h = halfExtents + Vec3(inflateM);
    return glm::length(local - glm::clamp(local, -h, h));
}
/// boxStrictlyContains for a point already in the box's frame (as boxDistanceOutsideLocal).
/// [servo]
inline bool boxStrictlyContainsLocal(const Vec3& halfExtents, const Vec3& local,
                                     double inflateM) noexcept {
    const Vec3 l = glm::abs(local);
    const Vec3 h = halfExtents + Vec3(inflateM);
    return l.x < h.x && l.y < h.y && l.z < h.z;
}
/// True when p lies in the closed sphere: |p - center|^2 <= radius^2. [servo]
bool sphereContains(const Vec3& center, double radius, const Vec3& p) noexcept;
/// True when p lies strictly inside the sphere: |p - center|^2 < radius^2. [servo]
bool sphereStrictlyContains(const Vec3& center, double radius, const Vec3& p) noexcept;
/// The axis i whose face a point at `local` (box frame) lies farthest beyond, |local_i| -
/// halfExtents_i largest (for an inside point: the nearest face); the first axis on ties.
/// [servo]
int dominantFaceAxis(const Vec3& local, const Vec3& halfExtents) noexcept;

/// Largest |component| of v. [servo]
double maxAbsComponent(const Vec3& v) noexcept;
/// The size scale of a box for tolerances: largest |centre| coordinate plus largest edge (m).
/// [servo]
double aabbScale(const Aabb& box) noexcept;
/// The tolerance (m) an overlap test allows between two things of these scales (m). [servo]
inline double overlapToleranceFor(double scaleA, double scaleB) noexcept {
    return kOverlapTolerance * (scaleA + scaleB);
}

/// Separating-axis test, all 15 axes, between two oriented boxes. Conservative. [any thread]
bool overlapsObbObb(const Obb& a, const Obb& b) noexcept;
/// Separating-axis test between an oriented box and an axis-aligned box. Conservative.
/// [any thread]
bool overlapsObbAabb(const Obb& box, const Aabb& cell) noexcept;
/// Exact sphere/box test (distance from the centre to the box <= radius), conservative by the
/// tolerance. [any thread]
bool overlapsSphereAabb(const Vec3& center, double radius, const Aabb& cell) noexcept;
/// Closed AABB/AABB test widened by the tolerance. [any thread]
bool overlapsAabbAabb(const Aabb& a, const Aabb& b) noexcept;

/// The corners of a triangle (m), in the frame the caller works in.
using TriangleCorners = std::array<Vec3, 3>;
/// The tightest AABB of a triangle (m). [any thread]
Aabb triangleAabb(const TriangleCorners& t) noexcept;
/// Exact triangle/box separating-axis test (Akenine-Moeller 2001, "Fast 3D triangle-box
/// overlap testing"): the box's three face normals, the triangle's normal and the nine cross
/// products of box axes and triangle edges. Each axis L separates only by more than
/// `toleranceM` * |L|, so a nearly null cross product (an edge almost parallel to a box axis)
/// never separates by rounding, and a degenerate triangle is tested by its remaining axes.
/// Conservative like the box tests: overlapToleranceFor(aabbScale(triangleAabb(t)),
/// aabbScale(box)) is the tolerance of the overload without one. [any thread]
bool overlapsTriangleAabb(const TriangleCorners& t, const Aabb& box, double toleranceM) noexcept;
/// The same, with the scaled tolerance of every overlap test here. [any thread]
bool overlapsTriangleAabb(const TriangleCorners& t, const Aabb& box) noexcept;

} // namespace hapto
