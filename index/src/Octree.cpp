// The modified octree of Raymaekers & Coninx (section 2.2), built breadth first in parallel.
//
// Design note.
// Idea: a node whose cell overlaps more than M objects splits into eight octants, unless
// halving it would make its cells smaller than the minimum leaf size; each object goes into
// every child its bounds overlap (section 2.3, Overlap.h). The build runs one level at a
// time: for every node of the level that splits, each of its objects gets an 8-bit mask of
// the octants it overlaps (in parallel over nodes and, nested, over a node's objects); the
// children's object lists are then cut from the parent's by those masks, which keeps every
// list sorted by slot and the result identical on any number of threads. A node that does
// not split becomes a leaf and its list is appended to one slot array (CSR: each leaf one
// contiguous run, in node order); when the children are at the minimum size (they cannot
// split), their lists are cut straight into the slots and the build ends. Per node of a level
// the build keeps only its list's start and split rank (a node splits when its list is longer
// than M, known before classifying), and its scratch arrays are left uninitialised, so the
// threads that fill them touch their pages first (a fresh page's fault costs about 11 us on
// the 2-core VM, and a 10^6 build's time follows the fresh memory it touches). Neighbour links of a
// new level come from the level above in O(1) each: across an inner face the neighbour is a
// sibling; across an outer face it is the parent's neighbour's mirrored child when that neighbour
// split, else the parent's neighbour itself (equal size, or the smallest larger node covering the
// face). Invariant: node cells are given by (level, integer coordinates) and every coordinate is
// computed by one formula, min + i * size / 2^level, so a face shared by two nodes of any
// levels is the same double in both, and "which leaf holds p" has one answer everywhere:
// the half-open cell [lo, hi) that holds p, closed on the bounds' upper faces.
// Cost: build O(sum over levels of the objects listed at that level), each with up to 8
// overlap tests (an AABB reject, then the SAT; an axis-aligned box stops at the AABB test);
// memory 40 bytes per node + 4 bytes per eight siblings (their parent) + 4 bytes per
// object-leaf pair, every array sized exactly. Query: O(depth) from the root; O(1) + descent with
// links (see Cursor.h).

#include "hapto/index/Octree.h"

#include "BuildTimer.h"
#include "IndexItems.h"
#include "IndexMemory.h"
#include "Parallel.h"
#include "ScratchArray.h"

#include "hapto/io/InputError.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>

namespace hapto {
namespace {

using detail::ScratchArray;

// A node's object list is split over threads only above this many objects.
constexpr std::size_t kNestedGrain = 4096;

} // namespace

Octree::Octree(const IndexSpec& spec, const Aabb& bounds, std::uint32_t items)
    : SpatialIndex(spec, bounds, items) {
    const Vec3 size = bounds.max - bounds.min;
    for (int l = 0; l <= kMaxDepth + 1; ++l) {
        mStep[l] = Vec3(std::ldexp(size.x, -l), std::ldexp(size.y, -l), std::ldexp(size.z, -l));
    }
    mSplitLevels = splitLevels(bounds, spec.minLeafSize);
}

int Octree::splitLevels(const Aabb& bounds, double minLeafSize) noexcept {
    const Vec3 size = bounds.max - bounds.min;
    int level = 0;
    while (level < kMaxDepth) {
        const double edge = std::ldexp(std::max({size.x, size.y, size.z}), -(level + 1));
        if (!(edge >= minLeafSize * (1.0 - 1e-12))) {
            break;
        }
        ++level;
    }
    return level;
}

Aabb Octree::nodeBounds(std::uint32_t node) const noexcept {
    const OctreeNode& n = mNodes[node];
    Aabb b;
    const int l = n.level();
    for (int a = 0; a < 3; ++a) {
        b.min[a] = coord(l, n.cellAt(a, l), a);
        b.max[a] = coord(l, n.cellAt(a, l) + 1, a);
    }
    return b;
}

bool Octree::visitLeaves(const Aabb& box, LeafVisitor visit, void* context) const noexcept {
    if (!isQueryBox(box) || !box.overlaps(bounds()) || mNodes.empty()) {
        return true;
    }
    // Depth-first: a node on the stack overlaps the box; an inner node pushes its overlapping
    // children (at most 8 per level below the root, so 8 * kMaxDepth + 1 entries suffice).
    std::array<std::uint32_t, 8 * kMaxDepth + 1> stack;
    std::size_t top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const std::uint32_t node = stack[--top];
        const OctreeNode& n = mNodes[node];
        if (n.isLeaf()) {
            if (!visit(context, node)) {
                return false;
            }
            continue;
        }
        for (std::uint32_t octant = 8; octant-- > 0;) { // pushed 7..0: visited 0..7
            const std::uint32_t child = n.firstChild() + octant;
            if (nodeBounds(child).overlaps(box)) {
                stack[top++] = child;
            }
        }
    }
    return true;
}

