#pragma once
/// A triangle mesh in its own frame: the geometry of a `Shape::Mesh` scene object.
///
/// Design note. A mesh's vertices are stored once, in the object's own frame with the scene
/// file's uniform scale already applied (m), and shared (immutable, by shared_ptr) by every
/// scene copy and snapshot that places the object. Moving a mesh changes only its object's
/// pose: nothing here is copied or transformed. World-frame vertices are computed where they
/// are needed (index builds, the renderer's few nearby triangles) from the object's pose.

#include "hapto/core/Geometry.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace hapto {

/// One triangle: three vertex indices, counter-clockwise seen from outside (the outward normal
/// is (v1 - v0) x (v2 - v0)).
using TriangleIndices = std::array<std::uint32_t, 3>;

/// Where a mesh came from, for messages and for writing the scene back.
struct MeshSource {
    std::string file;   ///< The model file as the scene names it (relative to the scene file);
                        ///< empty for inline vertices and triangles, or a generated mesh.
    double scale = 1.0; ///< The uniform scale applied to the file's or inline coordinates.
};

/// Immutable triangles in a local frame (m). Built once on a control thread, then read from
/// any thread.
class TriangleMesh {
public:
    /// The most triangles one mesh may have: 2^24 (16.7 million), above the 10^7 the
    /// experiments use. A bigger model is refused as bad input.
    static constexpr std::uint32_t kMaxTriangles = 1u << 24;
    /// The most vertices one mesh may have (three per triangle).
    static constexpr std::uint32_t kMaxVertices = 3 * kMaxTriangles;

    /// Builds a mesh from local vertices (m, scale applied) and triangles. Drops degenerate
    /// triangles (a repeated vertex, or an area below 1e-24 m^2 relative to the squared longest
    /// edge) and counts them. Throws InputError, naming `where` and the element (e.g.
    /// "triangles[12][2]: vertex index 40 is out of range (the mesh has 12 vertices)") for a
    /// non-finite vertex, an index out of range, too many vertices or triangles, or no
    /// triangle left. [control]
    static std::shared_ptr<const TriangleMesh> make(std::vector<Vec3> vertices,
                                                    std::vector<TriangleIndices> triangles,
                                                    MeshSource source, const std::string& where);

    /// The vertices, local frame (m). [any thread]
    std::span<const Vec3> vertices() const noexcept { return mVertices; }
    /// The triangles kept (degenerate ones dropped). [any thread]
    std::span<const TriangleIndices> triangles() const noexcept { return mTriangles; }
    /// Number of triangles kept. [any thread]
    std::uint32_t triangleCount() const noexcept {
        return static_cast<std::uint32_t>(mTriangles.size());
    }
    /// The corners of triangle t, local frame (m). [any thread]
    std::array<Vec3, 3> corners(std::uint32_t t) const noexcept {
        const TriangleIndices& i = mTriangles[t];
        return {mVertices[i[0]], mVertices[i[1]], mVertices[i[2]]};
    }
    /// Degenerate triangles dropped when the mesh was made. [any thread]
    std::uint64_t droppedDegenerate() const noexcept { return mDropped; }
    /// The tightest local AABB of the vertices used by triangles (m). [any thread]
    const Aabb& localBounds() const noexcept { return mBounds; }
    /// The largest distance from the local origin to a vertex (m): the radius of the bounding
    /// sphere about the object's centre. [any thread]
    double boundingRadius() const noexcept { return mRadius; }
    /// True when every edge is shared by exactly two triangles (a closed, two-sided surface
    /// whose inside is well defined). [any thread]
    bool closed() const noexcept { return mClosed; }
    /// Where it came from. [any thread]
    const MeshSource& source() const noexcept { return mSource; }

private:
    TriangleMesh() = default;

    std::vector<Vec3> mVertices;
    std::vector<TriangleIndices> mTriangles;
    MeshSource mSource;
    Aabb mBounds = Aabb::empty();
    double mRadius = 0.0;
    std::uint64_t mDropped = 0;
    bool mClosed = false;
};

} // namespace hapto
