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

std::string megabytes(std::uint64_t bytes) {
    const double mb = static_cast<double>(bytes) / (1 << 20);
    char buf[32];
    std::snprintf(buf, sizeof buf, mb < 10.0 ? "%.1f" : "%.0f", mb);
    return buf;
}

} // namespace

void refuseIndexMemory(const IndexSpec& spec, std::uint64_t bytes, const std::string& detail,
                       bool atLeast) {
    throw IndexTooLargeError("index " + spec.toString() + " would need " +
                             (atLeast ? "more than " : "about ") + megabytes(bytes) +
                             " MB of memory (" + detail + "), more than the " +
                             megabytes(spec.maxBytes) +
                             " MB limit; choose a coarser index (fewer grid cells, a "
                             "larger octree MIN or M) or raise the limit with --max-index-mb");
}

} // namespace detail

std::uint64_t estimateIndexBytes(const Scene& scene, const IndexSpec& spec) {
    std::uint64_t count = 0;
    for (std::uint32_t i = 0; i < scene.itemCount(); ++i) {
        count += scene.isIndexed(scene.item(i));
    }
    switch (spec.kind) {
    case IndexSpec::Kind::BruteForce:
        return count * sizeof(std::uint32_t);
    case IndexSpec::Kind::Octree:
        // Per item: Morton key, id, shape, root flag and list entry; plus the root node; the
        // enumeration of the items.
        return count *
                   (sizeof(std::uint64_t) + 3 * sizeof(std::uint32_t) + sizeof(OverlapShape) + 1) +
               sizeof(OctreeNode);
    case IndexSpec::Kind::Grid:
        break;
    }
    const std::uint64_t n = static_cast<std::uint64_t>(std::max(spec.gridCells, 1));
    const Aabb b = partitionBounds(scene.bounds());
    const Vec3 step = (b.max - b.min) / static_cast<double>(n);
    const double last = static_cast<double>(n - 1);
    // In parallel (a control thread's TBB loop, like the build): each range sums its own.
    std::atomic<std::uint64_t> pairs{0};
    parallel::forRanges(0, scene.itemCount(), 4096, [&](std::size_t first, std::size_t end) {
        std::uint64_t rangePairs = 0;
        for (std::size_t i = first; i < end; ++i) {
            const std::uint32_t item = scene.item(static_cast<std::uint32_t>(i));
            if (!scene.isIndexed(item)) {
                continue;
            }
            const Aabb box = itemAabb(scene, item);
            const double scale =
                std::max({std::abs(box.min.x), std::abs(box.min.y), std::abs(box.min.z),
                          std::abs(box.max.x), std::abs(box.max.y), std::abs(box.max.z)}) +
                std::max({std::abs(b.min.x), std::abs(b.min.y), std::abs(b.min.z),
                          std::abs(b.max.x), std::abs(b.max.y), std::abs(b.max.z)});
            const double tol = 2.0 * kOverlapTolerance * scale;
            std::uint64_t cells = 1;
            for (int a = 0; a < 3 && cells > 0; ++a) {
                const double lo = std::floor((box.min[a] - tol - b.min[a]) / step[a]);
                const double hi = std::floor((box.max[a] + tol - b.min[a]) / step[a]);
                if (!(hi >= 0.0) || !(lo <= last)) {
                    cells = 0; // wholly outside on this axis (or NaN): in no cell
                    break;
                }
                cells *= static_cast<std::uint64_t>(std::min(hi, last) - std::max(lo, 0.0)) + 1;
            }
            rangePairs += cells;
        }
        pairs.fetch_add(rangePairs, std::memory_order_relaxed);
    });
    const std::uint64_t cellCount = n * n * n;
    // The counting sort (UniformGrid.cpp): cell offsets and the per-cell counters (which become
    // the stats' counts); per item its id, pair offset, pair count and candidate range (8 bytes
    // at most); per pair its cell and item.
    return (2 * cellCount + 1) * sizeof(std::uint32_t) + sizeof(std::uint64_t) +
           count * (2 * sizeof(std::uint32_t) + 2 * sizeof(std::uint64_t)) +
           pairs.load() * 2 * sizeof(std::uint32_t);
}

std::unique_ptr<SpatialIndex> buildIndex(const Scene& scene, const IndexSpec& spec) {
    const std::uint64_t need = estimateIndexBytes(scene, spec);
    if (need > spec.maxBytes) {
        const std::string detail =
            spec.kind == IndexSpec::Kind::Grid
                ? std::to_string(std::uint64_t(spec.gridCells) * spec.gridCells * spec.gridCells) +
                      " cells over " + std::to_string(scene.itemCount()) + " items"
                : std::to_string(scene.itemCount()) + " items";
        detail::refuseIndexMemory(spec, need, detail, spec.kind == IndexSpec::Kind::Octree);
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
