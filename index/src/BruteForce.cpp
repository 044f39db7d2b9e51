#include "hapto/index/BruteForce.h"

#include "BuildTimer.h"

#include <chrono>
#include <numeric>

namespace hapto {

BruteForce::BruteForce(const IndexSpec& spec, const Scene& scene)
    : SpatialIndex(spec, partitionBounds(scene.bounds()), scene.size()), mSlots(scene.size()) {
    std::iota(mSlots.begin(), mSlots.end(), 0u);
}

std::unique_ptr<BruteForce> BruteForce::build(const Scene& scene, const IndexSpec& spec) {
    const BuildTimer timer;
    std::unique_ptr<BruteForce> index(new BruteForce(spec, scene));
    IndexStats& s = index->mStats;
    s.nodes = 1;
    const std::uint32_t counts[1] = {scene.size()};
    s.recordLeaves(counts);
    s.bytes = index->mSlots.size() * sizeof(std::uint32_t);
    s.bytesPerObject = scene.size() == 0 ? 0.0 : static_cast<double>(s.bytes) / scene.size();
    timer.finish(s);
    return index;
}

LocateResult BruteForce::locate(const Vec3& p) const noexcept {
    // The standard renderer tests every object wherever the pointer is: objects may reach
    // outside the partitioned space, and brute force has no space to leave.
    const bool outside = !inBounds(p);
    return {mSlots, outside ? kNoLeaf : 0u, 0, outside};
}

LocateResult BruteForce::locateFrom(std::uint32_t, const Vec3& p, CursorStrategy) const noexcept {
    return locate(p);
}

std::span<const std::uint32_t> BruteForce::leafObjects(std::uint32_t) const noexcept {
    return mSlots;
}

Aabb BruteForce::leafBounds(std::uint32_t) const noexcept {
    return bounds();
}

} // namespace hapto
