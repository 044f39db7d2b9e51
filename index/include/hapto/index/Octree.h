#pragma once
/// The paper's modified octree (section 2.2) with neighbour links (2.2.3), as flat arrays.

#include "hapto/index/SpatialIndex.h"

#include <array>
#include <bit>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace hapto {

/// "No node": a missing parent, child or neighbour (outside the bounds).
inline constexpr std::uint32_t kNoNode = 0xFFFFFFFFu;

/// The six faces of a node, in link order: face = 2 * axis + (positive ? 1 : 0).
enum class Face : std::uint8_t { NegX, PosX, NegY, PosY, NegZ, PosZ };

/// One octree node (40 bytes). Its cell is given by level and integer coordinates: along each
/// axis it spans [min + c * step(level), min + (c + 1) * step(level)], step = size / 2^level.
/// What can be derived is not stored: the parent (one entry per eight siblings,
/// Octree::parent) and whether a leaf reached the minimum size (Octree::atMinimumSize). A leaf's
/// first slot and an inner node's first child share a word, told apart by the slot count; the
/// level and the three coordinates share one 64-bit word: per axis a 21-bit field
/// 2^level + c (c < 2^level <= 2^20), whose top set bit gives the level.
struct OctreeNode {
    /// Per face: the adjacent node of equal size, else the smallest larger node covering the
    /// face; kNoNode outside the bounds.
    std::array<std::uint32_t, 6> neighbours{kNoNode, kNoNode, kNoNode, kNoNode, kNoNode, kNoNode};

    /// True for a leaf. [any thread]
    bool isLeaf() const noexcept { return mCount != kInner; }
    /// Inner node: its children are firstChild() + octant (bit a: upper half on axis a);
    /// kNoNode for a leaf. [any thread]
    std::uint32_t firstChild() const noexcept { return isLeaf() ? kNoNode : mFirst; }
    /// Leaf: its items are slots()[firstSlot(), +slotCount()); 0 for an inner node. [any thread]
    std::uint32_t firstSlot() const noexcept { return isLeaf() ? mFirst : 0; }
    /// Leaf: number of items; 0 for an inner node. [any thread]
    std::uint32_t slotCount() const noexcept { return isLeaf() ? mCount : 0; }
    /// The level, root 0. [any thread]
    int level() const noexcept { return std::bit_width(mCell & kField) - 1; }
    /// The integer coordinate on an axis at this level. [any thread]
    std::uint32_t cell(int axis) const noexcept { return cellAt(axis, level()); }
    /// The same, given the level (level()) a caller already has. [any thread]
    std::uint32_t cellAt(int axis, int level) const noexcept {
        return static_cast<std::uint32_t>(((mCell >> (kFieldBits * axis)) & kField) ^
                                          (std::uint64_t(1) << level));
    }
    /// Sets level and coordinates (each below 2^level, level <= 20). [control]
    void setCell(int level, std::uint32_t x, std::uint32_t y, std::uint32_t z) noexcept {
        const std::uint64_t top = std::uint64_t(1) << level;
        mCell = (top | x) | (top | y) << kFieldBits | (top | z) << (2 * kFieldBits);
    }
    /// Makes this node a leaf listing slots()[first, +count), count < 2^32 - 1. [control]
    void makeLeaf(std::uint32_t first, std::uint32_t count) noexcept {
        mFirst = first;
        mCount = count;
    }
    /// Makes this node an inner node whose children start at `first`. [control]
    void makeInner(std::uint32_t first) noexcept {
        mFirst = first;
        mCount = kInner;
    }

private:
    static constexpr std::uint32_t kInner = 0xFFFFFFFFu; ///< mCount of an inner node
    static constexpr int kFieldBits = 21;
    static constexpr std::uint64_t kField = (std::uint64_t(1) << kFieldBits) - 1;

    std::uint32_t mFirst = 0; ///< Leaf: first slot; inner node: first child.
    std::uint32_t mCount = 0; ///< Leaf: slot count; kInner for an inner node.
    std::uint64_t mCell = 1 | std::uint64_t(1) << kFieldBits | std::uint64_t(1) << (2 * kFieldBits);
};
static_assert(sizeof(OctreeNode) == 40, "octree nodes are 40 bytes; update the note if not");

