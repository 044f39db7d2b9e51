#pragma once
/// What the god-object renderer's parts share (private to runtime/src): the skin and tolerance
/// constants, the item helpers, and the near-list walks every part loops over.
///
/// The renderer is four files, one job each: GodObjectRenderer.cpp (the tick: the proxy's
/// start, the contacts, the force, the faults; the design note of the whole), GodObjectNearList.cpp
/// (the candidate gathering: the near list and the mesh walk), GodObjectSolver.cpp (the proxy
/// solve: plane solve, swept test, edge and corner rules) and GodObjectFriction.cpp (the friction
/// cone and the second solve). The shape geometry they use is core's (ClosestPoint.h,
/// SweptShapes.h, ShapeGeometry.h).

#include "hapto/core/ClosestPoint.h"
#include "hapto/core/ShapeGeometry.h"
#include "hapto/runtime/GodObjectRenderer.h"

#include <cstdint>
#include <limits>

namespace hapto::godobject {

constexpr double kSkinM = GodObjectRenderer::kSkinM;
constexpr double kShrinkM = 1e-9;     ///< Swept tests use surfaces this far inside the skin (m).
constexpr double kOnM = 2e-9;         ///< "On a plane / touching an object" tolerance (m).
constexpr double kProbeM = 4e-9;      ///< Covered-face probe step (m), > kShrinkM.
constexpr double kFeasibleM = 1e-12;  ///< Half-space feasibility slack (m).
constexpr double kNearMarginM = 1e-3; ///< Extra radius of the near ball for objects (m).
constexpr double kTriangleNearMarginM = 1e-6; ///< Extra radius of the near ball for triangles (m).
constexpr double kFrictionCover = 1.0; ///< Near ball also covers a friction lag up to mu_d = 1.
constexpr double kInf = std::numeric_limits<double>::infinity();
/// Render copies a near list asks the cache for ahead of reading them (prefetchBodies).
constexpr std::uint32_t kPrefetchBodies = 64;

inline double length2(const Vec3& v) {
    return glm::dot(v, v);
}

/// True when p is inside the object's shrunk skin (strictly). An axis-aligned box's frame is
/// p - centre (RenderBody::toLocal), which is what the rotation by the identity gives.
inline bool insideSkin(const RenderBody& o, const Vec3& p) {
    return o.shape == Shape::Sphere
               ? sphereStrictlyContains(o.center, o.halfExtents.x + kSkinM - kShrinkM, p)
               : boxStrictlyContainsLocal(o.halfExtents, o.toLocal(p), kSkinM - kShrinkM);
}

/// A triangle's corners and edges (m, world) from its corners, for one not in the near list's
/// copy.
inline TriangleGeometry fetchTriangle(const std::array<Vec3, 3>& v, const Vec3& normal) {
    return {v, triangleEdges(v, normal)};
}

/// A valid item of this scene: a box or sphere slot, or a triangle item.
inline bool validItem(const Scene& scene, std::uint32_t item) {
    if (isTriangleItem(item)) {
        return (item & ~kTriangleItemBit) < scene.triangleCount();
    }
    return item < scene.size() && scene.object(item).shape != Shape::Mesh;
}

/// The item of a mesh object's first triangle (GodObjectNearList.cpp).
std::uint32_t firstTriangleItem(const Scene& scene, std::uint32_t slot) noexcept;

} // namespace hapto::godobject

namespace hapto {

/// Defined here, not with the other poses in GodObjectNearList.cpp, so that every pass's loop
/// over the near list inlines it.
inline const RenderBody& GodObjectRenderer::bodyAt(const Scene& scene,
                                                   std::uint32_t slot) const noexcept {
    if (mDynamic != nullptr && mDynamic->count > 0) {
        if (const DynamicBodySet::Entry* e = mDynamic->find(slot)) {
            return e->render;
        }
    }
    return scene.body(slot);
}

/// The mesh walk: visits (calls fn(item) for) every triangle of the mesh in `slot` within
/// `radius` + the skin of `center` (m, world), in the mesh's own frame through its local BVH
/// (TriangleMesh::forEachTriangleNear): one point transformed, no triangle copied, no
/// allocation.
template <class Fn>
void GodObjectRenderer::forEachMeshTriangleNear(const Scene& scene, std::uint32_t slot,
                                                const Vec3& center, double radius,
                                                Fn&& fn) const noexcept {
    const SceneObject& o = scene.object(slot);
    if (!o.mesh) {
        return;
    }
    // In the mesh's own frame: distances are the same there, and nothing is transformed but
    // the one point.
    const Vec3 local = bodyAt(scene, slot).toLocal(center);
    const double reach = radius + godobject::kSkinM;
    const std::uint32_t first = godobject::firstTriangleItem(scene, slot);
    const TriangleMesh& mesh = *o.mesh;
    mesh.forEachTriangleNear(Aabb{local - Vec3(reach), local + Vec3(reach)}, [&](std::uint32_t t) {
        if (triangleDistance2(local, mesh.corners(t)) <= reach * reach) {
            fn(first + t);
        }
    });
}

/// Calls fn(item, near) for every item of the near list (`near`: its place in mTriangleData,
/// or kNotCached); when the list overflowed, for every item of the candidate spans instead
/// (duplicates are harmless, they give the same answer twice), a mesh object's slot standing
/// for its triangles within the near ball.
template <class Fn>
void GodObjectRenderer::forEachNear(const Scene& scene, const CandidateSet& candidates,
                                    Fn&& fn) const noexcept {
    if (!mNearOverflow) {
        for (std::uint32_t i = 0; i < mNearCount; ++i) {
            const std::uint32_t cached = mNearCached[i];
            fn(mNear[i], cached < kCachedTriangles ? cached : kNotCached);
        }
        return;
    }
    const std::uint32_t n = scene.size();
    for (std::size_t s = 0; s < candidates.count && s < CandidateSet::kMaxSpans; ++s) {
        for (const std::uint32_t item : candidates.spans[s]) {
            if (skipItem(scene, item)) {
                continue;
            }
            if (isTriangleItem(item)) {
                if (godobject::validItem(scene, item)) {
                    fn(item, kNotCached);
                }
            } else if (item < n && scene.object(item).shape == Shape::Mesh) {
                forEachMeshTriangleNear(scene, item, mNearCenter, mNearRadius,
                                        [&](std::uint32_t t) { fn(t, kNotCached); });
            } else if (item < n) {
                fn(item, kNotCached);
            }
        }
    }
}

} // namespace hapto
