#pragma once
/// The query interface shared by every spatial index, and the function that builds one.
///
/// An index is built once on a control thread and never changes afterwards: every query is
/// `const`, allocates nothing, and is safe from any number of threads at once. Queries hand
/// back candidate *items* (Scene.h: the slot of a box or sphere, or `kTriangleItemBit | n` for
/// a mesh triangle; `scene.objectSlotOf(item)` names the object), never copies.

#include "hapto/index/IndexSpec.h"
#include "hapto/index/IndexStats.h"
#include "hapto/io/InputError.h"
#include "hapto/scenes/Scene.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace hapto {

/// How a cursor finds the leaf of a point that left its cached leaf.
enum class CursorStrategy : std::uint8_t {
    FromRoot,      ///< Descend from the root every time (no cache).
    Climb,         ///< Climb from the cached leaf to the first ancestor holding the point.
    NeighbourLinks ///< Cross faces through neighbour links (falls back to Climb when that is
                   ///< no shorter); the default.
};

/// "No leaf": the result of a point outside the bounds, or an unbound cursor.
inline constexpr std::uint32_t kNoLeaf = 0xFFFFFFFFu;

/// The answer to "which objects may touch this point".
struct LocateResult {
    std::span<const std::uint32_t> candidates; ///< The leaf's items, ascending.
    std::uint32_t leaf = kNoLeaf;              ///< Octree node, grid cell, or 0 (brute force).
    std::uint32_t steps = 0; ///< Links followed (parent, child, neighbour) to get there.
    bool outside = true;     ///< The point is outside the bounds: the candidates are then the
                             ///< items that reach outside them (SpatialIndex::outsideObjects;
                             ///< BruteForce: every item, as everywhere).
};

/// The leaves ahead of a moving point, brought into the cache one dependent read a step
/// (SpatialIndex::streamAhead): a step reads only what the step before prefetched, so no
/// step waits on memory. One per point followed (a HapticTick keeps one for its proxy).
/// [servo]
struct LeafStream {
    /// Leaves the stream goes on past the first across the face ahead (two:
    /// docs/results/tick-motions.md, "The leaves ahead").
    static constexpr std::uint8_t kFurther = 2;
    /// The node (grid: cell) whose line the last step prefetched; kNoLeaf: none.
    std::uint32_t pending = kNoLeaf;
    /// The item list of the leaf the last step reached, which it prefetched (empty: none).
    std::span<const std::uint32_t> items{};
    std::uint32_t from = kNoLeaf; ///< The leaf whose neighbour ahead was taken.
    std::uint8_t face = 0;        ///< The face crossed: 2 axis + 1 upward.
    std::uint8_t further = 0;     ///< Leaves still to go past the one pending.

    /// The face ahead of a point moving along `direction`: on the axis it moves most along
    /// (ties: the first), 2 axis + 1 when upward; -1 when it does not move (or NaN).
    static int faceAhead(const Vec3& direction) noexcept;
};

/// Asks the cache for the line of the first and of the last of `bytes` bytes at `at` (all of
/// a node or a cell's range, which may straddle two lines; a long item list's ends). A hint.
/// [servo]
inline void prefetchEnds(const void* at, std::size_t bytes) noexcept {
    const char* p = static_cast<const char*>(at);
    __builtin_prefetch(p);
    __builtin_prefetch(p + (bytes - 1));
}

/// Asks the cache for both ends of a leaf's item list (prefetchEnds); nothing for an empty one.
/// A hint. [servo]
inline void prefetchItems(std::span<const std::uint32_t> items) noexcept {
    if (!items.empty()) {
        prefetchEnds(items.data(), items.size_bytes());
    }
}

/// An index that would need more memory than its spec allows (IndexSpec::maxBytes). Bad input:
/// the `hapto` command exits with code 2; the message names the estimate, the limit and
/// `--max-index-mb`.
class IndexTooLargeError : public InputError {
public:
    /// The message names the index, its estimated size and the limit.
    using InputError::InputError;
};

/// A spatial index over a static scene: immutable after build, all queries const.
class SpatialIndex {
public:
    virtual ~SpatialIndex();
    SpatialIndex(const SpatialIndex&) = delete;
    SpatialIndex& operator=(const SpatialIndex&) = delete;

    /// What was built. [any thread]
    const IndexSpec& spec() const noexcept { return mSpec; }
    /// Size, shape and build time. [any thread]
    const IndexStats& stats() const noexcept { return mStats; }
    /// The partitioned box, closed: the scene bounds, upper faces moved out by at most a few
    /// ulps so that cell boundaries are exact (m). [any thread]
    const Aabb& bounds() const noexcept { return mBounds; }
    /// Number of items it holds: the scene's indexed items (boxes, spheres and mesh triangles;
    /// Scene::isIndexed) when it was built. [any thread]
    std::uint32_t itemCount() const noexcept { return mItemCount; }
    /// True when the point lies in the closed bounds (false for NaN). [servo]
    bool inBounds(const Vec3& point) const noexcept;
    /// The items (ascending) whose bounds reach outside the index's bounds, found at build
    /// time: the candidates of every point outside the bounds, so a hand inside the part of an
    /// object that sticks out still feels it. [servo]
    std::span<const std::uint32_t> outsideObjects() const noexcept { return mOutside; }

