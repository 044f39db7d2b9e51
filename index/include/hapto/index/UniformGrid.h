#pragma once
/// The paper's uniform n x n x n grid (section 2.1): O(1) lookup, each cell's items one run.

#include "hapto/index/SpatialIndex.h"

#include <array>
#include <memory>
#include <vector>

namespace hapto {

/// n^3 equal cells over the bounds; each item (a box, a sphere or a mesh triangle) is listed in
/// every cell its bounds overlap.
/// Cell (ix, iy, iz) has id (iz * n + iy) * n + ix and spans [min + i * step, min + (i+1) *
/// step] per axis, computed by that one formula everywhere, so shared faces are exact.
class UniformGrid final : public SpatialIndex {
public:
    /// Builds the grid (TBB inside). [control]
    static std::unique_ptr<UniformGrid> build(const Scene& scene, const IndexSpec& spec);

    /// The cell holding the point, O(1). [servo]
    LocateResult locate(const Vec3& point) const noexcept override;
    /// Same as locate (the grid needs no walk). [servo]
    LocateResult locateFrom(std::uint32_t leaf, const Vec3& point,
                            CursorStrategy strategy) const noexcept override;
    /// The items of a cell, ascending. [servo]
    std::span<const std::uint32_t> leafObjects(std::uint32_t cell) const noexcept override;
    /// The closed box of a cell (m). [servo]
    Aabb leafBounds(std::uint32_t cell) const noexcept override;
    /// The cell across the face ahead (its id is arithmetic), its item range, then its items
    /// and the cell beyond (a step each). [servo]
    void streamAhead(LeafStream& stream, std::uint32_t cell, const Vec3& point,
                     const Vec3& direction) const noexcept override;
    /// Every cell of the range `box` covers inside the bounds, x fastest. [servo]
    bool visitLeaves(const Aabb& box, LeafVisitor visit, void* context) const noexcept override;

    /// n, cells per side. [any thread]
    int cellsPerSide() const noexcept { return mN; }
    /// n^3. [any thread]
    std::uint32_t cellCount() const noexcept { return mN * mN * mN; }
    /// The id of cell (ix, iy, iz). [any thread]
    std::uint32_t cellId(std::uint32_t ix, std::uint32_t iy, std::uint32_t iz) const noexcept {
        return (iz * mN + iy) * mN + ix;
    }
    /// The cell index along one axis holding coordinate v (clamped into 0..n-1). [servo]
    std::uint32_t cellIndex(double v, int axis) const noexcept;

private:
    UniformGrid(const IndexSpec& spec, const Aabb& bounds, const Vec3& step, std::uint32_t items);
    /// The cell across face `face` (2 axis + 1 upward) of `cell`, or kNoLeaf at the bounds.
    std::uint32_t across(std::uint32_t cell, int face) const noexcept;
    double coord(std::uint32_t i, int axis) const noexcept {
        return bounds().min[axis] + static_cast<double>(i) * mStep[axis];
    }
    friend class GridBuilder; // build's parts (UniformGrid.cpp)

    std::uint32_t mN;
    Vec3 mStep{0.0};
    Vec3 mInvStep{0.0};
    std::vector<std::uint32_t> mCellStart; // n^3 + 1 offsets into mItems (CSR)
    std::vector<std::uint32_t> mItems;
};

} // namespace hapto
