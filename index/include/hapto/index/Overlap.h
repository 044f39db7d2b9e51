#pragma once
/// Conservative overlap tests between index items' bounds (boxes, spheres, triangles) and cells,
/// over the separating-axis tests of hapto/core/ShapeGeometry.h.
///
/// Every test here may say "overlap" for a pair that is separated by a hair (a tolerance scaled
/// to the sizes and positions involved), and never says "separated" for a pair that overlaps:
/// a missed overlap is a hole the pointer falls through, a spurious one costs one more candidate.
/// Touching counts as overlap.

#include "hapto/core/Geometry.h"
#include "hapto/core/ShapeGeometry.h"
#include "hapto/scenes/Scene.h"
#include "hapto/scenes/SceneObject.h"

#include <cstdint>

namespace hapto {

/// Which bounds place objects into cells: the tight oriented box, or the world AABB.
enum class OverlapMode : std::uint8_t { Obb, Aabb };

/// An index item's bounds (a box, a sphere or a mesh triangle), prepared once for many cell
/// tests.
struct OverlapShape {
    /// What the bounds are.
    enum class Kind : std::uint8_t { Box, Sphere, Triangle };

    union {
        Obb obb{};                ///< Box: its oriented box; sphere: its axis-aligned cube.
        TriangleCorners triangle; ///< Triangle: its world corners (m).
    };
    Aabb aabb;             ///< The tightest world AABB (m).
    double radius = 0.0;   ///< Sphere radius (m); 0 otherwise.
    double scale = 0.0;    ///< Box, sphere: largest |centre| coordinate plus largest half
                           ///< extent; triangle: aabbScale of its AABB (m).
    Kind kind = Kind::Box; ///< Which member of the union holds the bounds.
    /// Box: its axes are signed unit axes exactly (no rotation, or a quarter turn whose matrix
    /// came out exact), so its AABB is the box itself and the AABB test is its whole test.
    bool axisAligned = false;

    /// Prepares a box's or sphere's bounds (not a mesh's: its triangles are the items).
    /// [any thread]
    static OverlapShape of(const SceneObject& object);
    /// The same from the object's render copy (Scene::body), without turning its rotation into
    /// a matrix again. [any thread]
    static OverlapShape of(const RenderBody& body) noexcept;
    /// Prepares a triangle's bounds from its world corners (m). [any thread]
    static OverlapShape ofTriangle(const TriangleCorners& corners) noexcept;
    /// Prepares an index item's bounds (Scene.h: an object slot or a triangle item); the item
    /// must be indexed (scene.isIndexed). [any thread]
    static OverlapShape of(const Scene& scene, std::uint32_t item);
};
static_assert(sizeof(OverlapShape) == 192, "per-item build memory; update estimateIndexBytes");

/// An index item's tightest world AABB (m): a triangle item's corners' box, an object slot's
/// SceneObject::aabb(). What a consumer of candidates tests first. [any thread]
Aabb itemAabb(const Scene& scene, std::uint32_t item) noexcept;
/// An item's tightest world AABB (m) and its tolerance scale: OverlapShape's `aabb` and
/// `scale`, bit for bit, without preparing the rest of its shape.
struct OverlapBounds {
    Aabb aabb;          ///< The tightest world AABB (m).
    double scale = 0.0; ///< The tolerance scale (m), as OverlapShape::scale.
};
/// An index item's OverlapBounds (the item must be indexed). [any thread]
OverlapBounds overlapBounds(const Scene& scene, std::uint32_t item) noexcept;
/// An index item's centre (m): a triangle's centroid, an object's centre. [any thread]
Vec3 itemCenter(const Scene& scene, std::uint32_t item) noexcept;

/// A cell prepared once for many object tests.
struct OverlapCell {
    Aabb box;           ///< The closed cell (m).
    double scale = 0.0; ///< Largest |centre| coordinate plus largest edge (m).

    /// Prepares a cell. [any thread]
    static OverlapCell of(const Aabb& box) noexcept;
};

// The separating-axis tests themselves (overlapsObbObb, overlapsObbAabb, overlapsSphereAabb,
// overlapsAabbAabb) and their tolerances live in hapto/core/ShapeGeometry.h.

/// Whether an item's bounds overlap a cell. Aabb mode: its world AABB. Obb mode: its AABB
/// and then its OBB (boxes), exact sphere (spheres) or exact triangle (the 13-axis test of
/// overlapsTriangleAabb), so Obb mode never places an item in a cell that Aabb mode leaves
/// out. An axis-aligned box stops at its AABB test in both modes: the 15-axis test of such a
/// box repeats the face tests with a tolerance no smaller (its R is a signed permutation and
/// the edge axes are face axes again), so it could only reject a pair the AABB test kept by
/// less than a rounding error, and biased to overlap, we keep it. [any thread]
bool overlaps(const OverlapShape& shape, const Aabb& cell, OverlapMode mode) noexcept;
/// The same, for a prepared cell. [any thread]
bool overlaps(const OverlapShape& shape, const OverlapCell& cell, OverlapMode mode) noexcept;
/// The first test of overlaps(): an AABB with its shape's scale (OverlapShape::scale) against
/// a prepared cell, with their tolerance; the whole test of an axis-aligned box, or of any
/// item in Aabb mode. [any thread]
bool overlapsAabb(const Aabb& aabb, double scale, const OverlapCell& cell) noexcept;
/// The tolerance (m) overlaps() allows between these bounds and a cell. [any thread]
double overlapTolerance(const OverlapShape& shape, const OverlapCell& cell) noexcept;

} // namespace hapto
