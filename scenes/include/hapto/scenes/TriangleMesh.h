#pragma once
/// A triangle mesh in its own frame: the geometry of a `Shape::Mesh` scene object.
///
/// Design note. A mesh's vertices are stored once, in the object's own frame with the scene
/// file's uniform scale already applied (m), and shared (immutable, by shared_ptr) by every
/// scene copy and snapshot that places the object. Moving a mesh changes only its object's
/// pose: nothing here is copied or transformed. World-frame vertices are computed where they
/// are needed (index builds, the renderer's few nearby triangles) from the object's pose
/// (Scene's render copy keeps it as a matrix). Each triangle's plane is kept beside it, in the
/// local frame (TriangleFace, 32 B), so the renderer rejects a triangle with two dot products.

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

/// A triangle's plane in its mesh's frame: {x : dot(normal, x) = offset}, the unit normal
/// pointing out (the side its corners turn counter-clockwise). Computed once with the mesh, so
/// the servo path never takes a cross product and a square root to learn it.
struct TriangleFace {
    Vec3 normal{0.0};    ///< Outward unit normal (local frame); zero for a triangle too thin to
                         ///< have one (such a triangle is never touched).
    double offset = 0.0; ///< dot(normal, corner 0) (m, local frame).
};

/// One node of a mesh's local BVH (32 bytes): float bounds rounded outwards, and either two
/// children (the left one is the next node, depth first) or a run of triangles.
struct MeshBvhNode {
    std::array<float, 3> min{}; ///< Lower corner, local frame (m), rounded down.
    std::array<float, 3> max{}; ///< Upper corner, local frame (m), rounded up.
    std::uint32_t first = 0;    ///< Leaf: first position in the triangle order; inner: the
                                ///< right child's node index.
    std::uint32_t count = 0;    ///< Leaf: its triangles (>= 1); inner: 0.
};
static_assert(sizeof(MeshBvhNode) == 32, "BVH nodes are 32 bytes; update the design note");

/// Immutable triangles in a local frame (m). Built once on a control thread, then read from
/// any thread.
class TriangleMesh {
public:
    /// The most triangles in a leaf of the local BVH.
    static constexpr std::uint32_t kBvhLeafTriangles = 4;
    /// The deepest the local BVH can be (root 0): log2(kMaxTriangles / leaf) + 1 = 23, with room.
    static constexpr int kBvhMaxDepth = 32;

    /// The most triangles one mesh may have: 2^24 (16.7 million), above the 10^7 the
    /// experiments use. A bigger model is refused as bad input.
    static constexpr std::uint32_t kMaxTriangles = 1u << 24;
    /// The most vertices one mesh may have (three per triangle).
    static constexpr std::uint32_t kMaxVertices = 3 * kMaxTriangles;
    /// The farthest a vertex may lie from its mesh's origin on any axis (m, scale applied):
    /// 1e9. The degeneracy test takes a triangle's size to the 4th power, which overflows near
    /// 1e77 m (and the local BVH keeps float bounds, which end at 3.4e38); 1e9 m keeps every
    /// such product exact in range and is far beyond any haptic scene.
    static constexpr double kMaxCoordinate = 1e9;
    /// The smallest a mesh may be across (m, scale applied: the largest side of its vertices'
    /// box, when they are not all one point): 1e-9. Below about 1e-75 m a triangle's area
    /// underflows and every triangle would read as degenerate; a nanometre is far below what
    /// any haptic device resolves.
    static constexpr double kMinSize = 1e-9;

    /// Builds a mesh from local vertices (m, scale applied) and triangles. Drops degenerate
    /// triangles (a repeated vertex, or an area below 1e-24 m^2 relative to the squared longest
    /// edge) and counts them; drops and counts duplicates too (a triangle whose three corners
    /// are at the positions of an earlier one's, in any order: the first is kept). Throws
    /// InputError, naming `where` and the element (e.g. "triangles[12][2]: vertex index 40 is
    /// out of range (the mesh has 12 vertices)") for a non-finite vertex, one beyond
    /// kMaxCoordinate, vertices spanning less than kMinSize, an index out of range, too many
    /// vertices or triangles, or no triangle left. [control]
    static std::shared_ptr<const TriangleMesh> make(std::vector<Vec3> vertices,
                                                    std::vector<TriangleIndices> triangles,
                                                    MeshSource source, const std::string& where);