bool Octree::holds(std::uint32_t node, const Vec3& p) const noexcept {
    const OctreeNode& n = mNodes[node];
    const int l = n.level();
    const std::uint32_t top = 1u << l;
    for (int a = 0; a < 3; ++a) {
        const std::uint32_t c = n.cellAt(a, l);
        const double lo = coord(l, c, a);
        const double hi = coord(l, c + 1, a);
        if (!(p[a] >= lo && (p[a] < hi || (c + 1 == top && p[a] <= hi)))) {
            return false;
        }
    }
    return true;
}

std::span<const std::uint32_t> Octree::leafObjects(std::uint32_t node) const noexcept {
    const OctreeNode& n = mNodes[node];
    return {mSlots.data() + n.firstSlot(), n.slotCount()};
}

LocateResult Octree::descend(std::uint32_t node, const Vec3& p,
                             std::uint32_t steps) const noexcept {
    const OctreeNode* n = &mNodes[node];
    while (!n->isLeaf()) {
        const int l = n->level() + 1;
        std::uint32_t octant = 0;
        for (int a = 0; a < 3; ++a) {
            octant |= std::uint32_t(p[a] >= coord(l, 2 * n->cellAt(a, l - 1) + 1, a)) << a;
        }
        node = n->firstChild() + octant;
        n = &mNodes[node];
        ++steps;
    }
    return {{mSlots.data() + n->firstSlot(), n->slotCount()}, node, steps, false};
}

LocateResult Octree::locate(const Vec3& p) const noexcept {
    if (!inBounds(p)) {
        return outsideResult();
    }
    return descend(0, p, 0);
}

LocateResult Octree::climb(std::uint32_t leaf, const Vec3& p) const noexcept {
    std::uint32_t node = leaf, steps = 0;
    while (!holds(node, p)) {
        node = parent(node);
        ++steps;
        if (node == kNoNode) { // cannot happen for a point in the bounds; stay safe
            return descend(0, p, steps);
        }
    }
    return descend(node, p, steps);
}

LocateResult Octree::followLinks(std::uint32_t leaf, const Vec3& p) const noexcept {
    // Cross faces only when that is never longer than climbing (the argument is in Cursor.h):
    // the point must lie in the 3x3x3 block of leaf-sized cells around the leaf, and a corner
    // crossing (3 axes) needs the common ancestor to be 2+ levels up.
    // The point's cell q on each axis at the leaf's level (the cell whose faces hold it, the
    // last one keeping the top face; the point is in the bounds), from the leaf's cell faces:
    // at most two face positions an axis.
    const OctreeNode& from = mNodes[leaf];
    const int level = from.level();
    const std::uint32_t last = (1u << level) - 1;
    std::uint32_t axesCrossed = 0, differ = 0;
    for (int a = 0; a < 3; ++a) {
        const std::uint32_t c = from.cellAt(a, level);
        std::uint32_t q = c;
        if (p[a] < coord(level, c, a)) {
            if (c == 0 || p[a] < coord(level, c - 1, a)) {
                return climb(leaf, p);
            }
            q = c - 1;
        } else if (c < last && p[a] >= coord(level, c + 1, a)) {
            if (c + 1 < last && p[a] >= coord(level, c + 2, a)) {
                return climb(leaf, p);
            }
            q = c + 1;
        }
        axesCrossed += q != c;
        differ |= q ^ c;
    }
    const int climbUp = std::bit_width(differ); // levels up to the common ancestor
    if (axesCrossed == 0 || (axesCrossed == 3 && climbUp < 2)) {
        return climb(leaf, p);
    }
    std::uint32_t node = leaf, steps = 0;
    for (int a = 0; a < 3; ++a) {
        const OctreeNode& n = mNodes[node];
        const int l = n.level();
        const std::uint32_t c = n.cellAt(a, l);
        const double lo = coord(l, c, a);
        const double hi = coord(l, c + 1, a);
        const bool top = c + 1 == (1u << l);
        if (p[a] < lo) {
            node = n.neighbours[2 * a];
        } else if (!(p[a] < hi || (top && p[a] <= hi))) {
            node = n.neighbours[2 * a + 1];
        } else {
            continue;
        }
        ++steps;
        if (node == kNoNode) { // cannot happen for a point in the bounds; stay safe
            return climb(leaf, p);
        }
    }
    if (!holds(node, p)) { // cannot happen (each crossing keeps the axes already fixed)
        return climb(leaf, p);
    }
    return descend(node, p, steps);
}

