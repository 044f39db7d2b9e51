#pragma once
/// Baseline: FCL's DynamicAABBTreeCollisionManager, queried with a zero-size box at the point.

#include "BroadPhase.h"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/narrowphase/collision_object.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace hapto::bench {

/// One FCL collision object per box (an fcl::Boxd of the box's size, translated to its
/// centre, so its AABB is the box), registered at once (`registerObjects`, FCL's bulk
/// build), then `setup()`. A query moves a zero-size box to the point, recomputes its AABB
/// and calls `collide(obj, data, callback)`: the manager's AABB traversal, whose callback
/// only records the slot (no narrow phase). The objects and their geometry are part of what
/// FCL needs to answer, so they count in its build time and memory.
class FclBroadPhase {
public:
    /// Builds the objects and the tree over the boxes (m). [control]
    explicit FclBroadPhase(std::span<const Aabb> boxes);
    ~FclBroadPhase();
    FclBroadPhase(const FclBroadPhase&) = delete;
    FclBroadPhase& operator=(const FclBroadPhase&) = delete;

    /// Clears `out` and appends the slot of every box holding the point. [one thread]
    QueryCounts query(const Vec3& point, std::vector<std::uint32_t>& out);

private:
    std::vector<std::unique_ptr<fcl::CollisionObjectd>> mObjects;
    fcl::DynamicAABBTreeCollisionManagerd mManager;
    fcl::CollisionObjectd mQuery;
};

} // namespace hapto::bench
