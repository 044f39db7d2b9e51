// The memory estimate of an index build: bounds computed from counts, never by building.
//
// Design note.
// Idea: brute force and the grid allocate what a count of items and cell ranges gives, so
// their estimate is their build's peak. An octree's node count is known only once built, so
// the estimate bounds it from both sides, level by level, from two counts per item and level
// (each O(1): a product of three cell ranges), with no memory per node:
// - reach(l): the level-l cells the item's AABB reaches, widened by the overlap tolerance. A
//   node lists at most the items reaching its cell, so the level's list entries are at most
//   the sum R(l), a level splits at most R(l) / (M + 1) nodes (each lists more than M) and no
//   more than it has, and the next level has 8 nodes per split: an upper bound of every
//   figure the build allocates (octreeBuildBytes) without building.
// - inner(l): the level-l cells wholly inside a box the item surely overlaps (its AABB when
//   that is what places it, an axis-aligned box's own box, the cube inscribed in a sphere or
//   in a rotated box's inscribed sphere; none for a triangle in Obb mode). Such a cell lists
//   the item. A cell listing more than M items splits, and so did every ancestor (which lists
//   all of them too), so it is a node of the real tree. Of the level's cells at most
//   C = min(8^l, I(l), cells of the inner boxes' hull) hold any inner box; those listing at
//   most M inner items hold at most M * C of the sum I(l), the others at most K(l) each (K the
//   items with an inner cell at l), so at least (I(l) - M * C) / (K - M) cells split: a lower
//   bound of the real nodes. The build is refused before it starts when that floor passes the
//   limit, so "octree:1:1e-9" over overlapping boxes is refused in milliseconds, not after
//   building the levels that fit.
// Invariant: atLeastBytes <= the build's peak accounting <= atMostBytes (tests/index), every
// sum saturating at 2^64 - 1 ("more than any limit").
// Cost: O(items * levels) with no allocation per item or node; levels <= Octree::kMaxDepth + 1.

#include "hapto/index/Octree.h"
#include "hapto/index/SpatialIndex.h"

#include "IndexMemory.h"
#include "Parallel.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>

namespace hapto {
namespace detail {

std::uint64_t octreeBuildBytes(const OctreeBuildFigures& f) noexcept {
    constexpr std::uint64_t kPerItem = 4 + 4 + 4 + 4 + sizeof(OverlapShape) + 8 + 2;
    constexpr std::uint64_t kPerNode = 2 * sizeof(OctreeNode) + 1; // + 2 * 4 B per 8 siblings
    std::uint64_t b = mulSat(f.items, kPerItem);
    b = addSat(b, mulSat(f.nodes, kPerNode));
    b = addSat(b, mulSat(addSat(f.slots, 1), 2 * sizeof(std::uint32_t)));
    b = addSat(b, mulSat(f.levelEntries, sizeof(std::uint32_t) + 1));
    b = addSat(b, mulSat(f.nextEntries, sizeof(std::uint32_t)));
    b = addSat(b, mulSat(addSat(f.levelNodes, 1), 57 + 8 * sizeof(std::uint64_t)));
    return b;
}

} // namespace detail

namespace {

using detail::addSat;
using detail::mulSat;

constexpr int kLevels = Octree::kMaxDepth + 1;

/// The cells [0, n) along one axis that [lo, hi] reaches, both in cell units.
std::uint64_t reachOnAxis(double lo, double hi, std::uint64_t n) {
    const double last = static_cast<double>(n - 1);
    const double first = std::floor(lo);
    const double end = std::floor(hi);
    if (!(end >= 0.0) || !(first <= last)) {
        return 0; // wholly outside on this axis (or NaN)
    }
    return static_cast<std::uint64_t>(std::min(end, last) - std::max(first, 0.0)) + 1;
}

/// The cells [0, n) along one axis wholly inside [lo, hi], both in cell units.
std::uint64_t insideOnAxis(double lo, double hi, std::uint64_t n) {
    const double first = std::max(std::ceil(lo), 0.0);
    const double end = std::min(std::floor(hi), static_cast<double>(n));
    return end > first ? static_cast<std::uint64_t>(end - first) : 0;
}

double absMax(const Aabb& b) {
    return std::max({std::abs(b.min.x), std::abs(b.min.y), std::abs(b.min.z), std::abs(b.max.x),
                     std::abs(b.max.y), std::abs(b.max.z)});
}

/// The widening of an AABB, times the largest |coordinate| of the item's and the bounds'
/// boxes, that covers the tolerance of any overlap test of the item with a cell (Overlap.h:
/// scaled by the item's and the cell's coordinates and sizes, each at most 3 times the
/// largest |coordinate| of its box).
constexpr double kReachTolerance = 4.0 * kOverlapTolerance;

/// The cells of an n^3 division of `b` an item's AABB reaches, widened by kReachTolerance.
std::uint64_t reachCells(const Aabb& box, const Aabb& b, std::uint64_t n) {
    const double tol = kReachTolerance * (absMax(box) + absMax(b));
    std::uint64_t cells = 1;
    for (int a = 0; a < 3 && cells > 0; ++a) {
        const double step = (b.max[a] - b.min[a]) / static_cast<double>(n);
        cells *= reachOnAxis((box.min[a] - tol - b.min[a]) / step,
                             (box.max[a] + tol - b.min[a]) / step, n);
    }
    return cells;
}

/// A box the item surely overlaps all of (empty when there is none), shrunk by a relative
/// 1e-9 so rounding never puts a cell "inside" that only touches it.
Aabb innerBox(const OverlapShape& s, OverlapMode mode) {
    Aabb in{Vec3(0.0), Vec3(-1.0)}; // empty
    if (mode == OverlapMode::Aabb || (s.kind == OverlapShape::Kind::Box && s.axisAligned)) {
        in = s.aabb;
    } else if (s.kind == OverlapShape::Kind::Sphere) {
        in = {s.obb.center - Vec3(s.radius / std::sqrt(3.0)),
              s.obb.center + Vec3(s.radius / std::sqrt(3.0))};
    } else if (s.kind == OverlapShape::Kind::Box) {
        const double r = std::min({s.obb.halfExtents.x, s.obb.halfExtents.y, s.obb.halfExtents.z});
        in = {s.obb.center - Vec3(r / std::sqrt(3.0)), s.obb.center + Vec3(r / std::sqrt(3.0))};
    }
    const double shrink = 1e-9 * (absMax(in) + 1e-300);
    return {in.min + Vec3(shrink), in.max - Vec3(shrink)};
}

/// Per level of an octree: the sums of reach and inner cells, the items with an inner cell,
/// and the hull of the inner boxes.
struct LevelCounts {
    std::array<std::uint64_t, kLevels> reach{};
    std::array<std::uint64_t, kLevels> inner{};
    std::array<std::uint64_t, kLevels> innerItems{};
    Aabb hull{Vec3(std::numeric_limits<double>::infinity()),
              Vec3(-std::numeric_limits<double>::infinity())};
    std::uint64_t items = 0;

