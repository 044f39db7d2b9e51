#pragma once
/// Baseline: Bullet's dynamic bounding-volume tree (btDbvt), double precision.

#include "BroadPhase.h"

#include <BulletCollision/BroadphaseCollision/btDbvt.h>

#include <cstdint>
#include <span>
#include <vector>

namespace hapto::bench {

/// btDbvt over the boxes: inserted one by one, then rebuilt top-down (`optimizeTopDown`), as
/// a static scene would be. The slot rides in each leaf's data pointer. Queried with
/// `collideTVNoStackAlloc` and a zero-size volume at the point (btDbvt's closed overlap test),
/// reusing one traversal stack, so a query allocates nothing once warm.
class BulletDbvtBroadPhase {
public:
    /// Builds the tree over the boxes (m). [control]
    explicit BulletDbvtBroadPhase(std::span<const Aabb> boxes);
    BulletDbvtBroadPhase(const BulletDbvtBroadPhase&) = delete;
    BulletDbvtBroadPhase& operator=(const BulletDbvtBroadPhase&) = delete;

    /// Clears `out` and appends the slot of every box holding the point. [one thread]
    QueryCounts query(const Vec3& point, std::vector<std::uint32_t>& out);

private:
    btDbvt mTree;
    btAlignedObjectArray<const btDbvtNode*> mStack;
};

} // namespace hapto::bench
