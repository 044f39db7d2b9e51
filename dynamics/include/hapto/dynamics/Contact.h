#pragma once
/// The narrow phase of the dynamics: the contact points between a body's convex shape (box,
/// sphere or convex hull) and another convex shape (box, sphere, hull or one triangle of a
/// static mesh), exactly, from the shapes' own geometry (no bounding-box stand-ins).
///
/// Conventions (SI units, m): every ContactPoint is in world coordinates; `normal` is a unit
/// vector pointing from `b` towards `a` (the direction that separates a from b);
/// `separation` is the signed distance between the two surfaces along the normal at that point
/// (< 0: they overlap by that much). Points are reported while separation <= the margin given,
/// so a solver can stop an approaching body before it reaches a surface (speculative contacts).
/// Depths are exact; so are the gaps of sphere pairs and of faces facing each other; the gap
/// of two polytopes apart corner to edge or corner to corner is a lower bound (the best
/// separating axis's), so such a point may come early, never late. Cost: constant for sphere
/// pairs, box-box and box-triangle; a hull costs O(its vertices) per axis tested and every
/// pair of edge directions is an axis, so hull-hull grows as edges(a) x edges(b) x vertices.
/// Every function here is noexcept, allocates nothing and is deterministic (the same inputs in
/// the same order give the same points in the same order, bit for bit). [any thread]

#include "hapto/core/ConvexHull.h"
#include "hapto/core/Geometry.h"
#include "hapto/core/ShapeGeometry.h"

#include <array>
#include <cstdint>

namespace hapto {

/// A convex shape placed in the world, as the narrow phase sees it. Plain value; the hull, if
/// any, is borrowed.
struct ConvexShape {
    /// What it is.
    enum class Kind : std::uint8_t { Box, Sphere, Hull, Triangle };
    Kind kind = Kind::Box;            ///< Which of the fields below describe it.
    Vec3 center{0.0};                 ///< Box, sphere: centre; hull: its frame's origin (m, world).
    Mat3 axes{1.0};                   ///< Box, hull: own axes (column i = axis i, world).
    Vec3 halfExtents{0.0};            ///< Box: half size per own axis (m).
    double radius = 0.0;              ///< Sphere: radius (m).
    const ConvexHull* hull = nullptr; ///< Hull: vertices and planes in its own frame.
    TriangleCorners triangle{};       ///< Triangle: corners (m, world).
    /// Triangle: its outward unit normal when it belongs to a closed mesh (contacts then push
    /// only out of that side, so nothing is pulled through a thin wall); zero for a two-sided
    /// triangle of an open mesh.
    Vec3 triangleNormal{0.0};

    /// A box. [any thread]
    static ConvexShape box(const Vec3& center, const Mat3& axes, const Vec3& halfExtents) noexcept;
    /// A sphere. [any thread]
    static ConvexShape sphere(const Vec3& center, double radius) noexcept;
    /// A hull placed at `origin` with `axes`. [any thread]
    static ConvexShape hullAt(const ConvexHull& hull, const Vec3& origin,
                              const Mat3& axes) noexcept;
    /// A triangle; `outwardNormal` zero for a two-sided one. [any thread]
    static ConvexShape triangleOf(const TriangleCorners& corners,
                                  const Vec3& outwardNormal) noexcept;
    /// The tightest world AABB (m). [any thread]
    Aabb aabb() const noexcept;
};

/// One contact point (world frame).
struct ContactPoint {
    Vec3 position{0.0};         ///< Where the surfaces meet: midway between them (m).
    Vec3 normal{0.0, 1.0, 0.0}; ///< Unit, from b towards a.
    double separation = 0.0;    ///< Signed gap along the normal (m); < 0: penetration depth.
    /// Which feature pair made it (stable while the pair keeps touching the same way: a solver
    /// may key its warm start on it). 0 when the test has no such notion.
    std::uint32_t feature = 0;
};

/// Up to kMax contact points between two shapes.
struct ContactManifold {
    static constexpr int kMax = 8; ///< A box face on a box face needs at most 8 clipped points.
    std::array<ContactPoint, kMax> points{}; ///< The first `count` are set.
    int count = 0;                           ///< How many points.
};

/// The contact points between `a` (Box, Sphere or Hull) and `b` (any kind) whose separation is
/// at most `marginM` (>= 0), written to `out` (its count reset first). Pairs: sphere-sphere,
/// sphere-box, sphere-hull, sphere-triangle, box-box and box-hull by separating axes with face
/// clipping, box-triangle and hull-triangle likewise, hull-hull. A manifold of more than kMax
/// points keeps the kMax that span it best (deepest first). [any thread]
void collide(const ConvexShape& a, const ConvexShape& b, double marginM,
             ContactManifold& out) noexcept;

} // namespace hapto
