#pragma once
/// Swept tests of a straight path against a box, a sphere and a one-sided triangle, each grown
/// by a skin: where the path enters the skin (SI units, m; fractions of the path).
///
/// The renderer's proxy moves along straight paths and must stop on the first skin it meets
/// (runtime/src/GodObjectRenderer*.cpp). Each test answers two fractions: `t`, where the path
/// enters the skin shrunk by `shrinkM` (the test proper: a path resting on the skin itself is
/// not entering it), and `tStop` <= t, where it reaches the skin (where the proxy stops). A path
/// that starts inside the shrunk skin passes (it leaves, it does not enter). No allocation, no
/// exception.

#include "hapto/core/ClosestPoint.h"
#include "hapto/core/Geometry.h"

#include <algorithm>
#include <limits>

namespace hapto {

/// Where a path first enters a shape's skin, as fractions of the path.
struct SweptEntry {
    bool found = false;                                 ///< The path enters the shrunk skin.
    double t = std::numeric_limits<double>::infinity(); ///< Entry into the shrunk skin, [0, 1).
    double tStop = 0;                                   ///< Arrival at the skin, in [0, t].
    int axis = -1;   ///< Box: the entered face's axis; -1 for a sphere or a triangle.
    double sign = 0; ///< Box: the entered face's side (+1 or -1 along the axis).
};

/// The slab test of a box grown by `skinM` (half extents `halfExtents`), in the box's own
/// frame: the path from `from` along `delta` (both box frame). [servo]
SweptEntry sweepBoxLocal(const Vec3& halfExtents, const Vec3& from, const Vec3& delta, double skinM,
                         double shrinkM) noexcept;
/// The swept test of a sphere grown by `skinM`: the smaller root of the quadratic, in a
/// stable form. [servo]
SweptEntry sweepSphere(const Vec3& center, double radius, const Vec3& from, const Vec3& to,
                       double skinM, double shrinkM) noexcept;

/// The swept test of a triangle entered only from its front (the side its unit normal points
/// to), plane {x : dot(normal, x) = offset}. The path is stopped where it would enter the skin
/// slab (the plane `skinM` in front, shrunk by `shrinkM`) at a point over the triangle grown by
/// `skinM` across its edges (so the skins of the triangles around a convex edge meet like a
/// box's, and a flat mesh's skin is the box face's), or wherever it really crosses the triangle
/// grown by `crossMarginM` (so no path reaches behind a closed mesh, whatever its dihedral
/// angles). A path that starts behind the plane, or does not go deeper, passes.
///
/// The plane comes first (two dot products reject most triangles); `geometry()` (a
/// TriangleGeometry, or anything with `corners` and `edges`) is called only for a path that
/// reaches the skin slab before `beforeT`, so a caller may fetch the corners lazily, and a
/// caller that has already found an entry at t = beforeT on this path (an entry is kept only
/// when it comes strictly earlier) spares the edge tests of every later one. [servo]
template <class GeometryFn>
SweptEntry sweepTriangleFront(const Vec3& normal, double offset, GeometryFn&& geometry,
                              const Vec3& from, const Vec3& to, double skinM, double shrinkM,
                              double crossMarginM, double beforeT = 1.0) noexcept {
    if (normal == Vec3(0.0)) {
        return {};
    }
    const double sf = glm::dot(normal, from) - offset; // heights over the plane (m)
    const double st = glm::dot(normal, to) - offset;
    if (!(sf >= 0.0) || !(st < sf)) {
        return {}; // behind (one-sided), or not going deeper
    }
    const double h = skinM - shrinkM;
    double t = 0.0;
    if (sf > h) {
        if (st >= h) {
            return {};
        }
        t = (sf - h) / (sf - st);
    }
    if (t >= std::min(beforeT, 1.0)) {
        return {};
    }
    const Vec3 d = to - from;
    const auto& g = geometry();
    bool over = overGrownTriangle(from + t * d, g.corners, normal, g.edges, skinM);
    if (!over && st < 0.0) {
        over = overGrownTriangle(from + (sf / (sf - st)) * d, g.corners, normal, g.edges,
                                 crossMarginM);
    }
    if (!over) {
        return {};
    }
    SweptEntry e;
    e.found = true;
    e.t = t;
    e.tStop = sf > skinM ? std::clamp((sf - skinM) / (sf - st), 0.0, t) : 0.0;
    return e;
}

} // namespace hapto