void Octree::streamAhead(LeafStream& s, std::uint32_t leaf, const Vec3& p,
                         const Vec3& direction) const noexcept {
    // Each step reads only the node the step before prefetched: a leaf's items are prefetched
    // and handed out and the leaf beyond it prefetched; an inner node's child on the point's
    // side is (across a face the point lies on the near side, so that is the child touching
    // the face, as descend picks it).
    s.items = {};
    if (s.pending != kNoNode) {
        const OctreeNode& n = mNodes[s.pending];
        if (n.isLeaf()) {
            s.items = {mSlots.data() + n.firstSlot(), n.slotCount()};
            prefetchItems(s.items);
            s.pending = s.further > 0 ? n.neighbours[s.face] : kNoNode;
            s.further -= s.further > 0 ? 1 : 0;
        } else {
            const int l = n.level() + 1;
            std::uint32_t octant = 0;
            for (int a = 0; a < 3; ++a) {
                octant |= std::uint32_t(p[a] >= coord(l, 2 * n.cellAt(a, l - 1) + 1, a)) << a;
            }
            s.pending = n.firstChild() + octant;
        }
        if (s.pending != kNoNode) {
            prefetchEnds(&mNodes[s.pending], sizeof(OctreeNode));
        }
    }
    const int face = LeafStream::faceAhead(direction);
    if (leaf == s.from || leaf >= mNodes.size() || face < 0) {
        return;
    }
    s.from = leaf;
    s.pending = mNodes[leaf].neighbours[static_cast<std::size_t>(face)];
    s.face = static_cast<std::uint8_t>(face);
    s.further = LeafStream::kFurther;
    if (s.pending != kNoNode) {
        prefetchEnds(&mNodes[s.pending], sizeof(OctreeNode));
    }
}

LocateResult Octree::locateFrom(std::uint32_t leaf, const Vec3& p,
                                CursorStrategy strategy) const noexcept {
    if (!inBounds(p)) {
        return outsideResult();
    }
    if (leaf >= mNodes.size() || strategy == CursorStrategy::FromRoot) {
        return descend(0, p, 0);
    }
    return strategy == CursorStrategy::Climb ? climb(leaf, p) : followLinks(leaf, p);
}

std::unique_ptr<Octree> Octree::build(const Scene& scene, const IndexSpec& spec) {
    if (spec.kind != IndexSpec::Kind::Octree || spec.maxObjects < 1 || !(spec.minLeafSize > 0.0) ||
        !std::isfinite(spec.minLeafSize)) {
        throw InputError("octree index: need M >= 1 and a minimum leaf size > 0 m, got " +
                         spec.toString());
    }
    const BuildTimer timer;
    const std::vector<std::uint32_t> items = detail::indexedItems(scene);
    std::unique_ptr<Octree> tree(new Octree(spec, partitionBounds(scene.bounds()),
                                            static_cast<std::uint32_t>(items.size())));
    tree->recordOutsideObjects(scene, items);
    tree->buildNodes(scene, items);

    IndexStats& st = tree->mStats;
    st.nodes = tree->mNodes.size();
    std::vector<std::uint32_t> perLeaf;
    for (std::uint32_t i = 0; i < tree->mNodes.size(); ++i) {
        const OctreeNode& n = tree->mNodes[i];
        if (n.isLeaf()) {
            perLeaf.push_back(n.slotCount());
            st.depth = std::max<std::uint32_t>(st.depth, static_cast<std::uint32_t>(n.level()));
            st.leavesAtMinimumSize += tree->atMinimumSize(i);
        }
    }
    st.recordLeaves(perLeaf);
    st.bytes =
        tree->mNodes.capacity() * sizeof(OctreeNode) +
        (tree->mGroupParent.capacity() + tree->mSlots.capacity() + tree->outsideObjects().size()) *
            sizeof(std::uint32_t);
    st.bytesPerObject = items.empty() ? 0.0 : static_cast<double>(st.bytes) / items.size();
    timer.finish(st);
    return tree;
}

