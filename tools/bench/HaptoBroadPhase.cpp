#include "HaptoBroadPhase.h"

#include <utility>

namespace hapto::bench {

HaptoBroadPhase::HaptoBroadPhase(std::span<const Aabb> boxes,
                                 std::shared_ptr<const SpatialIndex> index, CursorStrategy strategy)
    : mIndex(std::move(index)), mBoxes(boxes), mCursor(*mIndex, strategy) {}

QueryCounts HaptoBroadPhase::query(const Vec3& point, std::vector<std::uint32_t>& out) {
    out.clear();
    const LocateResult r = mCursor.locate(point);
    for (const std::uint32_t slot : r.candidates) {
        if (mBoxes[slot].contains(point)) {
            out.push_back(slot);
        }
    }
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
