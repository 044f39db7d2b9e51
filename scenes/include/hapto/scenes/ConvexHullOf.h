#pragma once
/// The convex hull of a point set (qhull), as a ConvexHull and as a closed triangle surface.

#include "hapto/core/ConvexHull.h"
#include "hapto/scenes/TriangleMesh.h"

#include <span>
#include <vector>

namespace hapto {

/// A convex hull and its surface: each face cut into a fan of triangles, counter-clockwise seen
/// from outside, indices into `hull.vertices` (what volume integrals and drawing need).
struct ConvexHullSurface {
    ConvexHull hull;                        ///< Vertices, merged face planes, unique edges.
    std::vector<TriangleIndices> triangles; ///< The faces as outward triangles.
};

/// The convex hull of `points` (m, any frame; at least 4 not in one plane). Coplanar facets are
/// merged (qhull's default C-0 premerge), so a cube has 6 faces and 12 edges; the vertices are
/// input points, bit for bit. Throws std::invalid_argument when the points span no volume
/// (fewer than 4, or all in one plane or line), or when a point is not finite. [control]
ConvexHullSurface convexHullOf(std::span<const Vec3> points);

} // namespace hapto
