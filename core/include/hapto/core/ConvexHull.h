#pragma once
/// A convex polyhedron given by its vertices, face planes and edges, in its own frame (m): what
/// a dynamic mesh collides as (its convex hull) and what an open mesh's mass is computed from.

#include "hapto/core/Geometry.h"

#include <array>
#include <cstdint>
#include <vector>

namespace hapto {

/// A convex polyhedron. Invariants (convexHullOf in scenes/ConvexHullOf.h makes them hold):
/// every vertex v satisfies dot(face.normal, v) <= face.offset + a rounding tolerance for every
/// face; each face normal is a unit vector pointing out; each edge joins two vertices and is
/// listed once.
struct ConvexHull {
    /// A face's plane: {x : dot(normal, x) = offset}, the solid on the side dot(normal, x) <=
    /// offset.
    struct Face {
        Vec3 normal{0.0};    ///< Outward unit normal.
        double offset = 0.0; ///< (m).

        /// Both fields equal (ConvexHull's operator== needs it).
        bool operator==(const Face&) const = default;
    };
    std::vector<Vec3> vertices;                      ///< Corners (m, own frame).
    std::vector<Face> faces;                         ///< Face planes.
    std::vector<std::array<std::uint32_t, 2>> edges; ///< Vertex index pairs, each edge once.

    /// Every field equal.
    bool operator==(const ConvexHull&) const = default;
};

} // namespace hapto