/// One build of an octree's nodes, level by level (the design note above): the items in Morton
/// order, the current level's object lists back to back, and what each step of a level hands
/// the next. A friend of Octree: it writes the tree's arrays.
class OctreeBuilder {
public:
    OctreeBuilder(Octree& tree, const Scene& scene, std::span<const std::uint32_t> items);
    /// Builds the root's list, then every level until no node splits.
    void run();
    /// The most memory the build held by its accounting (octreeBuildBytes), in bytes.
    std::uint64_t peakBytes() const { return mPeakBytes; }

private:
    /// Of a node that splits: its eight children's cells, its own cell and its midpoint.
    struct SplitCells {
        OverlapCell child[8];
        OverlapCell whole;
        Vec3 mid{0.0};
    };

    void sortByMorton(const Scene& scene, std::span<const std::uint32_t> items);
    void listRoot();
    void classifyLevel();
    SplitCells splitCells(std::uint64_t node) const;
    void classifyObjects(const SplitCells& cells, std::size_t lo, std::size_t hi);
    template <class Bounds>
    void classifyWith(const ScratchArray<Bounds>& bounds, const SplitCells& cells, std::size_t lo,
                      std::size_t hi);
    bool overlapsCell(std::uint32_t local, const OverlapCell& cell) const;
    void allocateLevel();
    void refuseAbove(std::uint64_t nodes, std::uint64_t slots, std::uint64_t next) const;
    void placeNode(std::size_t k, std::uint64_t& leafTotal);
    void fillLists();
    void cutChildLists(std::size_t k, std::uint64_t childBase);
    template <class Value>
    void cutInto(std::size_t k, std::uint64_t childBase, std::uint32_t* to, const Value& value);
    void linkLevel(std::uint64_t begin, std::uint64_t end);

    Octree& mTree;
    const IndexSpec& mSpec;
    const std::uint32_t mCount;         // items
    const std::uint32_t mMaxObjects;    // M
    std::vector<std::uint32_t> mSlotOf; // per local id (Morton order): the item id
    // Per local id, one of: the item's AABB and scale when that is every item's whole test (Aabb
    // mode, or only axis-aligned boxes: 56 bytes an item), else its shape (192 bytes).
    bool mAabbOnly = false;
    ScratchArray<OverlapBounds> mBoxes;
    ScratchArray<OverlapShape> mShapes;
    ScratchArray<std::uint32_t> mEntries; // the lists of the current level's nodes, back to back
    ScratchArray<std::uint64_t> mStart;   // per node of the level, + 1: where its list starts
    ScratchArray<std::uint8_t> mMasks;    // per entry of the nodes that split: its octants
    ScratchArray<std::uint32_t> mNext;    // the next level's lists
    // Per child of the level's nodes that split (8 per node, by split rank), + 1: where its list
    // starts in mNext; the classification writes each child's count there, allocateLevel sums.
    ScratchArray<std::uint64_t> mNextStart;
    // The level being built: nodes [mLevelBegin, mLevelEnd), all of depth mLevel.
    std::uint64_t mLevelBegin = 0, mLevelEnd = 1;
    int mLevel = 0;
    std::size_t mWidth = 0;
    // Per node of the level: its rank among the nodes that split, or kStaysLeaf. A node splits
    // when its list is longer than M and its level can split, known before classifying.
    static constexpr std::uint32_t kStaysLeaf = std::numeric_limits<std::uint32_t>::max();
    ScratchArray<std::uint32_t> mSplitRank;
    std::uint64_t mSplitCount = 0, mSlotBase = 0;
    std::uint64_t mLeafEntries = 0; // entries of the level's nodes that stay leaves
    // The next level cannot split (it is at the minimum size), so the children are leaves: their
    // lists go straight into the slots, from mChildSlots on, and the build ends with them.
    bool mChildrenAreLeaves = false;
    std::uint64_t mChildSlots = 0;
    mutable std::uint64_t mPeakBytes = 0; // the largest accounting checked (bytes)
};

OctreeBuilder::OctreeBuilder(Octree& tree, const Scene& scene, std::span<const std::uint32_t> items)
    : mTree(tree), mSpec(tree.spec()), mCount(static_cast<std::uint32_t>(items.size())),
      mMaxObjects(static_cast<std::uint32_t>(tree.spec().maxObjects)) {
    sortByMorton(scene, items);
}

