#include "hapto/index/UniformGrid.h"

#include "BuildTimer.h"
#include "IndexItems.h"
#include "Parallel.h"

#include "hapto/io/InputError.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>

namespace hapto {

UniformGrid::UniformGrid(const IndexSpec& spec, const Aabb& bounds, const Vec3& step,
                         std::uint32_t items)
    : SpatialIndex(spec, bounds, items), mN(static_cast<std::uint32_t>(spec.gridCells)),
      mStep(step), mInvStep(1.0 / step) {}

std::uint32_t UniformGrid::cellIndex(double v, int axis) const noexcept {
    const double t = std::floor((v - bounds().min[axis]) * mInvStep[axis]);
    const double last = static_cast<double>(mN - 1);
    std::uint32_t i = static_cast<std::uint32_t>(t < 0.0 ? 0.0 : t > last ? last : t);
    // The multiplication may be off by an ulp; settle on the formula the cell boxes use.
    if (i > 0 && v < coord(i, axis)) {
        --i;
    } else if (i + 1 < mN && v >= coord(i + 1, axis)) {
        ++i;
    }
    return i;
}

namespace {

// The step per axis that makes cell n - 1 reach the scene's upper face: (max - min) / n,
// nudged up until min + n * step >= max; `bounds` gets its upper faces moved out to there.
Vec3 fitStep(const Aabb& sceneBounds, std::uint32_t n, Aabb& bounds) {
    bounds = sceneBounds;
    Vec3 step(0.0);
    for (int a = 0; a < 3; ++a) {
        step[a] = (sceneBounds.max[a] - sceneBounds.min[a]) / n;
        while (sceneBounds.min[a] + static_cast<double>(n) * step[a] < sceneBounds.max[a]) {
            step[a] = std::nextafter(step[a], std::numeric_limits<double>::infinity());
        }
        bounds.max[a] = sceneBounds.min[a] + static_cast<double>(n) * step[a];
    }
    return step;
}

} // namespace

/// One fill of a grid's cells, a counting sort by cell. In parallel over items: size each
/// item's candidate range (no overlap test), then test its cells once and list the overlapped
/// ones at the item's own offset (plain sequential writes), keeping the count. Then count each
/// cell's items from those lists, and, in item order, place each item at its cells' next free
/// positions, so every cell's run lists its items ascending on any number of threads (no locked
/// instruction per pair: the random stores do not wait for each other). Items are worked on by
/// their position k in `items` (ascending ids). Each pass prepares an item's bounds afresh from
/// the scene's render copy: cheaper than writing and rereading 192 bytes per item. A friend of
/// UniformGrid: it writes the grid's arrays.
class GridBuilder {
public:
    GridBuilder(UniformGrid& grid, const Scene& scene, std::span<const std::uint32_t> items);
    /// Fills the grid's cell offsets and item lists; returns each cell's item count.
    std::vector<std::uint32_t> fill();

private:
    /// Per axis: cell faces, |cell centre| and cell edge, by cell index.
    struct Axis {
        std::vector<double> coord, absCenter, edge;
    };
    /// An item's candidate cells per axis, kept between the two passes (n <= 256 cells per
    /// side fit a byte).
    struct Range {
        std::uint8_t lo[3], hi[3];
        bool empty;
    };
    static_assert(IndexSpec::kMaxGridCells <= 256);

    Range rangeOf(const OverlapShape& s) const;
    std::uint64_t rangeSize(std::uint32_t k);
    template <class Visit> void forEachCell(std::uint32_t k, Visit&& visit) const;
    std::uint64_t listPairs();
    template <class Visit> void forEachBandPair(Visit&& visit) const;

