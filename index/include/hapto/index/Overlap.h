#pragma once
/// Conservative overlap tests between object bounds and index cells, over the separating-axis
/// tests of hapto/core/ShapeGeometry.h.
///
/// Every test here may say "overlap" for a pair that is separated by a hair (a tolerance scaled
/// to the sizes and positions involved), and never says "separated" for a pair that overlaps:
/// a missed overlap is a hole the pointer falls through, a spurious one costs one more candidate.
/// Touching counts as overlap.

#include "hapto/core/Geometry.h"
#include "hapto/core/ShapeGeometry.h"
#include "hapto/scenes/SceneObject.h"

#include <cstdint>

namespace hapto {

/// Which bounds place objects into cells: the tight oriented box, or the world AABB.
enum class OverlapMode : std::uint8_t { Obb, Aabb };

/// An object's bounds, prepared once for many cell tests.
struct OverlapShape {
    Obb obb;             ///< A box's oriented box; a sphere's axis-aligned cube.
    Aabb aabb;           ///< The tightest world AABB (m).
    double radius = 0.0; ///< Sphere radius (m); 0 for a box.
    double scale = 0.0;  ///< Largest |centre| coordinate plus largest half extent (m).
    bool sphere = false; ///< True for a sphere (exact sphere/box test in Obb mode).

    /// Prepares an object's bounds. [any thread]
    static OverlapShape of(const SceneObject& object);
};

/// A cell prepared once for many object tests.
struct OverlapCell {
    Aabb box;           ///< The closed cell (m).
    double scale = 0.0; ///< Largest |centre| coordinate plus largest edge (m).

    /// Prepares a cell. [any thread]
    static OverlapCell of(const Aabb& box) noexcept;
};

// The separating-axis tests themselves (overlapsObbObb, overlapsObbAabb, overlapsSphereAabb,
// overlapsAabbAabb) and their tolerances live in hapto/core/ShapeGeometry.h.

/// Whether an object's bounds overlap a cell. Aabb mode: its world AABB. Obb mode: its AABB
/// and then its OBB (boxes) or exact sphere (spheres), so Obb mode never places an object in
/// a cell that Aabb mode leaves out. [any thread]
bool overlaps(const OverlapShape& shape, const Aabb& cell, OverlapMode mode) noexcept;
/// The same, for a prepared cell. [any thread]
bool overlaps(const OverlapShape& shape, const OverlapCell& cell, OverlapMode mode) noexcept;
/// The tolerance (m) overlaps() allows between these bounds and a cell. [any thread]
double overlapTolerance(const OverlapShape& shape, const OverlapCell& cell) noexcept;

} // namespace hapto