void OctreeBuilder::run() {
    listRoot();
    while (mLevelBegin < mLevelEnd) {
        mLevel = mTree.mNodes[mLevelBegin].level();
        mWidth = mLevelEnd - mLevelBegin;
        classifyLevel();
        allocateLevel();
        fillLists();
        const std::uint64_t newBegin = mLevelEnd, newEnd = mTree.mNodes.size();
        linkLevel(newBegin, newEnd);
        if (mChildrenAreLeaves) {
            break; // the new level's leaves are written: nothing is left to split
        }
        mEntries.swap(mNext);
        mStart.swap(mNextStart);
        mNext.reset(0); // the level above's lists: no longer needed
        mNextStart.reset(0);
        mLevelBegin = newBegin;
        mLevelEnd = newEnd;
    }
}

// Work on the items in Morton order of their centres, so a node's items are close together in
// memory (the build is bound by memory latency otherwise); "local" ids index that order and
// become item ids again when leaves are written.
void OctreeBuilder::sortByMorton(const Scene& scene, std::span<const std::uint32_t> items) {
    const Aabb box = mTree.bounds();
    ScratchArray<std::uint64_t> keys;
    keys.reset(mCount);
    const bool aabbMode = mSpec.mode == OverlapMode::Aabb;
    std::atomic<bool> anyExact{false};
    parallel::forEach(0, mCount, 4096, [&](std::size_t i) {
        // An exact test is needed past the AABB for triangles, spheres and rotated boxes (a
        // quarter-turned box, axis-aligned by its shape, is counted here too: it only costs the
        // compact path).
        const std::uint32_t item = items[i];
        if (!aabbMode && (isTriangleItem(item) || scene.body(item).shape == Shape::Sphere ||
                          !scene.body(item).axisAligned)) {
            anyExact.store(true, std::memory_order_relaxed);
        }
        const Vec3 c = itemCenter(scene, item);
        std::uint64_t code = 0;
        for (int a = 0; a < 3; ++a) {
            const double t = (c[a] - box.min[a]) / (box.max[a] - box.min[a]);
            const auto q = static_cast<std::uint32_t>(std::clamp(t, 0.0, 1.0) * 1023.0);
            for (int bit = 0; bit < 10; ++bit) {
                code |= std::uint64_t((q >> bit) & 1) << (3 * bit + a);
            }
        }
        keys[i] = (code << 32) | i;
    });
    parallel::sort(keys.begin(), keys.end());
    mSlotOf.resize(mCount);
    mAabbOnly = !anyExact.load();
    (mAabbOnly ? mBoxes.reset(mCount) : mShapes.reset(mCount));
    parallel::forEach(0, mCount, 4096, [&](std::size_t local) {
        mSlotOf[local] = items[static_cast<std::uint32_t>(keys[local])];
        if (mAabbOnly) {
            mBoxes[local] = overlapBounds(scene, mSlotOf[local]);
        } else {
            mShapes[local] = OverlapShape::of(scene, mSlotOf[local]);
        }
    });
}

bool OctreeBuilder::overlapsCell(std::uint32_t local, const OverlapCell& cell) const {
    return mAabbOnly ? overlapsAabb(mBoxes[local].aabb, mBoxes[local].scale, cell)
                     : overlaps(mShapes[local], cell, mSpec.mode);
}

// The root's list: every object overlapping the bounds; the root node itself.
void OctreeBuilder::listRoot() {
    const Aabb box = mTree.bounds();
    std::vector<std::uint8_t> keep(mCount);
    const OverlapCell cell = OverlapCell::of(box);
    parallel::forEach(0, mCount, 4096, [&](std::size_t i) {
        keep[i] = overlapsCell(static_cast<std::uint32_t>(i), cell);
    });
    mEntries.reset(static_cast<std::size_t>(std::count(keep.begin(), keep.end(), 1)));
    for (std::uint32_t i = 0, out = 0; i < mCount; ++i) {
        if (keep[i]) {
            mEntries[out++] = i;
        }
    }
    mStart.reset(2);
    mStart[0] = 0;
    mStart[1] = mEntries.size();
    mTree.mNodes.emplace_back();
}