    /// The leaf holding the point, found from the root. [servo]
    virtual LocateResult locate(const Vec3& point) const noexcept = 0;
    /// The leaf holding the point, found from a previous leaf with a strategy. [servo]
    virtual LocateResult locateFrom(std::uint32_t leaf, const Vec3& point,
                                    CursorStrategy strategy) const noexcept = 0;
    /// The items of a leaf, ascending. [servo]
    virtual std::span<const std::uint32_t> leafObjects(std::uint32_t leaf) const noexcept = 0;
    /// The closed box of a leaf (m). A point belongs to the leaf whose box holds it, with
    /// ties on shared faces going to the upper leaf. [servo]
    virtual Aabb leafBounds(std::uint32_t leaf) const noexcept = 0;
    /// One step of `stream` for a point at `point` in `leaf` moving along `direction`: the
    /// node the last step prefetched is read (a leaf: its items prefetched and handed out in
    /// stream.items, and the leaf beyond it prefetched while stream.further says so; an inner
    /// node: its child on the point's side prefetched), and when `leaf` is new to the stream,
    /// its neighbour across the face ahead on the axis the point moves most along is
    /// prefetched instead. Hints only: no result depends on it. Default: nothing (brute force:
    /// one leaf). [servo]
    virtual void streamAhead(LeafStream& stream, std::uint32_t leaf, const Vec3& point,
                             const Vec3& direction) const noexcept;

    /// Called by visitLeaves with the caller's context and a leaf; returns false to stop.
    using LeafVisitor = bool (*)(void* context, std::uint32_t leaf);
    /// The box query (the dynamics' broad phase): calls `visit` once for every leaf whose
    /// closed box overlaps the closed `box` (m), so every item whose shape reaches into the
    /// part of `box` inside the bounds is among those leaves' leafObjects() (an item may come
    /// in several leaves: callers that need each once deduplicate). The part outside the
    /// bounds is answered by outsideObjects() when reachesOutside(box). Octree: depth-first
    /// from the root with a fixed stack; grid: the cell range, x fastest; brute force: its one
    /// leaf for any non-empty box. Returns false when `visit` stopped the walk. An empty or
    /// NaN box visits nothing. Allocates nothing. [servo]
    virtual bool visitLeaves(const Aabb& box, LeafVisitor visit, void* context) const noexcept = 0;
    /// The same with a callable `bool f(std::uint32_t leaf)` (return false to stop). [servo]
    template <class F> bool visitLeavesWith(const Aabb& box, F& f) const noexcept {
        return visitLeaves(
            box, [](void* c, std::uint32_t leaf) { return (*static_cast<F*>(c))(leaf); }, &f);
    }
    /// True when the closed `box` reaches outside the closed bounds: the items found there
    /// are outsideObjects(). False for an empty or NaN box. [servo]
    bool reachesOutside(const Aabb& box) const noexcept;

protected:
    /// Sets the spec, the bounds and the item count. [control]
    SpatialIndex(const IndexSpec& spec, const Aabb& bounds, std::uint32_t itemCount);

    /// Fills outsideObjects() from the scene's indexed items (ascending), after the bounds
    /// are final. [control]
    void recordOutsideObjects(const Scene& scene, std::span<const std::uint32_t> items);
    /// True when min <= max on every axis (false for an empty box or a NaN). [servo]
    static bool isQueryBox(const Aabb& box) noexcept {
        return box.min.x <= box.max.x && box.min.y <= box.max.y && box.min.z <= box.max.z;
    }
    /// The answer for a point outside the bounds: outsideObjects(), no leaf. [servo]
    LocateResult outsideResult() const noexcept { return {mOutside, kNoLeaf, 0, true}; }

    IndexStats mStats; ///< Filled by the builder.

private:
    std::vector<std::uint32_t> mOutside; // items reaching outside the bounds, ascending
    IndexSpec mSpec;
    Aabb mBounds;
    std::uint32_t mItemCount;
};

/// Builds the index a spec asks for (in parallel, with TBB). Throws InputError for a spec
/// that cannot be built (e.g. an octree that would need too many nodes), and
/// IndexTooLargeError, before allocating it, for one that would need more than spec.maxBytes
/// (estimateIndexMemory's floor; an octree checks again before each level's allocations).
/// [control]
std::unique_ptr<SpatialIndex> buildIndex(const Scene& scene, const IndexSpec& spec);

/// What an index build needs at its peak (bytes), bounded from both sides without building.
struct IndexMemoryEstimate {
    /// The build holds at least this much: buildIndex refuses a spec whose floor passes
    /// spec.maxBytes before building anything. Brute force and grid: their exact peak.
    std::uint64_t atLeastBytes = 0;
    /// The build holds at most this much (its peak accounting, index/src/IndexMemory.h).
    /// Brute force and grid: the same as atLeastBytes.
    std::uint64_t atMostBytes = 0;
    /// Octree: nodes the tree surely has (a floor); 0 for the others.
    std::uint64_t nodesAtLeast = 0;
};

/// The memory a build of this index needs at its peak, bounded without building it: brute
/// force exactly; the grid from its cells and, per item, the cells its AABB reaches (what the
/// build allocates: the OBB and triangle tests only remove pairs later); the octree from two
/// cell counts per item and level (index/src/IndexMemory.cpp's note): a floor from the cells
/// surely listing more than M items, a ceiling from the cells items reach; the floor is
/// counted only when the ceiling passes spec.maxBytes (otherwise it is the items' share alone,
/// still a floor). Octree::build checks spec.maxBytes again before allocating each level.
/// O(items * levels); no memory per node, and per item (at most 2^20 of them) 32 bytes only
/// while counting a floor. [control]
IndexMemoryEstimate estimateIndexMemory(const Scene& scene, const IndexSpec& spec);

/// estimateIndexMemory(scene, spec).atMostBytes: no build of this index holds more. [control]
std::uint64_t estimateIndexBytes(const Scene& scene, const IndexSpec& spec);

/// The bounds an index partitions: the scene's, each upper face moved out by the few ulps
/// needed so that min + (max - min) >= max in floating point. [any thread]
Aabb partitionBounds(const Aabb& sceneBounds);

} // namespace hapto
