#pragma once
/// A per-thread cursor into a spatial index that remembers the leaf it found last.
///
/// Design note. The idea: a haptic pointer moves at most a millimetre or so per servo tick,
/// so it nearly always stays in the leaf it was in, and otherwise moves to a neighbour. The
/// cursor keeps that leaf's box (lo, hiOpen) in its own cache line: the common case is six
/// compares. When the point has left, the index is asked to walk from the old leaf
/// (`SpatialIndex::locateFrom`): through neighbour links across faces, then down to a leaf.
/// Invariant: after every locate, the cached leaf is exactly the leaf a fresh locate from the
/// root gives (same half-open convention: ties on a shared face go to the upper leaf).
/// Cost: O(1) while inside the leaf; O(1) links plus the descent into a finer neighbour when
/// crossing a face; never more steps than climbing to the common ancestor. Why: crossing a
/// faces (one per axis on which the point is in the next leaf-sized cell) lands on a node N
/// that holds the point but not the old leaf A, so N lies strictly below the common ancestor
/// C, and links cost a + depth(B) - depth(N) <= a - 1 + depth(B) - depth(C) while climbing
/// costs k + depth(B) - depth(C) with k = depth(A) - depth(C) >= 1. So links win for a <= 2,
/// and for a = 3 when k >= 2; otherwise (or for longer jumps) the octree climbs.

#include "hapto/index/SpatialIndex.h"

#include <cstdint>
#include <span>

namespace hapto {

/// What a walk along a segment found (Cursor::firstLeafNotIn): the first leaf on the way that
/// is not listed, if any.
struct SegmentWalk {
    LocateResult at; ///< That leaf (at.leaf == kNoLeaf: every leaf on the way is listed).
    /// Where on the segment that leaf begins (0 at its start, 1 at its end); 1 when none does.
    double t = 1.0;
    /// The walk stopped before the end without knowing (more than Cursor::kMaxWalkLeaves
    /// leaves on one segment, which only rounding that keeps finding the same face could
    /// make): the segment counts as not covered.
    bool unknown = false;
    /// The listed leaf box the segment's end lies in, when the walk got there through the
    /// leaves (empty otherwise: an unlisted leaf, outside the bounds, a zero-length segment or
    /// an end on a leaf's face). A later segment inside it (a box is convex) needs no walk.
    Aabb endBox{Vec3(1.0), Vec3(-1.0)};
    /// Every leaf the segment passes through inside the bounds is listed. [any thread]
    bool covered() const noexcept { return at.leaf == kNoLeaf && !unknown; }
};

/// A per-thread, heap-free cursor caching its current leaf (one 64-byte cache line).
class alignas(64) Cursor {
public:
    /// An unbound cursor: locate returns "outside". [any thread]
    Cursor() noexcept;
    /// A cursor over an index (which must outlive it). [any thread]
    explicit Cursor(const SpatialIndex& index,
                    CursorStrategy strategy = CursorStrategy::NeighbourLinks) noexcept;

    /// Rebinds to another index (the world snapshot changed) and forgets the leaf; keeps the
    /// strategy. No allocation. [servo]
    void reset(const SpatialIndex& index) noexcept;
    /// The leaf holding the point and its candidates; for a point outside the bounds,
    /// "outside" with the objects that reach outside them as candidates (the cached leaf is
    /// kept, so the cursor recovers when the point comes back). [servo]
    LocateResult locate(const Vec3& point) noexcept;

    /// Changes the strategy used when the point leaves the cached leaf. [servo]
    void setStrategy(CursorStrategy strategy) noexcept { mStrategy = strategy; }
    /// The strategy. [servo]
    CursorStrategy strategy() const noexcept { return mStrategy; }
    /// The cached leaf, or kNoLeaf. [servo]
    std::uint32_t leaf() const noexcept { return mLeaf; }
    /// The index it is bound to, or nullptr. [servo]
    const SpatialIndex* index() const noexcept { return mIndex; }

    /// The most leaves firstLeafNotIn visits on one segment before it gives up (`unknown`).
    static constexpr int kMaxWalkLeaves = 64;
    /// The first leaf that the segment a -> b (m) passes through and that is not in `listed`,
    /// walking from a leaf to the next where the segment leaves each leaf's box (a nanometre
    /// past that face); none when there is none or the walk leaves the index's bounds (no item
    /// is indexed outside them), `unknown` after kMaxWalkLeaves leaves. The walk moves a copy of
    /// this cursor (best placed near a), so each step crosses to the next leaf by its links,
    /// not from the root; this cursor is unchanged. No allocation. [servo]
    SegmentWalk firstLeafNotIn(const Vec3& a, const Vec3& b,
                               std::span<const std::uint32_t> listed) const noexcept;
    /// The same walk with this cursor as the walker: it is left at the last leaf it located
    /// (the leaf found, or the way's last inside the bounds). A caller that lists each leaf found
    /// and walks on from where the segment enters it (`a + t (b - a)`) with the same walker locates
    /// every leaf of the way once. No allocation. [servo]
    SegmentWalk walkToFirstLeafNotIn(const Vec3& a, const Vec3& b,
                                     std::span<const std::uint32_t> listed) noexcept;

private:
    void forget() noexcept;
    /// The cached leaf's closed box, as leafBounds gives it (after a locate inside the bounds).
    Aabb cachedBox() const noexcept;

    Vec3 mLo{0.0};     // cached leaf box, lower corner (inclusive)
    Vec3 mHiOpen{0.0}; // upper corner (exclusive; nudged up on the bounds' faces)
    const SpatialIndex* mIndex = nullptr;
    std::uint32_t mLeaf = kNoLeaf;
    CursorStrategy mStrategy = CursorStrategy::NeighbourLinks;
};

static_assert(sizeof(Cursor) == 64, "a cursor is exactly one cache line");

} // namespace hapto