// Step 1: which nodes of the level split (serially, by their lists' lengths), then in parallel
// for their objects which octants each overlaps, and each child's object count. Nothing is
// allocated per node beyond its split rank, and no masks when no node splits (the last level).
void OctreeBuilder::classifyLevel() {
    const bool splittable = mTree.canSplit(mLevel);
    mSplitRank.reset(mWidth);
    mSplitCount = 0;
    mLeafEntries = 0;
    for (std::size_t k = 0; k < mWidth; ++k) {
        const bool splits = splittable && mStart[k + 1] - mStart[k] > mMaxObjects;
        mSplitRank[k] = splits ? static_cast<std::uint32_t>(mSplitCount++) : kStaysLeaf;
        mLeafEntries += splits ? 0 : mStart[k + 1] - mStart[k];
    }
    mChildrenAreLeaves = mSplitCount > 0 && !mTree.canSplit(mLevel + 1);
    mNextStart.reset(8 * mSplitCount + 1); // every count is written below
    mNextStart[0] = 0;
    mMasks.reset(mSplitCount > 0 ? mEntries.size() : 0);
    if (mSplitCount == 0) {
        return;
    }
    parallel::forEach(0, mWidth, 16, [&](std::size_t k) {
        if (mSplitRank[k] == kStaysLeaf) {
            return;
        }
        const std::uint64_t b = mStart[k], e = mStart[k + 1];
        const SplitCells cells = splitCells(mLevelBegin + k);
        if (e - b > kNestedGrain) { // only big lists are worth a nested parallel loop
            parallel::forRanges(b, e, kNestedGrain / 4, [&](std::size_t lo, std::size_t hi) {
                classifyObjects(cells, lo, hi);
            });
        } else {
            classifyObjects(cells, b, e);
        }
        std::array<std::uint64_t, 8> c{};
        for (std::uint64_t i = b; i < e; ++i) {
            for (unsigned m = mMasks[i]; m != 0; m &= m - 1) {
                ++c[std::countr_zero(m)];
            }
        }
        std::copy(c.begin(), c.end(), mNextStart.begin() + 1 + 8 * std::size_t(mSplitRank[k]));
    });
}

// The cells a node's objects are tested against when it splits.
OctreeBuilder::SplitCells OctreeBuilder::splitCells(std::uint64_t node) const {
    const OctreeNode& n = mTree.mNodes[node];
    const int child = mLevel + 1;
    SplitCells cells;
    for (std::uint32_t o = 0; o < 8; ++o) {
        Aabb box;
        for (int a = 0; a < 3; ++a) {
            const std::uint32_t c = 2 * n.cell(a) + ((o >> a) & 1);
            box.min[a] = mTree.coord(child, c, a);
            box.max[a] = mTree.coord(child, c + 1, a);
        }
        cells.child[o] = OverlapCell::of(box);
    }
    cells.whole = OverlapCell::of(mTree.nodeBounds(static_cast<std::uint32_t>(node)));
    for (int a = 0; a < 3; ++a) {
        cells.mid[a] = mTree.coord(child, 2 * n.cell(a) + 1, a);
    }
    return cells;
}

// The octant masks of entries [lo, hi) of one node: the octants each AABB reaches (with the
// parent's tolerance, which is no smaller than any child's), then the full test on those only.
void OctreeBuilder::classifyObjects(const SplitCells& cells, std::size_t lo, std::size_t hi) {
    if (mAabbOnly) {
        classifyWith(mBoxes, cells, lo, hi);
    } else {
        classifyWith(mShapes, cells, lo, hi);
    }
}

template <class Bounds>
void OctreeBuilder::classifyWith(const ScratchArray<Bounds>& bounds, const SplitCells& cells,
                                 std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) {
        const Bounds& s = bounds[mEntries[i]];
        const double tol = overlapToleranceFor(s.scale, cells.whole.scale);
        std::uint32_t reach = 0xFF;
        for (int a = 0; a < 3; ++a) {
            const std::uint32_t upper = a == 0 ? 0xAA : a == 1 ? 0xCC : 0xF0;
            if (s.aabb.min[a] > cells.mid[a] + tol) {
                reach &= upper;
            } else if (s.aabb.max[a] + tol < cells.mid[a]) {
                reach &= ~upper;
            }
        }
        std::uint8_t m = 0;
        for (std::uint32_t o = 0; o < 8; ++o) {
            if ((reach >> o) & 1) {
                if constexpr (std::is_same_v<Bounds, OverlapBounds>) {
                    m |= std::uint8_t(overlapsAabb(s.aabb, s.scale, cells.child[o])) << o;
                } else {
                    m |= std::uint8_t(overlaps(s, cells.child[o], mSpec.mode)) << o;
                }
            }
        }
        mMasks[i] = m;
    }
}