    UniformGrid& mGrid;
    const Scene& mScene;
    std::span<const std::uint32_t> mItemIds;
    std::array<Axis, 3> mAxes;
    OverlapCell mWhole;
    std::vector<Range> mRanges;            // per item
    std::vector<std::uint64_t> mPairStart; // per item, + 1: where its cell list starts
    std::vector<std::uint32_t> mPairCell;  // the items' cell lists, back to back
    std::vector<std::uint32_t> mPairCount; // per item: the cells it overlaps
};

// Each cell's box and tolerance scale (OverlapCell::of: aabbScale of the box) come from per-axis
// tables, with the same arithmetic, so the tests see exactly the cells they would otherwise
// build one by one.
GridBuilder::GridBuilder(UniformGrid& grid, const Scene& scene,
                         std::span<const std::uint32_t> items)
    : mGrid(grid), mScene(scene), mItemIds(items), mWhole(OverlapCell::of(grid.bounds())),
      mRanges(items.size()) {
    const std::uint32_t n = grid.mN;
    for (int a = 0; a < 3; ++a) {
        Axis& ax = mAxes[a];
        ax.coord.resize(std::size_t(n) + 1);
        for (std::uint32_t i = 0; i <= n; ++i) {
            ax.coord[i] = grid.coord(i, a);
        }
        ax.absCenter.resize(n);
        ax.edge.resize(n);
        for (std::uint32_t i = 0; i < n; ++i) {
            ax.absCenter[i] = std::abs(0.5 * (ax.coord[i] + ax.coord[i + 1]));
            ax.edge[i] = ax.coord[i + 1] - ax.coord[i];
        }
    }
}

// The candidate cell range of an item: the cells its AABB reaches, widened by the overlap
// tolerance, plus the lower neighbour when that touches a cell's lower face exactly (closed
// cells share faces); overlaps() then decides cell by cell.
GridBuilder::Range GridBuilder::rangeOf(const OverlapShape& s) const {
    Range r{};
    r.empty = !overlapsAabbAabb(s.aabb, mGrid.bounds());
    const double tol = overlapTolerance(s, mWhole);
    for (int a = 0; a < 3 && !r.empty; ++a) {
        const double lo = s.aabb.min[a] - tol, hi = s.aabb.max[a] + tol;
        std::uint32_t first = mGrid.cellIndex(lo, a);
        if (first > 0 && lo <= mAxes[a].coord[first]) {
            --first;
        }
        r.lo[a] = static_cast<std::uint8_t>(first);
        r.hi[a] = static_cast<std::uint8_t>(mGrid.cellIndex(hi, a));
    }
    return r;
}

// Records item k's range; returns how many cells it spans.
std::uint64_t GridBuilder::rangeSize(std::uint32_t k) {
    const Range r = mRanges[k] = rangeOf(OverlapShape::of(mScene, mItemIds[k]));
    return r.empty ? 0
                   : std::uint64_t(r.hi[0] - r.lo[0] + 1) * std::uint64_t(r.hi[1] - r.lo[1] + 1) *
                         std::uint64_t(r.hi[2] - r.lo[2] + 1);
}

// Calls visit(cell id) for each cell of item k's range that the item overlaps, in id order.
template <class Visit> void GridBuilder::forEachCell(std::uint32_t k, Visit&& visit) const {
    const Range r = mRanges[k];
    if (r.empty) {
        return;
    }
    const OverlapShape s = OverlapShape::of(mScene, mItemIds[k]);
    const Axis &ax = mAxes[0], &ay = mAxes[1], &az = mAxes[2];
    for (std::uint32_t z = r.lo[2]; z <= r.hi[2]; ++z) {
        for (std::uint32_t y = r.lo[1]; y <= r.hi[1]; ++y) {
            for (std::uint32_t x = r.lo[0]; x <= r.hi[0]; ++x) {
                const OverlapCell cell{
                    {{ax.coord[x], ay.coord[y], az.coord[z]},
                     {ax.coord[x + 1], ay.coord[y + 1], az.coord[z + 1]}},
                    std::max({ax.absCenter[x], ay.absCenter[y], az.absCenter[z]}) +
                        std::max({ax.edge[x], ay.edge[y], az.edge[z]})};
                if (overlaps(s, cell, mGrid.spec().mode)) {
                    visit(mGrid.cellId(x, y, z));
                }
            }
        }
    }
}

// The two parallel passes over items: range sizes, then each item's overlapped cells at its own
// offset. Returns the number of item-cell pairs, refused (InputError) past 32-bit offsets.
std::uint64_t GridBuilder::listPairs() {
    const std::size_t count = mItemIds.size();
    mPairStart.assign(count + 1, 0);
    parallel::forEach(0, count, 256, [&](std::size_t i) {
        mPairStart[i + 1] = rangeSize(static_cast<std::uint32_t>(i));
    });
    for (std::size_t i = 0; i < count; ++i) {
        mPairStart[i + 1] += mPairStart[i];
    }
    mPairCell.resize(mPairStart[count]);
    mPairCount.assign(count, 0);
    parallel::forEach(0, count, 256, [&](std::size_t i) {
        std::uint32_t* out = mPairCell.data() + mPairStart[i];
        std::uint32_t listed = 0;
        forEachCell(static_cast<std::uint32_t>(i),
                    [&](std::uint32_t cell) { out[listed++] = cell; });
        mPairCount[i] = listed;
    });
    std::uint64_t pairs = 0;
    for (std::size_t i = 0; i < count; ++i) {
        pairs += mPairCount[i];
    }
    if (pairs >= std::numeric_limits<std::uint32_t>::max()) {
        throw InputError("grid index " + mGrid.spec().toString() + ": " + std::to_string(pairs) +
                         " item-cell pairs do not fit 32-bit offsets; use fewer cells");
    }
    return pairs;
}

// Calls visit(item position, cell) for every listed pair. The cells are split into bands, one
// per thread; each band's thread reads every item's list in item order and handles only its
// own cells' pairs, so the lists stay ascending and no two threads write the same counter or
// slot.
template <class Visit> void GridBuilder::forEachBandPair(Visit&& visit) const {
    const std::size_t cells = mGrid.cellCount(), count = mItemIds.size();
    const std::size_t bands = std::max(1u, std::thread::hardware_concurrency());
    const std::size_t bandCells = (cells + bands - 1) / bands;
    parallel::forEach(0, bands, 1, [&](std::size_t b) {
        const std::size_t lo = b * bandCells, hi = std::min(cells, lo + bandCells);
        for (std::size_t i = 0; i < count; ++i) {
            for (std::uint64_t p = mPairStart[i]; p < mPairStart[i] + mPairCount[i]; ++p) {
                if (mPairCell[p] >= lo && mPairCell[p] < hi) {
                    visit(i, mPairCell[p]);
                }
            }
        }
    });
}

std::vector<std::uint32_t> GridBuilder::fill() {
    const std::size_t cells = mGrid.cellCount();
    std::vector<std::uint32_t> fill(cells, 0);
    const std::uint64_t pairs = listPairs();
    forEachBandPair([&](std::size_t, std::uint32_t cell) { ++fill[cell]; });
    std::vector<std::uint32_t>& cellStart = mGrid.mCellStart;
    cellStart.assign(cells + 1, 0);
    for (std::size_t c = 0; c < cells; ++c) {
        cellStart[c + 1] = cellStart[c] + fill[c];
        fill[c] = cellStart[c]; // from here on: the cell's next free position
    }
    mGrid.mItems.resize(pairs);
    std::uint32_t* const placed = mGrid.mItems.data();
    forEachBandPair([&](std::size_t i, std::uint32_t cell) { placed[fill[cell]++] = mItemIds[i]; });
    for (std::size_t c = 0; c < cells; ++c) {
        fill[c] = cellStart[c + 1] - cellStart[c];
    }
    return fill;
}

std::unique_ptr<UniformGrid> UniformGrid::build(const Scene& scene, const IndexSpec& spec) {
    if (spec.kind != IndexSpec::Kind::Grid || spec.gridCells < 1 ||
        spec.gridCells > IndexSpec::kMaxGridCells) {
        throw InputError("grid index: need 1 <= n <= " + std::to_string(IndexSpec::kMaxGridCells) +
                         ", got " + spec.toString());
    }
    const BuildTimer timer;
    // Cell i spans [min + i * step, min + (i + 1) * step]; the index's bounds end where cell
    // n - 1 does, at or just past the scene's upper face.
    Aabb bounds;
    const Vec3 step = fitStep(scene.bounds(), static_cast<std::uint32_t>(spec.gridCells), bounds);
    const std::vector<std::uint32_t> items = detail::indexedItems(scene);
    const std::uint32_t count = static_cast<std::uint32_t>(items.size());
    std::unique_ptr<UniformGrid> grid(new UniformGrid(spec, bounds, step, count));
    grid->recordOutsideObjects(scene, items);
    const std::vector<std::uint32_t> perCell = GridBuilder(*grid, scene, items).fill();

    IndexStats& st = grid->mStats;
    st.nodes = grid->cellCount();
    st.recordLeaves(perCell);
    st.bytes = (grid->mCellStart.size() + grid->mItems.size() + grid->outsideObjects().size()) *
               sizeof(std::uint32_t);
    st.bytesPerObject = count == 0 ? 0.0 : static_cast<double>(st.bytes) / count;
    timer.finish(st);
    return grid;
}

LocateResult UniformGrid::locate(const Vec3& p) const noexcept {
    if (!inBounds(p)) {
        return outsideResult();
    }
    const std::uint32_t id = cellId(cellIndex(p.x, 0), cellIndex(p.y, 1), cellIndex(p.z, 2));
    return {leafObjects(id), id, 0, false};
}

LocateResult UniformGrid::locateFrom(std::uint32_t, const Vec3& p, CursorStrategy) const noexcept {
    return locate(p);
}

std::span<const std::uint32_t> UniformGrid::leafObjects(std::uint32_t cell) const noexcept {
    return {mItems.data() + mCellStart[cell], mCellStart[cell + 1] - mCellStart[cell]};
}

std::uint32_t UniformGrid::across(std::uint32_t cell, int face) const noexcept {
    const int axis = face / 2;
    const std::uint32_t stride = axis == 0 ? 1 : axis == 1 ? mN : mN * mN;
    const std::uint32_t at = (cell / stride) % mN;
    if (face % 2 == 1) {
        return at + 1 < mN ? cell + stride : kNoLeaf;
    }
    return at > 0 ? cell - stride : kNoLeaf;
}

void UniformGrid::streamAhead(LeafStream& s, std::uint32_t cell, const Vec3&,
                              const Vec3& direction) const noexcept {
    // The pending cell's range was prefetched the step before: its items are prefetched and
    // handed out, and the cell beyond is prefetched while the stream goes further.
    s.items = {};
    if (s.pending != kNoLeaf) {
        s.items = leafObjects(s.pending);
        prefetchItems(s.items);
        s.pending = s.further > 0 ? across(s.pending, s.face) : kNoLeaf;
        s.further -= s.further > 0 ? 1 : 0;
        if (s.pending != kNoLeaf) {
            prefetchEnds(&mCellStart[s.pending], 2 * sizeof(std::uint32_t));
        }
    }
    const int face = LeafStream::faceAhead(direction);
    if (cell == s.from || cell >= cellCount() || face < 0) {
        return;
    }
    s.from = cell;
    s.pending = across(cell, face);
    s.face = static_cast<std::uint8_t>(face);
    s.further = LeafStream::kFurther;
    if (s.pending != kNoLeaf) {
        prefetchEnds(&mCellStart[s.pending], 2 * sizeof(std::uint32_t));
    }
}

Aabb UniformGrid::leafBounds(std::uint32_t cell) const noexcept {
    const std::uint32_t x = cell % mN, y = (cell / mN) % mN, z = cell / (mN * mN);
    return {{coord(x, 0), coord(y, 1), coord(z, 2)},
            {coord(x + 1, 0), coord(y + 1, 1), coord(z + 1, 2)}};
}

bool UniformGrid::visitLeaves(const Aabb& box, LeafVisitor visit, void* context) const noexcept {
    if (!isQueryBox(box) || !box.overlaps(bounds())) {
        return true;
    }
    // cellIndex clamps into 0..n-1 and settles on the cell boxes' own formula.
    std::uint32_t lo[3];
    std::uint32_t hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = cellIndex(box.min[a], a);
        hi[a] = cellIndex(box.max[a], a);
    }
    for (std::uint32_t z = lo[2]; z <= hi[2]; ++z) {
        for (std::uint32_t y = lo[1]; y <= hi[1]; ++y) {
            for (std::uint32_t x = lo[0]; x <= hi[0]; ++x) {
                if (!visit(context, cellId(x, y, z))) {
                    return false;
                }
            }
        }
    }
    return true;
}

} // namespace hapto
