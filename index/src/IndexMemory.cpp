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
// - groups: that count is global, so it says nothing where items overlap only here and there
//   (10^6 random cubes). A cell that touches the inner boxes of more than M items lists them
//   all, so it splits, and so did its ancestors: a node of the real tree. Per axis, the level-l
//   cells touching every interval of a group are those in [max of the lows, min of the highs]
//   (or spanning the gap when that is empty), a product of three ranges, O(1) per level. The
//   groups come from near neighbours: the inner boxes in units of the bounds, as floats rounded
//   inward, sorted by the grid cell of their low corner (cells twice the median box, so boxes
//   that touch sit in adjacent cells), each tested against at most kPairChecks boxes after it
//   in its own and the four following rows; with M = 1 every pair that overlaps or has a gap
//   under a sixteenth of a grid cell is a group (cells spanning the gap list both), otherwise
//   a box and the following boxes that still share a region with it, taken greedily, once
//   more than M. Of each block of boxes the kKeep groups sharing the most volume are kept, and
//   per level the floor takes the largest kept group's cells (groups may share cells, so their
//   counts are not added). Items beyond the first kPairItems, or larger than a grid
//   cell, are left out: fewer items, a lower floor, still a floor. The groups are looked for
//   only when the ceiling passes the limit (under it the build fits whatever the floor says),
//   so a build that fits pays nothing for them.
// - shared vertices: a triangle has no inner box, so over a mesh none of the above counts
//   anything. But a cell that holds a mesh vertex (strictly inside) meets every triangle
//   around it, so where more than M triangles share the vertex the cell lists them all and
//   splits, and so did its ancestors, which hold the vertex too: every level's distinct cells
//   holding such a vertex are splits of the real tree, down to the minimum size. The vertices'
//   deepest cells as interleaved keys, sorted: two neighbours in key order are in different
//   cells from the level of their highest differing bit on, so one pass counts every level's
//   distinct cells. A vertex within 1/1024 of a deepest cell's side of a boundary is left out
//   (a lower floor, still a floor). Over a 10^6-triangle sphere at M = 4 and MIN 1e-9 the
//   floor is 4.4 x 10^7 nodes; the build was refused at depth 11 by its own check.
// - cell counts: items that do not overlap but sit closer than a level's cells (a lattice
//   with 0.5 mm gaps) split every cell spanning a gap, few per pair, so the largest group says
//   little, and boxes larger than a grid cell (five large overlapping boxes) are in no group.
//   When the floor with the groups still fits, every cell of the levels below kCountLevels
//   counts the boxes that touch it (strictly, as the groups' cells), exactly: each level is
//   swept along z, a plane's 2D difference array holding the (x, y) rectangles of the boxes
//   whose z range holds the slice (each box added at its first slice and taken out after its
//   last, O(1) whatever its size), and the plane's prefix sums are the slice's counts. Cells
//   counted over M are the level's splits, exactly what the boxes force there; a cell whose
//   parent is counted over M is a node, and its count is a floor of its list. At 10^6 cubes
//   with 0.5 mm gaps and M = 8 the floor is the real tree's 1 884 745 nodes.
// - level checks: a tree of few nodes can still be refused for its wide levels, where the
//   build holds per-node arrays and long lists while it makes the next. The build's check
//   after it places level l counts octreeBuildBytes of its nodes through level l + 1, the
//   level's nodes, its lists' entries, the leaf slots so far and the next level's entries;
//   with a split floor s(l) > 0 (so the build gets there) these are at least the floor's nodes
//   through l plus 8 s(l), max(8 s(l - 1), s(l)), and for the lists the larger of two floors:
//   (M + 1) s(l) or the counted lists of level l, with the counted lists of level l + 1; or
//   the counted tiles. The counted cells that are nodes but not counted over M (tiles) tile
//   the bounds with level l's nodes, and the real tree's leaves above l and nodes at l tile
//   each of them, listing at least its count (a box touching a cell touches one of its
//   children). A tile above l costs at least a leaf slot per count (8 bytes: a leaf, or level
//   l's lists and their children's); one at l, at least the smaller of a leaf's slots and
//   entries (13 bytes a count) and a split node's more than M entries and its children's
//   lists. At 10^6 cubes with 0.5 mm gaps the tiles are exactly the real leaves and lists
//   (12 091 904 entries through depth 8), and the floor at M = 4 is 99 % of the build's
//   check. The floor in bytes is the larger of that, over the levels, and what the finished
//   tree holds.
// Invariant: atLeastBytes <= the build's peak accounting <= atMostBytes (tests/index), every
// sum saturating at 2^64 - 1 ("more than any limit").
// Cost: O(items * levels) time; per mesh vertex shared by more than M triangles 8 bytes and a
// sort; memory per item (at most kPairItems of them) one inner box and its sort key (32
// bytes, 32 MB at 10^6 items), none per node; then for the cell counts
// per box its cell range and its place in two orders by z (20 bytes), a plane of (2^l + 1)^2
// counters per slab of slices (8 slabs in parallel, 1 MB each at level 9), and 8^l bits of
// the previous level (2 MB at level 8; the last level's are not kept); O(boxes + cells) per
// level, 1.5 x 10^8 cells through level 9.

#include "hapto/index/Octree.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/TriangleMesh.h"

#include "IndexMemory.h"
#include "Parallel.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <mutex>
#include <span>
#include <tuple>
#include <vector>