// Step 2, serially: allocate children (eight siblings together) and leaf runs, refusing a
// level that would pass the memory limit, the node limit or 32-bit slot offsets. The memory
// check before each allocation counts everything the build then holds (octreeBuildBytes), and
// the per-level arrays are allocated afresh at their exact size (a reused vector keeps the
// capacity of an earlier, larger level), so the limit bounds the build's resident memory.
void OctreeBuilder::allocateLevel() {
    std::vector<OctreeNode>& nodes = mTree.mNodes;
    const std::uint64_t newNodes = nodes.size() + 8 * mSplitCount;
    refuseAbove(newNodes, mTree.mSlots.size(), 0);
    if (newNodes > Octree::kMaxNodes) {
        throw InputError("octree " + mSpec.toString() + ": more than " +
                         std::to_string(Octree::kMaxNodes) +
                         " nodes needed (too many overlapping objects for this minimum "
                         "size); raise MIN or M");
    }
    mSlotBase = mTree.mSlots.size();
    // Arrays sized exactly: each level reserves what it adds, so no capacity is left over
    // (a reallocation per level copies the nodes so far: a geometric sum, cheap).
    nodes.reserve(newNodes);
    mTree.mGroupParent.reserve(mTree.mGroupParent.size() + mSplitCount);
    for (std::size_t i = 1; i < mNextStart.size(); ++i) { // the children's counts to starts
        mNextStart[i] += mNextStart[i - 1];
    }
    const std::uint64_t nextTotal = mNextStart[mNextStart.size() - 1];
    // Slots in node order: the level's leaves, then (when they are leaves) its children's.
    mChildSlots = mSlotBase + mLeafEntries;
    const std::uint64_t slots = mChildSlots + (mChildrenAreLeaves ? nextTotal : 0);
    const std::uint64_t next = mChildrenAreLeaves ? 0 : nextTotal;
    if (slots >= std::numeric_limits<std::uint32_t>::max() ||
        next >= std::numeric_limits<std::uint32_t>::max()) {
        throw InputError("octree " + mSpec.toString() +
                         ": more than 2^32 object-leaf pairs; raise MIN or M");
    }
    std::uint64_t leafTotal = 0;
    for (std::size_t k = 0; k < mWidth; ++k) {
        placeNode(k, leafTotal);
    }
    refuseAbove(nodes.size(), slots, next);
    mTree.mSlots.reserve(slots);
    mTree.mSlots.resize(slots);
    mNext.reset(next);
}

// Refuses the build (IndexTooLargeError) when the build would hold more than the spec's
// memory limit with this many nodes, leaf slots and next-level entries (IndexMemory.h).
void OctreeBuilder::refuseAbove(std::uint64_t nodes, std::uint64_t slots,
                                std::uint64_t next) const {
    const std::uint64_t bytes =
        detail::octreeBuildBytes({mCount, nodes, slots, mWidth, mEntries.size(), next});
    mPeakBytes = std::max(mPeakBytes, bytes);
    if (bytes > mSpec.maxBytes) {
        detail::refuseIndexMemory(mSpec, bytes,
                                  std::to_string(nodes) + " nodes by depth " +
                                      std::to_string(mLevel + 1) + " and still splitting",
                                  true);
    }
}

// Node k of the level becomes a leaf with the next run of slots, or an inner node whose eight
// children are appended (in split rank order, as their lists' starts in mNextStart).
void OctreeBuilder::placeNode(std::size_t k, std::uint64_t& leafTotal) {
    std::vector<OctreeNode>& nodes = mTree.mNodes;
    const std::uint32_t id = static_cast<std::uint32_t>(mLevelBegin + k);
    if (mSplitRank[k] == kStaysLeaf) {
        OctreeNode& n = nodes[id];
        n.makeLeaf(static_cast<std::uint32_t>(mSlotBase + leafTotal),
                   static_cast<std::uint32_t>(mStart[k + 1] - mStart[k]));
        leafTotal += n.slotCount();
        return;
    }
    const std::uint32_t first = static_cast<std::uint32_t>(nodes.size());
    nodes[id].makeInner(first);
    const OctreeNode parent = nodes[id];
    mTree.mGroupParent.push_back(id);
    const std::uint64_t childBase = 8 * std::uint64_t(mSplitRank[k]);
    for (std::uint32_t o = 0; o < 8; ++o) {
        OctreeNode c;
        c.setCell(mLevel + 1, 2 * parent.cell(0) + (o & 1), 2 * parent.cell(1) + ((o >> 1) & 1),
                  2 * parent.cell(2) + ((o >> 2) & 1));
        if (mChildrenAreLeaves) {
            const std::uint64_t start = mNextStart[childBase + o];
            c.makeLeaf(static_cast<std::uint32_t>(mChildSlots + start),
                       static_cast<std::uint32_t>(mNextStart[childBase + o + 1] - start));
        }
        nodes.push_back(c);
    }
}