/// A leaf holds at most M items unless it reached the minimum size; each item (a box, a sphere
/// or a mesh triangle) is listed in every leaf its bounds overlap. Nodes are stored breadth first,
/// eight siblings together.
class Octree final : public SpatialIndex {
public:
    /// Deepest level a node may have (cells of size / 2^20).
    static constexpr int kMaxDepth = 20;
    static_assert(kMaxDepth <= 20, "OctreeNode packs a level and a coordinate in 21 bits");
    static_assert(kMaxDepth <= 20, "OctreeNode packs coordinates in 20 bits");
    /// Most nodes a build may create (then it throws InputError: raise MIN or M).
    static constexpr std::uint32_t kMaxNodes = 1u << 26;

    /// How many levels of an octree over `bounds` may split (levels 0 .. result - 1): a level
    /// splits while its children's longest edge is at least `minLeafSize` (m) and it is above
    /// kMaxDepth. The one rule the build and the memory estimate use. [any thread]
    static int splitLevels(const Aabb& bounds, double minLeafSize) noexcept;
    /// Builds the tree, level by level, in parallel (TBB inside). [control]
    static std::unique_ptr<Octree> build(const Scene& scene, const IndexSpec& spec);

    /// The leaf holding the point, descending from the root. [servo]
    LocateResult locate(const Vec3& point) const noexcept override;
    /// The leaf holding the point, walking from `leaf` with the strategy. [servo]
    LocateResult locateFrom(std::uint32_t leaf, const Vec3& point,
                            CursorStrategy strategy) const noexcept override;
    /// The items of a leaf node, ascending. [servo]
    std::span<const std::uint32_t> leafObjects(std::uint32_t node) const noexcept override;
    /// The closed box of any node (m). [servo]
    Aabb leafBounds(std::uint32_t node) const noexcept override { return nodeBounds(node); }
    /// Across the face ahead, the neighbour (a step), down its children toward the point (a
    /// step a level), its items and the leaf beyond (a step). [servo]
    void streamAhead(LeafStream& stream, std::uint32_t leaf, const Vec3& point,
                     const Vec3& direction) const noexcept override;
    /// Every leaf whose closed box overlaps `box`, depth-first from the root with a fixed-size
    /// stack (the depth is bounded by kMaxDepth). [servo]
    bool visitLeaves(const Aabb& box, LeafVisitor visit, void* context) const noexcept override;

    /// The closed box of a node (m). [any thread]
    Aabb nodeBounds(std::uint32_t node) const noexcept;
    /// All nodes, breadth first; node 0 is the root. [any thread]
    std::span<const OctreeNode> nodes() const noexcept { return mNodes; }
    /// Every leaf's items, each leaf one contiguous run. [any thread]
    std::span<const std::uint32_t> slots() const noexcept { return mSlots; }
    /// A node's parent, kNoNode for the root (stored once per eight siblings). [servo]
    std::uint32_t parent(std::uint32_t node) const noexcept {
        return node == 0 ? kNoNode : mGroupParent[(node - 1) / 8];
    }
    /// True for a leaf that halving would make smaller than the minimum leaf size. [any thread]
    bool atMinimumSize(std::uint32_t node) const noexcept {
        return mNodes[node].isLeaf() && !canSplit(mNodes[node].level());
    }
    /// The neighbour of a node across a face, or kNoNode. [servo]
    std::uint32_t neighbour(std::uint32_t node, Face face) const noexcept {
        return mNodes[node].neighbours[static_cast<int>(face)];
    }
    /// True when the node's half-open cell holds the point (closed on the bounds' upper
    /// faces): the convention every locate uses. [servo]
    bool holds(std::uint32_t node, const Vec3& point) const noexcept;

private:
    Octree(const IndexSpec& spec, const Aabb& bounds, std::uint32_t items);
    double coord(int level, std::uint32_t i, int axis) const noexcept {
        return bounds().min[axis] + static_cast<double>(i) * mStep[level][axis];
    }
    bool canSplit(int level) const noexcept { return level < mSplitLevels; }
    LocateResult descend(std::uint32_t node, const Vec3& p, std::uint32_t steps) const noexcept;
    LocateResult climb(std::uint32_t leaf, const Vec3& p) const noexcept;
    LocateResult followLinks(std::uint32_t leaf, const Vec3& p) const noexcept;
    void buildNodes(const Scene& scene, std::span<const std::uint32_t> items);
    friend class OctreeBuilder; // buildNodes' parts (Octree.cpp)

    std::array<Vec3, kMaxDepth + 2> mStep{}; // cell size per level (m)
    int mSplitLevels = 0;                    // splitLevels(bounds, MIN)
    std::vector<OctreeNode> mNodes;
    std::vector<std::uint32_t> mGroupParent; // per eight siblings (nodes 1 + 8g ...): parent
    std::vector<std::uint32_t> mSlots;
};

} // namespace hapto