namespace hapto {
namespace detail {

std::uint64_t octreeBuildBytes(const OctreeBuildFigures& f) noexcept {
    constexpr std::uint64_t kPerItem = 4 + 4 + 4 + 4 + sizeof(OverlapShape) + 8 + 2;
    constexpr std::uint64_t kPerNode = 2 * sizeof(OctreeNode) + 1; // + 2 * 4 B per 8 siblings
    std::uint64_t b = mulSat(f.items, kPerItem);
    b = addSat(b, mulSat(f.nodes, kPerNode));
    b = addSat(b, mulSat(addSat(f.slots, 1), kSlotBytes));
    b = addSat(b, mulSat(f.levelEntries, kLevelEntryBytes));
    b = addSat(b, mulSat(f.nextEntries, kNextEntryBytes));
    b = addSat(b, mulSat(addSat(f.levelNodes, 1), 12 + 8 * sizeof(std::uint64_t)));
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

/// An item's inner box in units of the bounds' size (per axis (x - min) / size), rounded
/// inward to floats; empty (hi < lo) when the item has none.
struct UnitBox {
    std::array<float, 3> lo{1.0f, 1.0f, 1.0f};
    std::array<float, 3> hi{0.0f, 0.0f, 0.0f};

    bool empty() const { return !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]); }
    float extent() const { return std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}); }
};

/// The nearest float at or above v.
float floatUp(double v) {
    const float f = static_cast<float>(v);
    return static_cast<double>(f) < v ? std::nextafter(f, std::numeric_limits<float>::infinity())
                                      : f;
}

/// The nearest float at or below v.
float floatDown(double v) {
    const float f = static_cast<float>(v);
    return static_cast<double>(f) > v ? std::nextafter(f, -std::numeric_limits<float>::infinity())
                                      : f;
}

/// Items the group pass keeps at most (the first ones): 32 bytes each.
constexpr std::size_t kPairItems = std::size_t(1) << 20;
/// Boxes after it each box is tested against at most.
constexpr int kPairChecks = 64;

constexpr std::uint64_t kAxisCells = std::uint64_t(1) << 21;
/// The key of a box the group pass leaves out (none, or larger than a grid cell).
constexpr std::uint64_t kNoCell = std::numeric_limits<std::uint64_t>::max();

std::uint64_t packCell(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
    return (z << 42) | (y << 21) | x;
}

/// A box's sort record: the grid cell of its low corner (z, y, x, 21 bits each), then the box
/// (so equal keys sort the same way on any number of threads), and the box.
struct CellKey {
    std::uint64_t key = kNoCell;
    UnitBox box;
    bool operator<(const CellKey& o) const {
        return key != o.key ? key < o.key : std::tie(box.lo, box.hi) < std::tie(o.box.lo, o.box.hi);
    }
};

/// The inner box `in` in units of the bounds b, rounded inward.
UnitBox unitBox(const Aabb& in, const Aabb& b) {
    UnitBox u;
    for (int a = 0; a < 3; ++a) {
        const double size = b.max[a] - b.min[a];
        u.lo[a] = floatUp((in.min[a] - b.min[a]) / size);
        u.hi[a] = floatDown((in.max[a] - b.min[a]) / size);
    }
    return u;
}