// Step 3, in parallel: copy leaf lists out (back to item ids, ascending), cut children's lists
// by the masks.
void OctreeBuilder::fillLists() {
    parallel::forEach(0, mWidth, 16, [&](std::size_t k) {
        if (mSplitRank[k] != kStaysLeaf) {
            cutChildLists(k, 8 * std::uint64_t(mSplitRank[k]));
            return;
        }
        const std::uint64_t b = mStart[k], e = mStart[k + 1];
        const OctreeNode& leaf = mTree.mNodes[mLevelBegin + k];
        const auto out = mTree.mSlots.begin() + static_cast<std::ptrdiff_t>(leaf.firstSlot());
        std::transform(mEntries.begin() + b, mEntries.begin() + e, out,
                       [&](std::uint32_t local) { return mSlotOf[local]; });
        std::sort(out, out + static_cast<std::ptrdiff_t>(e - b));
    });
}

// The eight children's lists of node k, cut from its list by the masks (in order, so each stays
// sorted by local id): a long list one octant a task, a short one in one pass. Children that are
// leaves get their lists as slots: item ids, each run sorted.
void OctreeBuilder::cutChildLists(std::size_t k, std::uint64_t childBase) {
    if (mChildrenAreLeaves) {
        cutInto(k, childBase, mTree.mSlots.data() + mChildSlots,
                [&](std::uint32_t local) { return mSlotOf[local]; });
        for (std::uint64_t o = childBase; o < childBase + 8; ++o) {
            std::sort(mTree.mSlots.begin() + std::ptrdiff_t(mChildSlots + mNextStart[o]),
                      mTree.mSlots.begin() + std::ptrdiff_t(mChildSlots + mNextStart[o + 1]));
        }
    } else {
        cutInto(k, childBase, mNext.begin(), [](std::uint32_t local) { return local; });
    }
}

template <class Value>
void OctreeBuilder::cutInto(std::size_t k, std::uint64_t childBase, std::uint32_t* to,
                            const Value& value) {
    const std::uint64_t b = mStart[k], e = mStart[k + 1];
    if (e - b > kNestedGrain) {
        parallel::forEach(0, 8, 1, [&](std::size_t o) {
            std::uint64_t out = mNextStart[childBase + o];
            for (std::uint64_t i = b; i < e; ++i) {
                if ((mMasks[i] >> o) & 1) {
                    to[out++] = value(mEntries[i]);
                }
            }
        });
        return;
    }
    std::array<std::uint64_t, 8> out;
    std::copy_n(mNextStart.begin() + childBase, 8, out.begin());
    for (std::uint64_t i = b; i < e; ++i) {
        const std::uint32_t v = value(mEntries[i]);
        for (unsigned m = mMasks[i]; m != 0; m &= m - 1) {
            to[out[std::countr_zero(m)]++] = v;
        }
    }
}

// Step 4, in parallel: neighbour links of the new level's nodes [begin, end), from the level
// above (a sibling across an inner face; across an outer face the parent's neighbour, or its
// mirrored child when it split).
void OctreeBuilder::linkLevel(std::uint64_t begin, std::uint64_t end) {
    std::vector<OctreeNode>& nodes = mTree.mNodes;
    parallel::forEach(begin, end, 1024, [&](std::size_t j) {
        OctreeNode& c = nodes[j];
        const OctreeNode& parent = nodes[mTree.mGroupParent[(j - 1) / 8]];
        const std::uint32_t o = static_cast<std::uint32_t>(j - parent.firstChild());
        for (int a = 0; a < 3; ++a) {
            const std::uint32_t bit = 1u << a;
            for (int positive = 0; positive < 2; ++positive) {
                const int face = 2 * a + positive;
                if (((o & bit) != 0) != (positive != 0)) { // inner face: a sibling
                    c.neighbours[face] = parent.firstChild() + (o ^ bit);
                    continue;
                }
                const std::uint32_t across = parent.neighbours[face];
                if (across == kNoNode || nodes[across].isLeaf()) {
                    c.neighbours[face] = across;
                } else { // same size as the parent, split: its mirrored child
                    c.neighbours[face] = nodes[across].firstChild() + (o ^ bit);
                }
            }
        }
    });
}

void Octree::buildNodes(const Scene& scene, std::span<const std::uint32_t> items) {
    OctreeBuilder builder(*this, scene, items);
    builder.run();
    mStats.buildPeakBytes = builder.peakBytes();
}

} // namespace hapto
