#pragma once
/// hapto's own indices in hapto_bench: build, then cursor locate plus an AABB filter.

#include "BroadPhase.h"

#include "hapto/index/Cursor.h"
#include "hapto/index/SpatialIndex.h"

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace hapto::bench {

/// A hapto index (any spec) and one cursor with a strategy, doing the baselines' job: the
/// cursor finds the leaf, then each of the leaf's candidates whose world AABB holds the point
/// goes to `out`. (The servo path hands the leaf's span to the renderer without this filter;
/// `hapto bench query` times that.)
class HaptoBroadPhase {
public:
    /// Binds a cursor with the strategy to a built index (shared, so the strategies can share
    /// one build). `boxes` are the scene's world AABBs by slot and must outlive this. [control]
    HaptoBroadPhase(std::span<const Aabb> boxes, std::shared_ptr<const SpatialIndex> index,
                    CursorStrategy strategy);

    /// Clears `out` and appends the slot of every candidate whose box holds the point; returns
    /// the leaf's candidate count and the cursor's steps. [one thread]
    QueryCounts query(const Vec3& point, std::vector<std::uint32_t>& out);

    /// The servo path's work instead: locate, then add every candidate slot to `sum` (so the
    /// span is read), no filter. [one thread]
    QueryCounts locateAndTouch(const Vec3& point, std::uint64_t& sum);

    /// The index. [any thread]
    const SpatialIndex& index() const { return *mIndex; }

private:
    std::shared_ptr<const SpatialIndex> mIndex;
    std::span<const Aabb> mBoxes;
    Cursor mCursor;
};

} // namespace hapto::bench
