#include "hapto/index/SpatialIndex.h"

#include "hapto/index/BruteForce.h"
#include "hapto/index/Octree.h"
#include "hapto/index/UniformGrid.h"

#include "IndexItems.h"
#include "IndexMemory.h"
#include "Parallel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace hapto {

SpatialIndex::SpatialIndex(const IndexSpec& spec, const Aabb& bounds, std::uint32_t itemCount)
    : mSpec(spec), mBounds(bounds), mItemCount(itemCount) {
    mStats.index = spec.toString();
    mStats.objects = itemCount;
}

SpatialIndex::~SpatialIndex() = default;

void SpatialIndex::streamAhead(LeafStream&, std::uint32_t, const Vec3&,
                               const Vec3&) const noexcept {}

int LeafStream::faceAhead(const Vec3& direction) noexcept {
    const Vec3 d = glm::abs(direction);
    const int axis = d.x >= d.y && d.x >= d.z ? 0 : d.y >= d.z ? 1 : 2;
    return direction[axis] > 0.0 ? 2 * axis + 1 : direction[axis] < 0.0 ? 2 * axis : -1;
}

bool SpatialIndex::inBounds(const Vec3& p) const noexcept {
    return p.x >= mBounds.min.x && p.x <= mBounds.max.x && p.y >= mBounds.min.y &&
           p.y <= mBounds.max.y && p.z >= mBounds.min.z && p.z <= mBounds.max.z;
}

bool SpatialIndex::reachesOutside(const Aabb& box) const noexcept {
    return isQueryBox(box) && !(inBounds(box.min) && inBounds(box.max));
}

Aabb partitionBounds(const Aabb& sceneBounds) {
    Aabb b = sceneBounds;
    for (int a = 0; a < 3; ++a) {
        double size = sceneBounds.max[a] - sceneBounds.min[a];
        while (sceneBounds.min[a] + size < sceneBounds.max[a]) {
            size = std::nextafter(size, std::numeric_limits<double>::infinity());
        }
        b.max[a] = sceneBounds.min[a] + size;
    }
    return b;
}

void SpatialIndex::recordOutsideObjects(const Scene& scene, std::span<const std::uint32_t> items) {
    const std::size_t count = items.size();
    std::vector<std::uint8_t> reaches(count, 0);
    const Aabb& b = mBounds;
    parallel::forEach(0, count, 4096, [&](std::size_t i) {
        const Aabb box = itemAabb(scene, items[i]);
        // Widened like the overlap tests, so rounding in an AABB never hides a sticking-out
        // part (a spurious entry costs one candidate, and only outside the bounds).
        const double scale =
            std::max({std::abs(box.min.x), std::abs(box.min.y), std::abs(box.min.z),
                      std::abs(box.max.x), std::abs(box.max.y), std::abs(box.max.z)});
        const double tol = kOverlapTolerance * scale;
        bool out = false;
        for (int a = 0; a < 3; ++a) {
            out = out || box.min[a] - tol < b.min[a] || box.max[a] + tol > b.max[a];
        }
        reaches[i] = out;
    });
    mOutside.clear();
    for (std::size_t i = 0; i < count; ++i) {
        if (reaches[i]) {
            mOutside.push_back(items[i]);
        }
    }
    mOutside.shrink_to_fit();
    mStats.outsideObjects = mOutside.size();
}

namespace detail {

namespace {

/// Bytes in MB: one decimal under 10 MB, none above, or `places` decimals when >= 0.
std::string megabytes(std::uint64_t bytes, int places = -1) {
    const double mb = static_cast<double>(bytes) / (1 << 20);
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*f", places >= 0 ? places : mb < 10.0 ? 1 : 0, mb);
    return buf;
}

} // namespace

void refuseIndexMemory(const IndexSpec& spec, std::uint64_t bytes, const std::string& detail,
                       bool atLeast) {
    // Just over the limit, the figures get the decimals that tell them apart ("1024.43 MB ...
    // the 1024.00 MB limit", not "1024 MB ... the 1024 MB limit").
    int places = -1;
    while (places < 6 && megabytes(bytes, places) == megabytes(spec.maxBytes, places)) {
        places = places < 2 ? 2 : places + 2;
    }
    // A saturated count (IndexMemory.h) means "more than 2^64 bytes".
    const std::string need =
        bytes == std::numeric_limits<std::uint64_t>::max()
            ? "more than 2^64 bytes"
            : (atLeast ? "more than " : "about ") + megabytes(bytes, places) + " MB";
    throw IndexTooLargeError("index " + spec.toString() + " would need " + need + " of memory (" +
                             detail + "), more than the " + megabytes(spec.maxBytes, places) +
                             " MB limit; choose a coarser index (fewer grid cells, a "
                             "larger octree MIN or M) or raise the limit with --max-index-mb");
}

} // namespace detail

std::unique_ptr<SpatialIndex> buildIndex(const Scene& scene, const IndexSpec& spec) {
    const IndexMemoryEstimate need = estimateIndexMemory(scene, spec);
    if (need.atLeastBytes > spec.maxBytes) {
        const std::string items = std::to_string(detail::indexedItemCount(scene)) + " items";
        const std::string detail =
            spec.kind == IndexSpec::Kind::Grid
                ? std::to_string(std::uint64_t(spec.gridCells) * spec.gridCells * spec.gridCells) +
                      " cells over " + items
            : spec.kind == IndexSpec::Kind::Octree
                ? "at least " + std::to_string(need.nodesAtLeast) + " nodes over " + items
                : items;
        detail::refuseIndexMemory(spec, need.atLeastBytes, detail,
                                  spec.kind == IndexSpec::Kind::Octree);
    }
    switch (spec.kind) {
    case IndexSpec::Kind::BruteForce:
        return BruteForce::build(scene, spec);
    case IndexSpec::Kind::Grid:
        return UniformGrid::build(scene, spec);
    case IndexSpec::Kind::Octree:
        return Octree::build(scene, spec);
    }
    return BruteForce::build(scene, spec);
}

} // namespace hapto