    /// The vertices, local frame (m). [any thread]
    std::span<const Vec3> vertices() const noexcept { return mVertices; }
    /// The triangles kept (degenerate and duplicate ones dropped). [any thread]
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
    /// The plane of triangle t, local frame. [any thread]
    const TriangleFace& face(std::uint32_t t) const noexcept { return mFaces[t]; }
    /// Memory of the precomputed planes (bytes): 32 per triangle. [any thread]
    std::size_t faceBytes() const noexcept { return mFaces.size() * sizeof(TriangleFace); }
    /// Degenerate triangles dropped when the mesh was made. [any thread]
    std::uint64_t droppedDegenerate() const noexcept { return mDropped; }
    /// Duplicate triangles dropped when the mesh was made (the same three corner positions as
    /// a triangle kept, in any order). [any thread]
    std::uint64_t droppedDuplicate() const noexcept { return mDuplicates; }
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

    /// Calls fn(t) for every triangle t whose local AABB overlaps the closed local box
    /// `localBox` (m): exactly the triangles a linear scan with that test finds, in BVH order
    /// (each once). Allocation-free and non-throwing (fn must not throw either). [servo]
    template <class Fn> void forEachTriangleNear(const Aabb& localBox, Fn&& fn) const noexcept;
    /// The same for the box around a local sphere (centre, radius in m). [servo]
    template <class Fn>
    void forEachTriangleNear(const Vec3& localCenter, double radius, Fn&& fn) const noexcept {
        forEachTriangleNear(Aabb{localCenter - Vec3(radius), localCenter + Vec3(radius)},
                            static_cast<Fn&&>(fn));
    }
    /// The BVH's nodes, depth first; node 0 is the root. [any thread]
    std::span<const MeshBvhNode> bvhNodes() const noexcept { return mBvhNodes; }
    /// The BVH's depth (a root-only tree has 0). [any thread]
    int bvhDepth() const noexcept { return mBvhDepth; }
    /// Memory of the local BVH (bytes): nodes and triangle order. [any thread]
    std::size_t bvhBytes() const noexcept {
        return mBvhNodes.size() * sizeof(MeshBvhNode) + mBvhOrder.size() * sizeof(std::uint32_t);
    }

private:
    void buildBvh();
    TriangleMesh() = default;

    std::vector<Vec3> mVertices;
    std::vector<TriangleIndices> mTriangles;
    std::vector<TriangleFace> mFaces; // by triangle
    MeshSource mSource;
    Aabb mBounds = Aabb::empty();
    double mRadius = 0.0;
    std::uint64_t mDropped = 0;
    std::uint64_t mDuplicates = 0;
    bool mClosed = false;
    std::vector<MeshBvhNode> mBvhNodes;   // depth first
    std::vector<std::uint32_t> mBvhOrder; // triangle numbers, each leaf one run
    int mBvhDepth = 0;
};

template <class Fn> void TriangleMesh::forEachTriangleNear(const Aabb& q, Fn&& fn) const noexcept {
    if (mBvhNodes.empty() || q.isEmpty()) {
        return;
    }
    std::uint32_t stack[kBvhMaxDepth + 1];
    int top = 0;
    std::uint32_t node = 0;
    for (;;) {
        const MeshBvhNode& n = mBvhNodes[node];
        const bool hit = n.min[0] <= q.max.x && n.max[0] >= q.min.x && n.min[1] <= q.max.y &&
                         n.max[1] >= q.min.y && n.min[2] <= q.max.z && n.max[2] >= q.min.z;
        if (hit && n.count == 0) {
            stack[top++] = n.first; // the right child, after the left one (the next node)
            ++node;
            continue;
        }
        if (hit) {
            for (std::uint32_t k = n.first; k < n.first + n.count; ++k) {
                const std::uint32_t t = mBvhOrder[k];
                const TriangleIndices& i = mTriangles[t];
                const Vec3& a = mVertices[i[0]];
                const Vec3& b = mVertices[i[1]];
                const Vec3& c = mVertices[i[2]];
                const Vec3 lo = glm::min(glm::min(a, b), c), hi = glm::max(glm::max(a, b), c);
                if (lo.x <= q.max.x && hi.x >= q.min.x && lo.y <= q.max.y && hi.y >= q.min.y &&
                    lo.z <= q.max.z && hi.z >= q.min.z) {
                    fn(t);
                }
            }
        }
        if (top == 0) {
            return;
        }
        node = stack[--top];
    }
}

} // namespace hapto
