#include "HaptoBroadPhase.h"

#include <utility>

namespace hapto::bench {

HaptoBroadPhase::HaptoBroadPhase(std::span<const Aabb> boxes,
                                 std::shared_ptr<const SpatialIndex> index, CursorStrategy strategy)
    : mIndex(std::move(index)), mBoxes(boxes), mCursor(*mIndex, strategy) {}

QueryCounts HaptoBroadPhase::query(const Vec3& point, std::vector<std::uint32_t>& out) {
    const LocateResult r = mCursor.locate(point);
    // Branch-free: whether a candidate's box holds the point is a coin toss along the walk (a
    // branch per comparison mispredicts about once a query); every candidate is written and
    // the count advances only past the ones inside.
    out.resize(r.candidates.size());
    std::size_t n = 0;
    for (const std::uint32_t slot : r.candidates) {
        const Aabb& b = mBoxes[slot];
        out[n] = slot;
        n += (point.x >= b.min.x) & (point.x <= b.max.x) & (point.y >= b.min.y) &
             (point.y <= b.max.y) & (point.z >= b.min.z) & (point.z <= b.max.z);
    }
    out.resize(n);
    return {static_cast<std::uint32_t>(r.candidates.size()), r.steps};
}

QueryCounts HaptoBroadPhase::locateAndTouch(const Vec3& point, std::uint64_t& sum) {
    const LocateResult r = mCursor.locate(point);
    for (const std::uint32_t slot : r.candidates) {
        sum += slot;
    }
    return {static_cast<std::uint32_t>(r.candidates.size()), r.steps};
}

} // namespace hapto::bench