/// A box's record for a grid of `cell` edges (units): kNoCell when the pass leaves it out.
CellKey cellKey(const UnitBox& u, float cell) {
    CellKey k;
    k.box = u;
    if (u.empty() || !(u.extent() <= cell)) {
        return k;
    }
    std::uint64_t c[3];
    for (int a = 0; a < 3; ++a) {
        const double q = std::floor(static_cast<double>(u.lo[a]) / cell);
        c[a] = static_cast<std::uint64_t>(std::clamp(q, 0.0, double(kAxisCells - 1)));
    }
    k.key = packCell(c[0], c[1], c[2]);
    return k;
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

/// What a pass of countLevels counts: the reach (the ceiling's) or the inner cells (the
/// floor's, needed only when the ceiling passes the limit).
enum class CountPass { Reach, Inner };

// Per axis, the item's reach or inner interval in units of the bounds' size, so a level's
// cell coordinates are these times 2^l: exact, as the cell steps are size * 2^-l exactly.
void countItem(const Scene& scene, std::uint32_t item, const IndexSpec& spec, const Aabb& b,
               int levels, CountPass pass, LevelCounts& c) {
    std::array<double, 3> lo, hi;
    Aabb in{};
    if (pass == CountPass::Reach) { // the AABB and scale only, not the whole shape
        const OverlapBounds o = overlapBounds(scene, item);
        const double tol = kReachTolerance * (absMax(o.aabb) + absMax(b));
        for (int a = 0; a < 3; ++a) {
            lo[a] = (o.aabb.min[a] - tol - b.min[a]) / (b.max[a] - b.min[a]);
            hi[a] = (o.aabb.max[a] + tol - b.min[a]) / (b.max[a] - b.min[a]);
        }
        ++c.items;
    } else {
        in = innerBox(OverlapShape::of(scene, item), spec.mode);
        for (int a = 0; a < 3; ++a) {
            lo[a] = (in.min[a] - b.min[a]) / (b.max[a] - b.min[a]);
            hi[a] = (in.max[a] - b.min[a]) / (b.max[a] - b.min[a]);
        }
    }
    bool hasInner = false;
    for (int l = 0; l < levels; ++l) {
        const std::uint64_t n = std::uint64_t(1) << l;
        const double cells = static_cast<double>(n); // 2^l: the products below are exact
        std::uint64_t count = 1;
        for (int a = 0; a < 3; ++a) {
            count *= pass == CountPass::Reach ? reachOnAxis(lo[a] * cells, hi[a] * cells, n)
                                              : insideOnAxis(lo[a] * cells, hi[a] * cells, n);
        }
        if (pass == CountPass::Reach) {
            c.reach[l] = addSat(c.reach[l], count);
        } else {
            c.inner[l] = addSat(c.inner[l], count);
            c.innerItems[l] += count > 0;
            hasInner = hasInner || count > 0;
        }
    }
    if (hasInner) {
        c.hull.min = glm::min(c.hull.min, in.min);
        c.hull.max = glm::max(c.hull.max, in.max);
    }
}

LevelCounts countLevels(const Scene& scene, const IndexSpec& spec, const Aabb& b, int levels,
                        CountPass pass) {
    LevelCounts total;
    std::mutex merge;
    parallel::forRanges(0, scene.itemCount(), 4096, [&](std::size_t first, std::size_t end) {
        LevelCounts part;
        for (std::size_t i = first; i < end; ++i) {
            const std::uint32_t item = scene.item(static_cast<std::uint32_t>(i));
            if (scene.isIndexed(item)) {
                countItem(scene, item, spec, b, levels, pass, part);
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

/// Per level, the most cells one group's boxes all touch (the note's groups).
using LevelCells = std::array<std::uint64_t, kLevels>;

/// The level-l cells (strictly) touching every box of a group, per axis [first[a], last[a]]:
/// lo and hi are the largest low and the smallest high of the group's boxes. False when none.
bool groupRange(const std::array<float, 3>& lo, const std::array<float, 3>& hi, int l,
                std::array<std::uint64_t, 3>& first, std::array<std::uint64_t, 3>& last) {
    const double n = static_cast<double>(std::uint64_t(1) << l);
    for (int a = 0; a < 3; ++a) {
        // Cell c touches [lo, hi] when c < hi * n and c + 1 > lo * n.
        const double f = std::max(std::floor(static_cast<double>(lo[a]) * n), 0.0);
        const double e = std::min(std::ceil(static_cast<double>(hi[a]) * n) - 1.0, n - 1.0);
        if (!(e >= f)) {
            return false; // also for NaN bounds
        }
        first[a] = static_cast<std::uint64_t>(f);
        last[a] = static_cast<std::uint64_t>(e);
    }
    return true;
}

std::uint64_t groupCells(const std::array<float, 3>& lo, const std::array<float, 3>& hi, int l) {
    std::array<std::uint64_t, 3> first, last;
    if (!groupRange(lo, hi, l, first, last)) {
        return 0;
    }
    return (last[0] - first[0] + 1) * (last[1] - first[1] + 1) * (last[2] - first[2] + 1);
}

void takeGroup(const std::array<float, 3>& lo, const std::array<float, 3>& hi, int levels,
               LevelCells& most) {
    for (int l = 0; l < levels; ++l) {
        most[l] = std::max(most[l], groupCells(lo, hi, l));
    }
}

/// The group grid's cell edge (units): 1.25 times the median extent of the inner boxes of up to
/// 4096 items sampled from the first `count`; 0 when none has one.
float groupGridCell(const Scene& scene, const IndexSpec& spec, const Aabb& b, std::size_t count) {
    std::vector<float> sample;
    const std::size_t stride = std::max<std::size_t>(count / 4096, 1);
    for (std::size_t i = 0; i < count; i += stride) {
        const std::uint32_t item = scene.item(static_cast<std::uint32_t>(i));
        if (scene.isIndexed(item)) {
            const UnitBox u = unitBox(innerBox(OverlapShape::of(scene, item), spec.mode), b);
            if (!u.empty()) {
                sample.push_back(u.extent());
            }
        }
    }
    if (sample.empty()) {
        return 0.0f;
    }
    std::nth_element(sample.begin(), sample.begin() + sample.size() / 2, sample.end());
    return std::max(1.25f * sample[sample.size() / 2], std::ldexp(1.0f, -20));
}

/// Levels whose cells are counted (the note's cell counts): 2^27 cells at level 9, swept one
/// z slice at a time.
constexpr int kCountLevels = 10;

/// A box's cell range at the deepest counted level, per axis [lo, hi] (at most 2^9 cells).
struct CellRange {
    std::array<std::uint16_t, 3> lo;
    std::array<std::uint16_t, 3> hi;
};

/// One level's counted cells: those over m (splits), the counts of the cells whose parent is
/// over m (listed: nodes of the real tree), of those of them at m or under (tiles) and the
/// bytes those tiles' lists cost a check of their own level at least (tileBytes: a leaf's
/// list is a level's entries and slots, a list that splits is over m level entries and its
/// children's lists hold the count at least).
struct SweptLevel {
    std::uint64_t splits = 0;
    std::uint64_t listed = 0;
    std::uint64_t tiles = 0;
    std::uint64_t tileBytes = 0;
};

/// The boxes' indices in `ranges` ordered by z0(range), by counting (0 <= z0 < slots), and in
/// `first` where each slot's run begins (slots + 1 entries).
template <class Z>
std::vector<std::uint32_t> orderByZ(std::span<const CellRange> ranges, std::size_t slots,
                                    std::vector<std::uint32_t>& first, Z z0) {
    first.assign(slots + 1, 0);
    for (const CellRange& r : ranges) {
        ++first[z0(r) + 1];
    }
    for (std::size_t z = 0; z < slots; ++z) {
        first[z + 1] += first[z];
    }
    std::vector<std::uint32_t> order(ranges.size());
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
    for (std::uint32_t i = 0; i < ranges.size(); ++i) {
        order[next[z0(ranges[i])]++] = i;
    }
    return order;
}

/// One level's cell counts (the note's cell counts), swept along z: a plane's 2D difference
/// array holds the (x, y) rectangles of the boxes whose z range holds the slice, each box
/// added at its first slice and taken out after its last, and the plane's prefix sums are the
/// slice's counts. O(boxes + cells), (2^l + 1)^2 counters a slab of slices; the slabs run in
/// parallel and their sums add up, the same on any number of threads.
class LevelSweep {
public:
    /// Level l from the boxes' ranges at level `deepest`; `parentOver`: level l - 1's bits of
    /// cells over m; `over` (when not null) gets level l's.
    LevelSweep(std::span<const CellRange> ranges, int deepest, int l, std::uint32_t m,
               const std::vector<std::uint64_t>& parentOver, std::vector<std::uint64_t>* over)
        : mRanges(ranges), mShift(deepest - l), mLevel(l), mSide(std::size_t(1) << l), mM(m),
          mParentOver(parentOver), mOver(over) {
        mStarts = orderByZ(ranges, mSide, mStartAt, [this](const CellRange& r) { return z0(r); });
        mEnds = orderByZ(ranges, mSide, mEndAt, [this](const CellRange& r) { return z1(r); });
        if (mOver) {
            mOver->assign((mSide * mSide * mSide + 63) / 64, 0);
        }
    }

    SweptLevel run() const {
        // Slabs of whole slices, only from 64 cells a side: a slice is then a multiple of 64
        // cells, so the slabs set disjoint words of `over`.
        const std::size_t slabs = mSide >= 64 ? 8 : 1;
        SweptLevel out;
        std::mutex merge;
        parallel::forEach(0, slabs, 1, [&](std::size_t k) {
            const SweptLevel part = slab(mSide * k / slabs, mSide * (k + 1) / slabs);
            const std::lock_guard<std::mutex> lock(merge);
            out.splits += part.splits;
            out.listed += part.listed;
            out.tiles += part.tiles;
            out.tileBytes += part.tileBytes;
        });
        return out;
    }

private:
    std::size_t z0(const CellRange& r) const { return r.lo[2] >> mShift; }
    std::size_t z1(const CellRange& r) const { return r.hi[2] >> mShift; }

    /// Adds (sign 1) or takes out (-1) a box's (x, y) rectangle.
    void place(std::vector<std::int32_t>& plane, const CellRange& r, std::int32_t sign) const {
        const std::size_t n = mSide + 1;
        const std::size_t x0 = r.lo[0] >> mShift, x1 = (r.hi[0] >> mShift) + 1;
        const std::size_t y0 = r.lo[1] >> mShift, y1 = (r.hi[1] >> mShift) + 1;
        plane[y0 * n + x0] += sign;
        plane[y0 * n + x1] -= sign;
        plane[y1 * n + x0] -= sign;
        plane[y1 * n + x1] += sign;
    }

    /// The counts of slices [first, end).
    SweptLevel slab(std::size_t first, std::size_t end) const {
        std::vector<std::int32_t> plane((mSide + 1) * (mSide + 1), 0);
        for (std::uint32_t i = 0; i < mStartAt[first]; ++i) { // begun before the slab
            if (z1(mRanges[mStarts[i]]) >= first) {
                place(plane, mRanges[mStarts[i]], 1);
            }
        }
        SweptLevel out;
        std::vector<std::int64_t> column(mSide);
        for (std::size_t z = first; z < end; ++z) {
            for (std::uint32_t i = mStartAt[z]; i < mStartAt[z + 1]; ++i) {
                place(plane, mRanges[mStarts[i]], 1);
            }
            std::fill(column.begin(), column.end(), 0);
            for (std::size_t y = 0; y < mSide; ++y) {
                row(plane.data() + y * (mSide + 1), z, y, column, out);
            }
            for (std::uint32_t i = mEndAt[z]; i < mEndAt[z + 1]; ++i) {
                place(plane, mRanges[mEnds[i]], -1); // out after its last slice
            }
        }
        return out;
    }

    /// Row y of slice z: `column` holds the sums of the rows before it, per x.
    void row(const std::int32_t* diff, std::size_t z, std::size_t y,
             std::vector<std::int64_t>& column, SweptLevel& out) const {
        constexpr std::uint64_t kLeafBytes = detail::kSlotBytes + detail::kLevelEntryBytes;
        const std::uint64_t splitBytes = detail::kLevelEntryBytes * (std::uint64_t(mM) + 1);
        const std::size_t half = mSide / 2;
        const std::size_t parentRow = ((z / 2) * half + y / 2) * half;
        std::int64_t run = 0;
        for (std::size_t x = 0; x < mSide; ++x) {
            run += diff[x];
            column[x] += run;
            const auto count = static_cast<std::uint64_t>(column[x]);
            const std::size_t parent = parentRow + x / 2;
            if (mLevel == 0 || ((mParentOver[parent >> 6] >> (parent & 63)) & 1)) {
                out.listed += count; // a node: it lists at least its count
                if (count <= mM) {
                    out.tiles += count;
                    out.tileBytes +=
                        std::min(kLeafBytes * count, splitBytes + detail::kNextEntryBytes * count);
                }
            }
            if (count > mM) {
                ++out.splits;
                if (mOver) {
                    const std::size_t cell = (z * mSide + y) * mSide + x;
                    (*mOver)[cell >> 6] |= std::uint64_t(1) << (cell & 63);
                }
            }
        }
    }

    std::span<const CellRange> mRanges;
    int mShift;
    int mLevel;
    std::size_t mSide;
    std::uint32_t mM;
    const std::vector<std::uint64_t>& mParentOver;
    std::vector<std::uint64_t>* mOver;
    std::vector<std::uint32_t> mStarts, mStartAt, mEnds, mEndAt;
};

/// The cell counts' lists (the note's cell counts), per level counted: `nodes`, the counts of
/// the cells whose parent is counted over M, each a node of the real tree listing at least its
/// count; `tiles` and `tileBytes`, the part of them counted M or less (SweptLevel). Those
/// cells above a level and that level's nodes tile the bounds, and the real tree's leaves
/// above it and nodes at it tile each of them (a cell's boxes each touch one of its children).
struct CountedLists {
    LevelCells nodes{};
    LevelCells tiles{};
    LevelCells tileBytes{};
    int levels = 0;

    /// At least what the leaf slots and the lists cost a build's check after it places level
    /// l (octreeBuildBytes): a tile above l is covered by leaves (kSlotBytes an entry) or by
    /// level-l nodes (their entries and their children's, or slots); a tile at l costs its
    /// tileBytes; a cell at l counted over M splits, and its children are counted below it.
    std::uint64_t listBytes(int l) const {
        if (levels == 0) {
            return 0;
        }
        const int last = std::min(l, levels - 1);
        std::uint64_t above = 0;
        for (int k = 0; k < last; ++k) {
            above = addSat(above, tiles[k]);
        }
        if (l > last) { // not counted at l: the last level's nodes are tiles above l
            return mulSat(detail::kSlotBytes, addSat(above, nodes[last]));
        }
        const std::uint64_t next = l + 1 < levels ? nodes[l + 1] : 0;
        return addSat(addSat(mulSat(detail::kSlotBytes, above), tileBytes[l]),
                      addSat(mulSat(detail::kLevelEntryBytes, nodes[l] - tiles[l]),
                             mulSat(detail::kNextEntryBytes, next)));
    }
};

/// Per level below min(levels, kCountLevels), the cells that more than m boxes touch
/// (strictly, as groupRange): each lists those items, so it splits, and so did its ancestors;
/// the levels' lists go to `lists`. A box's cell range at a level is its range at the deepest
/// one shifted (floor(lo 2^l) and ceil(hi 2^l) - 1 halve with the cells); each level is swept
/// along z (LevelSweep). A box with no cell at the deepest level is left out: still a floor.
/// Exact counts, the same on any number of threads. Before the last level, which has 7/8 of
/// the cells, `more(splits, lists)` says whether to count it (false: the floor so far is
/// already past the limit).
template <class More>
LevelCells countedSplits(std::span<const CellKey> records, std::uint32_t m, int levels,
                         CountedLists& lists, const More& more) {
    LevelCells splits{};
    const int count = std::min(levels, kCountLevels);
    if (count == 0) {
        return splits;
    }
    std::vector<CellRange> ranges;
    ranges.reserve(records.size());
    std::array<std::uint64_t, 3> lo, hi;
    for (const CellKey& k : records) {
        if (!k.box.empty() && groupRange(k.box.lo, k.box.hi, count - 1, lo, hi)) {
            CellRange r;
            for (int a = 0; a < 3; ++a) {
                r.lo[a] = static_cast<std::uint16_t>(lo[a]);
                r.hi[a] = static_cast<std::uint16_t>(hi[a]);
            }
            ranges.push_back(r);
        }
    }
    std::vector<std::uint64_t> parentOver, over; // a bit per cell counted over m
    for (int l = 0; l < count; ++l) {
        if (l > 0 && l + 1 == count && !more(splits, lists)) {
            break;
        }
        const SweptLevel level =
            LevelSweep(ranges, count - 1, l, m, parentOver, l + 1 < count ? &over : nullptr).run();
        splits[l] = level.splits;
        lists.nodes[l] = level.listed;
        lists.tiles[l] = level.tiles;
        lists.tileBytes[l] = level.tileBytes;
        parentOver.swap(over);
        lists.levels = l + 1;
    }
    return splits;
}

/// The rows a box is tested against besides its own, (dy, dz) from its own: with its own row,
/// every pair of boxes in adjacent cells is seen from one of its two boxes.
constexpr int kRows[4][2] = {{1, 0}, {-1, 1}, {0, 1}, {1, 1}};

/// The sorted boxes' group search over [first, end): per row a cursor that only moves forward
/// (the rows' first keys grow with i's key).
class GroupSearch {
public:
    GroupSearch(std::span<const CellKey> keys, float cell, std::uint32_t m)
        : mKeys(keys), mCell(cell), mM(m) {}

    /// Finds the best group of box i (the most shared volume) and keeps it when it is among
    /// the kKeep best of the search so far.
    void run(std::size_t i) {
        const std::uint64_t k = mKeys[i].key;
        const std::uint64_t x = k & (kAxisCells - 1), y = (k >> 21) & (kAxisCells - 1);
        const std::uint64_t z = k >> 42;
        mBest = -1.0f;
        mMembers = 1;
        mLo = mKeys[i].box.lo;
        mHi = mKeys[i].box.hi;
        mChecks = 0;
        scan(i + 1, packCell(std::min(x + 1, kAxisCells - 1), y, z));
        for (int r = 0; r < 4 && mMembers <= mM; ++r) {
            const std::uint64_t ry = y + kRows[r][0], rz = z + kRows[r][1];
            if ((kRows[r][0] < 0 && y == 0) || ry >= kAxisCells || rz >= kAxisCells) {
                continue;
            }
            const std::uint64_t from = packCell(x == 0 ? 0 : x - 1, ry, rz);
            std::size_t& j = mCursor[r];
            if (j == kUnset) { // a range's first box: search once
                j = static_cast<std::size_t>(
                    std::lower_bound(mKeys.begin(), mKeys.end(), from,
                                     [](const CellKey& r, std::uint64_t k) { return r.key < k; }) -
                    mKeys.begin());
            }
            while (j < mKeys.size() && mKeys[j].key < from) {
                ++j;
            }
            scan(j, packCell(std::min(x + 1, kAxisCells - 1), ry, rz));
        }
        if (mBest >= 0.0f) {
            Group* worst = &mKept[0];
            for (Group& g : mKept) {
                worst = g.score < worst->score ? &g : worst;
            }
            if (mBest > worst->score) {
                *worst = {mBest, mBestLo, mBestHi};
            }
        }
    }

    /// The kept groups' cells into `most`, per level to `levels`.
    void take(int levels, LevelCells& most) const {
        for (const Group& g : mKept) {
            if (g.score >= 0.0f) {
                takeGroup(g.lo, g.hi, levels, most);
            }
        }
    }

private:
    // Boxes [j, ...) up to key `last`: M = 1 keeps the nearest pair (the most shared volume, a
    // gap under a sixteenth of a cell counting as a thin overlap); M > 1 narrows the shared
    // box greedily and keeps it once it has more than M members.
    void scan(std::size_t j, std::uint64_t last) {
        for (; j < mKeys.size() && mKeys[j].key <= last && mChecks < kPairChecks; ++j) {
            ++mChecks;
            const UnitBox& other = mKeys[j].box;
            std::array<float, 3> lo, hi;
            float volume = 1.0f;
            bool shared = true;
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::max(mLo[a], other.lo[a]);
                hi[a] = std::min(mHi[a], other.hi[a]);
                shared = shared && lo[a] < hi[a];
                volume *= std::max(hi[a] - lo[a] + mCell / 16.0f, 0.0f);
            }
            if (mM == 1 && volume > mBest) {
                mBest = volume;
                mBestLo = lo;
                mBestHi = hi;
            } else if (mM > 1 && shared) {
                mLo = lo;
                mHi = hi;
                if (++mMembers > mM) {
                    mBest = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
                    mBestLo = lo;
                    mBestHi = hi;
                    return;
                }
            }
        }
    }

    std::span<const CellKey> mKeys;
    float mCell;
    std::uint32_t mM;
    // The groups kept: evaluating each box's group at every level would cost more than finding
    // it, and the largest shared volumes give the largest counts where the counts are large.
    static constexpr std::size_t kKeep = 16;
    struct Group {
        float score = -1.0f;
        std::array<float, 3> lo{}, hi{};
    };
    std::array<Group, kKeep> mKept{};
    static constexpr std::size_t kUnset = std::numeric_limits<std::size_t>::max();
    std::array<std::size_t, 4> mCursor{kUnset, kUnset, kUnset, kUnset};
    std::array<float, 3> mLo{}, mHi{}, mBestLo{}, mBestHi{};
    float mBest = -1.0f;
    std::uint32_t mMembers = 1;
    int mChecks = 0;
};

/// The group pass's records of the first kPairItems items' inner boxes (kNoCell for an item
/// not indexed).
std::vector<CellKey> groupRecords(const Scene& scene, const IndexSpec& spec, const Aabb& b,
                                  float cell) {
    std::vector<CellKey> records(std::min<std::size_t>(scene.itemCount(), kPairItems));
    parallel::forEach(0, records.size(), 4096, [&](std::size_t i) {
        const std::uint32_t item = scene.item(static_cast<std::uint32_t>(i));
        if (scene.isIndexed(item)) {
            const OverlapShape shape = OverlapShape::of(scene, item);
            records[i] = cellKey(unitBox(innerBox(shape, spec.mode), b), cell);
        }
    });
    return records;
}

/// Sorts the group pass's records; the records of boxes it leaves out (kNoCell) come last and
/// are not in the span returned.
std::span<const CellKey> sortRecords(std::vector<CellKey>& keys) {
    parallel::sort(keys.begin(), keys.end());
    std::size_t used = keys.size();
    while (used > 0 && keys[used - 1].key == kNoCell) {
        --used;
    }
    return {keys.data(), used};
}

/// Per level, the most cells any kept group of more than M items' inner boxes touches (the
/// note's groups), over the sorted records.
LevelCells groupFloor(std::span<const CellKey> sorted, float cell, std::uint32_t m, int levels) {
    LevelCells most{};
    std::mutex merge;
    // Fixed blocks of boxes, each keeping its own groups: the same floor on any number of
    // threads.
    constexpr std::size_t kBlock = 4096;
    const std::size_t used = sorted.size();
    parallel::forEach(0, (used + kBlock - 1) / kBlock, 1, [&](std::size_t block) {
        LevelCells part{};
        GroupSearch search(sorted, cell, m);
        for (std::size_t i = block * kBlock; i < std::min(used, (block + 1) * kBlock); ++i) {
            search.run(i);
        }
        search.take(levels, part);
        const std::lock_guard<std::mutex> lock(merge);
        for (int l = 0; l < levels; ++l) {
            most[l] = std::max(most[l], part[l]);
        }
    });
    return most;
}

/// The floor's level-l splits: the larger of the global count and `groups` (the groups' and
/// the cells' counts).
std::uint64_t splitsFloor(const LevelCounts& c, const Aabb& b, std::uint64_t m, int l,
                          const LevelCells& groups) {
    return std::max(splitsAtLeast(c, b, l, m), groups[l]);
}

/// The floor's nodes: the root and 8 per level-l split (splitsFloor), l < levels.
std::uint64_t nodesFloor(const LevelCounts& c, const Aabb& b, std::uint64_t m, int levels,
                         const LevelCells& groups) {
    std::uint64_t nodes = 1;
    for (int l = 0; l < levels; ++l) {
        nodes = addSat(nodes, mulSat(8, splitsFloor(c, b, m, l, groups)));
    }
    return nodes;
}

/// Alive at the end of the build: per item its id, local id and shape; the nodes and their
/// parents.
std::uint64_t floorBytes(std::uint64_t items, std::uint64_t nodes) {
    return addSat(
        mulSat(items, 2 * sizeof(std::uint32_t) + sizeof(OverlapShape)),
        addSat(mulSat(nodes, sizeof(OctreeNode)), mulSat(nodes / 8, sizeof(std::uint32_t))));
}

/// At least what the build's own check counts after it places a level (the note's level
/// checks): at level l with a split floor s(l) > 0 (the level is reached) the tree then holds
/// at least the floor's nodes through l plus 8 s(l) children, the level has at least
/// max(8 s(l - 1), s(l)) nodes, and its lists and slots either at least (M + 1) s(l) and the
/// counted nodes' lists entries (each split node lists more than M items) and the next
/// level's the counted nodes' lists of level l + 1, or what CountedLists::listBytes says
/// (`lists`: the cell counts, or none); each is a floor, so the larger is.
std::uint64_t levelChecksFloor(const LevelCounts& c, const Aabb& b, std::uint64_t m, int levels,
                               const LevelCells& groups, const CountedLists& lists) {
    std::uint64_t through = 1, width = 1, most = 0;
    for (int l = 0; l < levels; ++l) {
        const std::uint64_t splits = splitsFloor(c, b, m, l, groups);
        const std::uint64_t children = mulSat(8, splits);
        if (splits > 0) {
            const std::uint64_t nodes = addSat(through, children), wide = std::max(width, splits);
            const std::uint64_t counted = l < lists.levels ? lists.nodes[l] : 0;
            const std::uint64_t next = l + 1 < lists.levels ? lists.nodes[l + 1] : 0;
            const std::uint64_t listed = detail::octreeBuildBytes(
                {c.items, nodes, 0, wide, std::max(mulSat(m + 1, splits), counted), next});
            const std::uint64_t tiled = addSat(
                detail::octreeBuildBytes({c.items, nodes, 0, wide, 0, 0}), lists.listBytes(l));
            most = std::max({most, listed, tiled});
        }
        through = addSat(through, children);
        width = children;
    }
    return most;
}

/// The floor in bytes: what the finished tree holds, or the most a level's check counts.
std::uint64_t bytesFloor(const LevelCounts& c, const Aabb& b, std::uint64_t m, int levels,
                         const LevelCells& groups, const CountedLists& lists = {}) {
    return std::max(floorBytes(c.items, nodesFloor(c, b, m, levels, groups)),
                    levelChecksFloor(c, b, m, levels, groups, lists));
}

/// A point's cell at level kMaxDepth as a key of its three coordinates' bits interleaved, the
/// coarsest first (a level-l cell is the key's top 3 l bits); false for a point outside the
/// bounds or within 1/1024 of a deepest cell's side of a cell boundary (so it lies strictly
/// inside its cell at every level, whatever the build's rounding).
bool deepCellKey(const Vec3& p, const Aabb& b, std::uint64_t& key) {
    constexpr double kCells = double(std::uint64_t(1) << Octree::kMaxDepth);
    std::array<std::uint64_t, 3> q{};
    for (int a = 0; a < 3; ++a) {
        const double u = (p[a] - b.min[a]) / (b.max[a] - b.min[a]) * kCells;
        if (!(u > 0.0 && u < kCells)) {
            return false;
        }
        const double frac = u - std::floor(u);
        if (frac < 1.0 / 1024 || frac > 1.0 - 1.0 / 1024) {
            return false;
        }
        q[a] = static_cast<std::uint64_t>(u);
    }
    key = 0;
    for (int bit = Octree::kMaxDepth - 1; bit >= 0; --bit) {
        for (int a = 2; a >= 0; --a) {
            key = (key << 1) | ((q[a] >> bit) & 1);
        }
    }
    return true;
}

/// Per level below `levels`, the distinct cells that hold a mesh vertex shared by more than m
/// of its mesh's triangles (the note's shared vertices): such a cell lists those triangles,
/// so it splits, and so did its ancestors, which hold the vertex too. O(triangles + vertices
/// log vertices), 8 bytes per such vertex.
LevelCells sharedVertexSplits(const Scene& scene, const Aabb& b, std::uint64_t m, int levels) {
    std::vector<std::uint64_t> keys;
    std::vector<std::uint32_t> valence;
    for (std::uint32_t slot = 0; slot < scene.size(); ++slot) {
        const SceneObject& o = scene.object(slot);
        if (o.shape != Shape::Mesh || !o.mesh) {
            continue;
        }
        valence.assign(o.mesh->vertices().size(), 0);
        for (const TriangleIndices& t : o.mesh->triangles()) {
            for (const std::uint32_t v : t) {
                ++valence[v];
            }
        }
        std::uint64_t key = 0;
        for (std::size_t v = 0; v < valence.size(); ++v) {
            if (valence[v] > m &&
                deepCellKey(scene.body(slot).toWorld(o.mesh->vertices()[v]), b, key)) {
                keys.push_back(key);
            }
        }
    }
    LevelCells cells{};
    if (keys.empty()) {
        return cells;
    }
    parallel::sort(keys.begin(), keys.end());
    // Two neighbours in key order first differ at the level of their top differing bit.
    std::array<std::uint64_t, kLevels + 1> firstApart{};
    for (std::size_t i = 1; i < keys.size(); ++i) {
        if (const std::uint64_t diff = keys[i] ^ keys[i - 1]; diff != 0) {
            ++firstApart[Octree::kMaxDepth - (63 - std::countl_zero(diff)) / 3];
        }
    }
    std::uint64_t distinct = 1;
    for (int l = 0; l < levels; ++l) {
        distinct += firstApart[l];
        cells[l] = distinct;
    }
    return cells;
}

/// The split cells per level below `levels`: those around shared mesh vertices, the largest
/// kept group's (the note's groups), and when the floor with them still fits the limit, the
/// counted cells (the note's cell counts, whose lists go to `lists`).
LevelCells groupSplits(const Scene& scene, const IndexSpec& spec, const Aabb& b,
                       const LevelCounts& c, int levels, CountedLists& lists) {
    const std::uint64_t m = static_cast<std::uint64_t>(std::max(spec.maxObjects, 1));
    LevelCells shared = sharedVertexSplits(scene, b, m, levels);
    if (bytesFloor(c, b, m, levels, shared) > spec.maxBytes) {
        return shared;
    }
    const float cell =
        groupGridCell(scene, spec, b, std::min<std::size_t>(scene.itemCount(), kPairItems));
    std::vector<CellKey> records = groupRecords(scene, spec, b, cell);
    const std::span<const CellKey> sorted = sortRecords(records);
    const auto mm = static_cast<std::uint32_t>(m);
    LevelCells groups = groupFloor(sorted, cell, mm, levels);
    for (int l = 0; l < levels; ++l) {
        groups[l] = std::max(groups[l], shared[l]);
    }
    if (bytesFloor(c, b, m, levels, groups) <= spec.maxBytes) {
        // Not refused yet: count every shallow cell's boxes (the note's cell counts), down to
        // the level below the last that splits (its lists are that level's next entries).
        const auto withCounts = [&](const LevelCells& counted) {
            LevelCells more = groups;
            for (int l = 0; l < levels; ++l) {
                more[l] = std::max(more[l], counted[l]);
            }
            return more;
        };
        const auto fits = [&](const LevelCells& counted, const CountedLists& sofar) {
            return bytesFloor(c, b, m, levels, withCounts(counted), sofar) <= spec.maxBytes;
        };
        groups = withCounts(countedSplits(records, mm, levels + 1, lists, fits));
    }
    return groups;
}

IndexMemoryEstimate estimateOctree(const Scene& scene, const IndexSpec& spec) {
    const Aabb b = partitionBounds(scene.bounds());
    const int splitLevels = Octree::splitLevels(b, spec.minLeafSize);
    LevelCounts c = countLevels(scene, spec, b, splitLevels + 1, CountPass::Reach);
    const std::uint64_t m = static_cast<std::uint64_t>(std::max(spec.maxObjects, 1));
    // Upper bounds: nodes and entries per level, their totals, the largest level.
    std::uint64_t nodes = 1, totalNodes = 1, slots = 0, widest = 1, entries = 0;
    int reached = 0; // levels that may have nodes
    for (int l = 0; l <= splitLevels && nodes > 0; ++l, ++reached) {
        const std::uint64_t listed = std::min(c.reach[l], mulSat(nodes, c.items));
        const std::uint64_t splits = l < splitLevels ? std::min(nodes, listed / (m + 1)) : 0;
        slots = addSat(slots, l < splitLevels ? std::min(listed, mulSat(m, nodes)) : listed);
        widest = std::max(widest, nodes);
        entries = std::max(entries, listed);
        nodes = mulSat(splits, 8);
        totalNodes = addSat(totalNodes, nodes);
    }
    IndexMemoryEstimate e;
    e.atMostBytes =
        detail::octreeBuildBytes({c.items, totalNodes, slots, widest, entries, entries});
    // Lower bound: nodes the real tree has. It only matters when the ceiling passes the limit:
    // under it the build fits whatever the floor says, and pays neither the inner counts nor
    // the group pass.
    const int splitting = std::min(reached, splitLevels);
    LevelCells groups{};
    CountedLists listed;
    if (e.atMostBytes > spec.maxBytes) {
        c.add(countLevels(scene, spec, b, splitLevels + 1, CountPass::Inner));
        groups = groupSplits(scene, spec, b, c, splitting, listed);
    }
    e.nodesAtLeast = nodesFloor(c, b, m, splitting, groups);
    e.atLeastBytes = bytesFloor(c, b, m, splitting, groups, listed);
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
