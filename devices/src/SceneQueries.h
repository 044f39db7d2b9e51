#pragma once
/// Internal geometry queries the simulated scripts plan with (control thread only).

#include "hapto/scenes/Scene.h"

#include <cstdint>
#include <span>
#include <vector>

namespace hapto::detail {

/// Signed distance from p to the object's surface (m): < 0 inside. Exact for spheres and boxes;
/// for a mesh, to its oriented bounding box (never more than the mesh's own distance).
double signedDistance(const SceneObject& object, const Vec3& p);

/// A point on an object's surface and the outward unit normal there.
struct SurfacePoint {
    Vec3 point{0.0};  ///< On the surface, world (m).
    Vec3 normal{0.0}; ///< Outward unit normal, world.
};

/// The surface point a hand at p would press on: for a box the centre-most point of the face p
/// lies beyond (kept `edgeMarginM` from the edges), for a sphere the radial point, for a mesh
/// the point of its triangles straight below that face point of its bounding box (O(triangles)).
SurfacePoint contactPoint(const SceneObject& object, const Vec3& p, double edgeMarginM);

/// Slots of the objects whose AABB, padded by `padM`, overlaps `region`.
std::vector<std::uint32_t> objectsNear(const Scene& scene, const Aabb& region, double padM);

/// True when every point of segment ab keeps at least about `marginM` (>= 0.75 marginM) from
/// the solids of `slots`, skipping slot `ignore`. Samples every marginM / 2.
bool segmentClear(const Scene& scene, std::span<const std::uint32_t> slots, const Vec3& a,
                  const Vec3& b, double marginM, std::uint32_t ignore = 0xFFFFFFFFu);

} // namespace hapto::detail
