#pragma once
/// The paper's modified octree (section 2.2) with neighbour links (2.2.3), as flat arrays.

#include "hapto/index/SpatialIndex.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace hapto {

/// "No node": a missing parent, child or neighbour (outside the bounds).
inline constexpr std::uint32_t kNoNode = 0xFFFFFFFFu;

/// The six faces of a node, in link order: face = 2 * axis + (positive ? 1 : 0).
enum class Face : std::uint8_t { NegX, PosX, NegY, PosY, NegZ, PosZ };

/// One octree node (56 bytes). Its cell is given by level and integer coordinates: along each
/// axis it spans [min + c * step(level), min + (c + 1) * step(level)], step = size / 2^level.
struct OctreeNode {
    std::uint32_t parent = kNoNode;     ///< Parent node, kNoNode for the root.
    std::uint32_t firstChild = kNoNode; ///< Children firstChild + octant (bit a: upper half
                                        ///< on axis a); kNoNode for a leaf.
    /// Per face: the adjacent node of equal size, else the smallest larger node covering the
    /// face; kNoNode outside the bounds.
    std::array<std::uint32_t, 6> neighbours{kNoNode, kNoNode, kNoNode, kNoNode, kNoNode, kNoNode};
    std::uint32_t firstSlot = 0; ///< Leaf: its items are slots()[firstSlot, +slotCount).
    std::uint32_t slotCount = 0; ///< Leaf: number of items.
    std::array<std::uint32_t, 3> cell{0, 0, 0}; ///< Integer coordinates at this level.
    std::uint8_t level = 0;                     ///< Root 0.
    std::uint8_t atMinimumSize = 0; ///< 1 when halving it would go below the minimum size.
    std::uint8_t padding[2] = {0, 0};

    /// True for a leaf. [any thread]
    bool isLeaf() const noexcept { return firstChild == kNoNode; }
};
static_assert(sizeof(OctreeNode) == 56, "octree nodes are 56 bytes; update the note if not");

/// A leaf holds at most M items unless it reached the minimum size; each item (a box, a sphere
/// or a mesh triangle) is listed in every leaf its bounds overlap. Nodes are stored breadth first,
/// eight siblings together.
class Octree final : public SpatialIndex {
public:
    /// Deepest level a node may have (cells of size / 2^20).
    static constexpr int kMaxDepth = 20;
    /// Most nodes a build may create (then it throws InputError: raise MIN or M).
    static constexpr std::uint32_t kMaxNodes = 1u << 26;

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

    /// The closed box of a node (m). [any thread]
    Aabb nodeBounds(std::uint32_t node) const noexcept;
    /// All nodes, breadth first; node 0 is the root. [any thread]
    std::span<const OctreeNode> nodes() const noexcept { return mNodes; }
    /// Every leaf's items, each leaf one contiguous run. [any thread]
    std::span<const std::uint32_t> slots() const noexcept { return mSlots; }
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
    bool canSplit(int level) const noexcept;
    std::uint32_t cellIndex(int level, double v, int axis) const noexcept;
    LocateResult descend(std::uint32_t node, const Vec3& p, std::uint32_t steps) const noexcept;
    LocateResult climb(std::uint32_t leaf, const Vec3& p) const noexcept;
    LocateResult followLinks(std::uint32_t leaf, const Vec3& p) const noexcept;
    void buildNodes(const Scene& scene, std::span<const std::uint32_t> items);

    std::array<Vec3, kMaxDepth + 2> mStep{}; // cell size per level (m)
    std::vector<OctreeNode> mNodes;
    std::vector<std::uint32_t> mSlots;
};

} // namespace hapto
