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
// contiguous run). Neighbour links of a new level come from the level above in O(1) each:
// across an inner face the neighbour is a sibling; across an outer face it is the parent's
// neighbour's mirrored child when that neighbour split, else the parent's neighbour itself
// (equal size, or the smallest larger node covering the face).
// Invariant: node cells are given by (level, integer coordinates) and every coordinate is
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

#include "hapto/io/InputError.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace hapto {
namespace {

// A node's object list is split over threads only above this many objects.
constexpr std::size_t kNestedGrain = 4096;

} // namespace

Octree::Octree(const IndexSpec& spec, const Aabb& bounds, std::uint32_t items)
    : SpatialIndex(spec, bounds, items) {
    const Vec3 size = bounds.max - bounds.min;
    for (int l = 0; l <= kMaxDepth + 1; ++l) {
        mStep[l] = Vec3(std::ldexp(size.x, -l), std::ldexp(size.y, -l), std::ldexp(size.z, -l));
        mInvStep[l] = 1.0 / mStep[l];
    }
}

bool Octree::canSplit(int level) const noexcept {
    if (level >= kMaxDepth) {
        return false;
    }
    const Vec3& child = mStep[level + 1];
    const double edge = std::max({child.x, child.y, child.z});
    return edge >= spec().minLeafSize * (1.0 - 1e-12);
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

std::uint32_t Octree::cellIndex(int level, double v, int axis) const noexcept {
    const std::uint32_t last = (1u << level) - 1;
    // A product with the inverse may land one cell off near a face; the comparisons below
    // settle on the formula the cell boxes use.
    const double t = std::floor((v - bounds().min[axis]) * mInvStep[level][axis]);
    std::uint32_t i = static_cast<std::uint32_t>(t < 0.0 ? 0.0 : t > last ? last : t);
    if (i > 0 && v < coord(level, i, axis)) {
        --i;
    } else if (i < last && v >= coord(level, i + 1, axis)) {
        ++i;
    }
    return i;
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
    const OctreeNode& from = mNodes[leaf];
    const int level = from.level();
    std::uint32_t axesCrossed = 0, differ = 0;
    for (int a = 0; a < 3; ++a) {
        const std::uint32_t q = cellIndex(level, p[a], a), c = from.cellAt(a, level);
        if (q + 1 < c || q > c + 1) {
            return climb(leaf, p);
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

void Octree::buildNodes(const Scene& scene, std::span<const std::uint32_t> items) {
    const std::uint32_t count = static_cast<std::uint32_t>(items.size());
    const IndexSpec& sp = spec();
    const std::uint32_t maxObjects = static_cast<std::uint32_t>(sp.maxObjects);
    // Work on the items in Morton order of their centres, so a node's items are close
    // together in memory (the build is bound by memory latency otherwise); "local" ids index
    // that order and become item ids again when leaves are written.
    const Aabb box = bounds();
    std::vector<std::uint64_t> keys(count);
    parallel::forEach(0, count, 4096, [&](std::size_t i) {
        const Vec3 c = itemCenter(scene, items[i]);
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
    std::vector<std::uint32_t> slotOf(count);
    std::vector<OverlapShape> shapes(count);
    parallel::forEach(0, count, 4096, [&](std::size_t local) {
        slotOf[local] = items[static_cast<std::uint32_t>(keys[local])];
        shapes[local] = OverlapShape::of(scene, slotOf[local]);
    });
    keys = {};

    // The root's list: every object overlapping the bounds.
    std::vector<std::uint8_t> keep(count);
    parallel::forEach(0, count, 4096,
                      [&](std::size_t i) { keep[i] = overlaps(shapes[i], box, sp.mode); });
    std::vector<std::uint32_t> entries; // the lists of the current level's nodes, back to back
    entries.reserve(count);
    for (std::uint32_t i = 0; i < count; ++i) {
        if (keep[i]) {
            entries.push_back(i);
        }
    }
    keep = {};
    std::vector<std::uint64_t> start{0, entries.size()}; // per node of the level, + 1
    mNodes.emplace_back();

    std::vector<std::uint8_t> masks;
    std::vector<std::uint32_t> next;
    std::vector<std::uint64_t> nextStart;
    std::uint64_t levelBegin = 0, levelEnd = 1;
    while (levelBegin < levelEnd) {
        const int level = mNodes[levelBegin].level();
        const bool splittable = canSplit(level);
        const std::size_t width = levelEnd - levelBegin;
        std::vector<std::array<std::uint32_t, 8>> childCount(width);
        std::vector<std::uint8_t> splits(width, 0);
        masks.assign(entries.size(), 0);

        // 1. Which nodes split, and for their objects, which octants each overlaps.
        parallel::forEach(0, width, 16, [&](std::size_t k) {
            const std::uint64_t b = start[k], e = start[k + 1];
            if (!splittable || e - b <= maxObjects) {
                return;
            }
            splits[k] = 1;
            const OctreeNode& n = mNodes[levelBegin + k];
            OverlapCell child[8];
            for (std::uint32_t o = 0; o < 8; ++o) {
                Aabb box;
                for (int a = 0; a < 3; ++a) {
                    const std::uint32_t c = 2 * n.cell(a) + ((o >> a) & 1);
                    box.min[a] = coord(level + 1, c, a);
                    box.max[a] = coord(level + 1, c + 1, a);
                }
                child[o] = OverlapCell::of(box);
            }
            const OverlapCell whole = OverlapCell::of(nodeBounds(levelBegin + k));
            Vec3 mid(0.0);
            for (int a = 0; a < 3; ++a) {
                mid[a] = coord(level + 1, 2 * n.cell(a) + 1, a);
            }
            const auto classify = [&](std::size_t lo, std::size_t hi) {
                for (std::size_t i = lo; i < hi; ++i) {
                    const OverlapShape& s = shapes[entries[i]];
                    // Octants the AABB reaches (with the parent's tolerance, which is no
                    // smaller than any child's), then the full test on those only.
                    const double tol = overlapTolerance(s, whole);
                    std::uint32_t reach = 0xFF;
                    for (int a = 0; a < 3; ++a) {
                        const std::uint32_t upper = a == 0 ? 0xAA : a == 1 ? 0xCC : 0xF0;
                        if (s.aabb.min[a] > mid[a] + tol) {
                            reach &= upper;
                        } else if (s.aabb.max[a] + tol < mid[a]) {
                            reach &= ~upper;
                        }
                    }
                    std::uint8_t m = 0;
                    for (std::uint32_t o = 0; o < 8; ++o) {
                        if ((reach >> o) & 1) {
                            m |= std::uint8_t(overlaps(s, child[o], sp.mode)) << o;
                        }
                    }
                    masks[i] = m;
                }
            };
            if (e - b > kNestedGrain) { // only big lists are worth a nested parallel loop
                parallel::forRanges(b, e, kNestedGrain / 4, classify);
            } else {
                classify(b, e);
            }
            std::array<std::uint32_t, 8> c{};
            for (std::uint64_t i = b; i < e; ++i) {
                for (std::uint32_t o = 0; o < 8; ++o) {
                    c[o] += (masks[i] >> o) & 1;
                }
            }
            childCount[k] = c;
        });

        // 2. Serially: allocate children (eight siblings together) and leaf runs.
        std::uint64_t splitCount = 0;
        for (std::size_t k = 0; k < width; ++k) {
            splitCount += splits[k];
        }
        // Memory, before this level is allocated: nodes so far and new, leaf slots so far,
        // this level's lists and masks, the per-object arrays; the lists of the next level and
        // the new leaves' slots are added once known, below.
        const std::uint64_t perObject =
            std::uint64_t(count) * (sizeof(std::uint32_t) + sizeof(OverlapShape));
        const auto memory = [&](std::uint64_t nodes, std::uint64_t slots, std::uint64_t next) {
            return nodes * sizeof(OctreeNode) + (nodes / 8 + slots + next) * sizeof(std::uint32_t) +
                   entries.size() * (sizeof(std::uint32_t) + 1) + perObject;
        };
        const auto checkMemory = [&](std::uint64_t bytes) {
            if (bytes > sp.maxBytes) {
                detail::refuseIndexMemory(sp, bytes,
                                          std::to_string(mNodes.size() + 8 * splitCount) +
                                              " nodes by depth " + std::to_string(level + 1) +
                                              " and still splitting",
                                          true);
            }
        };
        checkMemory(memory(mNodes.size() + 8 * splitCount, mSlots.size(), 0));
        if (mNodes.size() + 8 * splitCount > kMaxNodes) {
            throw InputError("octree " + sp.toString() + ": more than " +
                             std::to_string(kMaxNodes) +
                             " nodes needed (too many overlapping objects for this minimum "
                             "size); raise MIN or M");
        }
        const std::uint64_t slotBase = mSlots.size();
        // Arrays sized exactly: each level reserves what it adds, so no capacity is left over
        // (a reallocation per level copies the nodes so far: a geometric sum, cheap).
        mNodes.reserve(mNodes.size() + 8 * splitCount);
        mGroupParent.reserve(mGroupParent.size() + splitCount);
        std::vector<std::uint64_t> leafAt(width, 0);
        std::uint64_t leafTotal = 0, nextTotal = 0;
        nextStart.assign(1, 0);
        for (std::size_t k = 0; k < width; ++k) {
            const std::uint32_t id = static_cast<std::uint32_t>(levelBegin + k);
            if (!splits[k]) {
                OctreeNode& n = mNodes[id];
                n.makeLeaf(static_cast<std::uint32_t>(slotBase + leafTotal),
                           static_cast<std::uint32_t>(start[k + 1] - start[k]));
                leafAt[k] = slotBase + leafTotal;
                leafTotal += n.slotCount();
                continue;
            }
            const std::uint32_t first = static_cast<std::uint32_t>(mNodes.size());
            mNodes[id].makeInner(first);
            const OctreeNode parent = mNodes[id];
            mGroupParent.push_back(id);
            for (std::uint32_t o = 0; o < 8; ++o) {
                OctreeNode c;
                c.setCell(level + 1, 2 * parent.cell(0) + (o & 1),
                          2 * parent.cell(1) + ((o >> 1) & 1), 2 * parent.cell(2) + ((o >> 2) & 1));
                mNodes.push_back(c);
                nextTotal += childCount[k][o];
                nextStart.push_back(nextTotal);
            }
        }
        if (slotBase + leafTotal >= std::numeric_limits<std::uint32_t>::max() ||
            nextTotal >= std::numeric_limits<std::uint32_t>::max()) {
            throw InputError("octree " + sp.toString() +
                             ": more than 2^32 object-leaf pairs; raise MIN or M");
        }
        checkMemory(memory(mNodes.size(), slotBase + leafTotal, nextTotal));
        mSlots.reserve(slotBase + leafTotal);
        mSlots.resize(slotBase + leafTotal);
        next.resize(nextTotal);

        // 3. In parallel: copy leaf lists out, cut children's lists by the masks.
        std::vector<std::uint64_t> childBase(width, 0);
        for (std::size_t k = 0, c = 0; k < width; ++k) {
            if (splits[k]) {
                childBase[k] = c;
                c += 8;
            }
        }
        parallel::forEach(0, width, 16, [&](std::size_t k) {
            const std::uint64_t b = start[k], e = start[k + 1];
            if (!splits[k]) { // back to item ids, ascending
                const auto out = mSlots.begin() + static_cast<std::ptrdiff_t>(leafAt[k]);
                std::transform(entries.begin() + b, entries.begin() + e, out,
                               [&](std::uint32_t local) { return slotOf[local]; });
                std::sort(out, out + static_cast<std::ptrdiff_t>(e - b));
                return;
            }
            const auto cut = [&](std::size_t o) {
                std::uint64_t out = nextStart[childBase[k] + o];
                for (std::uint64_t i = b; i < e; ++i) {
                    if ((masks[i] >> o) & 1) {
                        next[out++] = entries[i];
                    }
                }
            };
            if (e - b > kNestedGrain) {
                parallel::forEach(0, 8, 1, cut);
            } else {
                for (std::size_t o = 0; o < 8; ++o) {
                    cut(o);
                }
            }
        });

        // 4. Neighbour links of the new level, from the level above.
        const std::uint64_t newBegin = levelEnd, newEnd = mNodes.size();
        parallel::forEach(newBegin, newEnd, 1024, [&](std::size_t j) {
            OctreeNode& c = mNodes[j];
            const OctreeNode& parent = mNodes[mGroupParent[(j - 1) / 8]];
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
                    if (across == kNoNode || mNodes[across].isLeaf()) {
                        c.neighbours[face] = across;
                    } else { // same size as the parent, split: its mirrored child
                        c.neighbours[face] = mNodes[across].firstChild() + (o ^ bit);
                    }
                }
            }
        });

        entries.swap(next);
        start.swap(nextStart);
        levelBegin = newBegin;
        levelEnd = newEnd;
    }
}

} // namespace hapto