    void add(const LevelCounts& o) {
        for (int l = 0; l < kLevels; ++l) {
            reach[l] = addSat(reach[l], o.reach[l]);
            inner[l] = addSat(inner[l], o.inner[l]);
            innerItems[l] += o.innerItems[l];
        }
        hull.min = glm::min(hull.min, o.hull.min);
        hull.max = glm::max(hull.max, o.hull.max);
        items += o.items;
    }
};

// Per axis, the item's reach and inner intervals in units of the bounds' size, so a level's
// cell coordinates are these times 2^l: exact, as the cell steps are size * 2^-l exactly.
void countItem(const Scene& scene, std::uint32_t item, const IndexSpec& spec, const Aabb& b,
               int levels, LevelCounts& c) {
    const OverlapShape s = OverlapShape::of(scene, item);
    const Aabb in = innerBox(s, spec.mode);
    const double tol = kReachTolerance * (absMax(s.aabb) + absMax(b));
    std::array<double, 3> reachLo, reachHi, inLo, inHi;
    for (int a = 0; a < 3; ++a) {
        const double size = b.max[a] - b.min[a];
        reachLo[a] = (s.aabb.min[a] - tol - b.min[a]) / size;
        reachHi[a] = (s.aabb.max[a] + tol - b.min[a]) / size;
        inLo[a] = (in.min[a] - b.min[a]) / size;
        inHi[a] = (in.max[a] - b.min[a]) / size;
    }
    ++c.items;
    bool hasInner = false;
    for (int l = 0; l < levels; ++l) {
        const std::uint64_t n = std::uint64_t(1) << l;
        const double cells = static_cast<double>(n); // 2^l: the products below are exact
        std::uint64_t reach = 1, inside = 1;
        for (int a = 0; a < 3; ++a) {
            reach *= reachOnAxis(reachLo[a] * cells, reachHi[a] * cells, n);
            inside *= insideOnAxis(inLo[a] * cells, inHi[a] * cells, n);
        }
        c.reach[l] = addSat(c.reach[l], reach);
        c.inner[l] = addSat(c.inner[l], inside);
        c.innerItems[l] += inside > 0;
        hasInner = hasInner || inside > 0;
    }
    if (hasInner) {
        c.hull.min = glm::min(c.hull.min, in.min);
        c.hull.max = glm::max(c.hull.max, in.max);
    }
}

LevelCounts countLevels(const Scene& scene, const IndexSpec& spec, const Aabb& b, int levels) {
    LevelCounts total;
    std::mutex merge;
    parallel::forRanges(0, scene.itemCount(), 4096, [&](std::size_t first, std::size_t end) {
        LevelCounts part;
        for (std::size_t i = first; i < end; ++i) {
            const std::uint32_t item = scene.item(static_cast<std::uint32_t>(i));
            if (scene.isIndexed(item)) {
                countItem(scene, item, spec, b, levels, part);
            }
        }
        const std::lock_guard<std::mutex> lock(merge);
        total.add(part);
    });
    return total;
}

/// Cells of level l (2^l per axis over b) that the hull reaches.
std::uint64_t hullCells(const Aabb& hull, const Aabb& b, int l) {
    if (!(hull.min.x <= hull.max.x)) {
        return 0;
    }
    return reachCells(hull, b, std::uint64_t(1) << l);
}

/// At least how many level-l nodes split (the note's floor).
std::uint64_t splitsAtLeast(const LevelCounts& c, const Aabb& b, int l, std::uint64_t m) {
    const std::uint64_t items = c.innerItems[l];
    if (items <= m) {
        return 0;
    }
    const std::uint64_t all = std::uint64_t(1) << (3 * l);
    const std::uint64_t held = std::min({all, c.inner[l], hullCells(c.hull, b, l)});
    // A saturated sum is below the real one, so the floor stays a floor.
    const std::uint64_t low = mulSat(m, held);
    return c.inner[l] <= low ? 0 : std::min(held, (c.inner[l] - low) / (items - m));
}

IndexMemoryEstimate estimateOctree(const Scene& scene, const IndexSpec& spec) {
    const Aabb b = partitionBounds(scene.bounds());
    const int splitLevels = Octree::splitLevels(b, spec.minLeafSize);
    const LevelCounts c = countLevels(scene, spec, b, splitLevels + 1);
    const std::uint64_t m = static_cast<std::uint64_t>(std::max(spec.maxObjects, 1));
    // Upper bounds: nodes and entries per level, their totals, the largest level.
    std::uint64_t nodes = 1, totalNodes = 1, slots = 0, widest = 1, entries = 0;
    // Lower bound: nodes the real tree has.
    std::uint64_t nodesAtLeast = 1;
    for (int l = 0; l <= splitLevels && nodes > 0; ++l) {
        const std::uint64_t listed = std::min(c.reach[l], mulSat(nodes, c.items));
        const std::uint64_t splits = l < splitLevels ? std::min(nodes, listed / (m + 1)) : 0;
        slots = addSat(slots, l < splitLevels ? std::min(listed, mulSat(m, nodes)) : listed);
        widest = std::max(widest, nodes);
        entries = std::max(entries, listed);
        nodes = mulSat(splits, 8);
        totalNodes = addSat(totalNodes, nodes);
        if (l < splitLevels) {
            nodesAtLeast = addSat(nodesAtLeast, mulSat(8, splitsAtLeast(c, b, l, m)));
        }
    }
    IndexMemoryEstimate e;
    e.atMostBytes =
        detail::octreeBuildBytes({c.items, totalNodes, slots, widest, entries, entries});
    // Alive at the end of the build: per item its id, local id and shape; the nodes and their
    // parents.
    e.atLeastBytes = addSat(mulSat(c.items, 2 * sizeof(std::uint32_t) + sizeof(OverlapShape)),
                            addSat(mulSat(nodesAtLeast, sizeof(OctreeNode)),
                                   mulSat(nodesAtLeast / 8, sizeof(std::uint32_t))));
    e.nodesAtLeast = nodesAtLeast;
    return e;
}

std::uint64_t gridBytes(const Scene& scene, const IndexSpec& spec, std::uint64_t count) {
    const std::uint64_t n = static_cast<std::uint64_t>(std::max(spec.gridCells, 1));
    const Aabb b = partitionBounds(scene.bounds());
    // In parallel (a control thread's TBB loop, like the build): each range sums its own.
    std::atomic<std::uint64_t> pairs{0};
    parallel::forRanges(0, scene.itemCount(), 4096, [&](std::size_t first, std::size_t end) {
        std::uint64_t rangePairs = 0;
        for (std::size_t i = first; i < end; ++i) {
            const std::uint32_t item = scene.item(static_cast<std::uint32_t>(i));
            if (scene.isIndexed(item)) {
                rangePairs += reachCells(itemAabb(scene, item), b, n);
            }
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

} // namespace

IndexMemoryEstimate estimateIndexMemory(const Scene& scene, const IndexSpec& spec) {
    if (spec.kind == IndexSpec::Kind::Octree) {
        return estimateOctree(scene, spec);
    }
    std::uint64_t count = 0;
    for (std::uint32_t i = 0; i < scene.itemCount(); ++i) {
        count += scene.isIndexed(scene.item(i));
    }
    const std::uint64_t bytes = spec.kind == IndexSpec::Kind::Grid ? gridBytes(scene, spec, count)
                                                                   : count * sizeof(std::uint32_t);
    return {bytes, bytes, 0};
}

std::uint64_t estimateIndexBytes(const Scene& scene, const IndexSpec& spec) {
    return estimateIndexMemory(scene, spec).atMostBytes;
}

} // namespace hapto
