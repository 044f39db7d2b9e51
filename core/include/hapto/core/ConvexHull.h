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
///
/// Design note. Besides the planes and edges, a hull keeps the topology the narrow phase needs
/// on every call (deriveTopology(), once, when the hull is made): each face's corners in
/// angular order about its normal, each edge's two faces (Gregorius's Gauss-map test) and its
/// size. A vertex is on a face when within kOnFaceTolerance * radiusM of its plane. Deriving
/// costs O(F V + E F), once; collide() then reads them instead of recomputing them per call.
/// collide() needs a hull whose topology is derived (hasTopology()).
struct ConvexHull {
    /// A vertex this close to a face's plane, relative to radiusM, lies on that face.
    static constexpr double kOnFaceTolerance = 1e-6;
    /// In edgeFaces: the edge does not lie on exactly two faces.
    static constexpr std::uint32_t kNoFace = 0xFFFFFFFFu;

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

    // Derived by deriveTopology() from the three above.
    /// Every face's corners (vertex indices), face f's at [faceCornerBegin[f],
    /// faceCornerBegin[f + 1]), in angular order about the face's normal through their mean.
    std::vector<std::uint32_t> faceCorners;
    std::vector<std::uint32_t> faceCornerBegin; ///< faces.size() + 1 offsets into faceCorners.
    /// Each edge's first two faces (face indices, in face order), or {kNoFace, kNoFace} when
    /// it lies on fewer.
    std::vector<std::array<std::uint32_t, 2>> edgeFaces;
    double radiusM = 0.0; ///< The largest distance of a vertex from the origin (m).

    /// Derives faceCorners, faceCornerBegin, edgeFaces and radiusM from vertices, faces and
    /// edges. Deterministic (index order throughout). [control]
    void deriveTopology();
    /// True when deriveTopology() ran for the current faces and edges. [any thread]
    bool hasTopology() const noexcept {
        return faceCornerBegin.size() == faces.size() + 1 && edgeFaces.size() == edges.size();
    }

    /// Every field equal.
    bool operator==(const ConvexHull&) const = default;
};

} // namespace hapto
