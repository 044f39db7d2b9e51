#include "hapto/index/BruteForce.h"

#include "BuildTimer.h"
#include "IndexItems.h"

#include <chrono>
#include <utility>

namespace hapto {

BruteForce::BruteForce(const IndexSpec& spec, const Scene& scene, std::vector<std::uint32_t> items)
    : SpatialIndex(spec, partitionBounds(scene.bounds()), static_cast<std::uint32_t>(items.size())),
      mItems(std::move(items)) {}

std::unique_ptr<BruteForce> BruteForce::build(const Scene& scene, const IndexSpec& spec) {
    const BuildTimer timer;
    std::unique_ptr<BruteForce> index(new BruteForce(spec, scene, detail::indexedItems(scene)));
    IndexStats& s = index->mStats;
    s.nodes = 1;
    const std::uint32_t counts[1] = {index->itemCount()};
    s.recordLeaves(counts);
    s.bytes = index->mItems.size() * sizeof(std::uint32_t);
    s.bytesPerObject =
        index->mItems.empty() ? 0.0 : static_cast<double>(s.bytes) / index->mItems.size();
    timer.finish(s);
    return index;
}

LocateResult BruteForce::locate(const Vec3& p) const noexcept {
    // The standard renderer tests every item wherever the pointer is: objects may reach
    // outside the partitioned space, and brute force has no space to leave.
    const bool outside = !inBounds(p);
    return {mItems, outside ? kNoLeaf : 0u, 0, outside};
}

LocateResult BruteForce::locateFrom(std::uint32_t, const Vec3& p, CursorStrategy) const noexcept {
    return locate(p);
}

std::span<const std::uint32_t> BruteForce::leafObjects(std::uint32_t) const noexcept {
    return mItems;
}

Aabb BruteForce::leafBounds(std::uint32_t) const noexcept {
    return bounds();
}

bool BruteForce::visitLeaves(const Aabb& box, LeafVisitor visit, void* context) const noexcept {
    // Every item is a candidate everywhere, inside the bounds or not (as locate says).
    return !isQueryBox(box) || visit(context, 0);
}

} // namespace hapto
