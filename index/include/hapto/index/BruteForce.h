#pragma once
/// The e-Touch "standard" renderer as an index: every item is a candidate everywhere.

#include "hapto/index/SpatialIndex.h"

#include <memory>
#include <vector>

namespace hapto {

/// One leaf, the whole bounds, holding every indexed item (boxes, spheres, mesh triangles).
class BruteForce final : public SpatialIndex {
public:
    /// Builds it (a list of all indexed items). [control]
    static std::unique_ptr<BruteForce> build(const Scene& scene, const IndexSpec& spec);

    /// Every item, for any point in the bounds. [servo]
    LocateResult locate(const Vec3& point) const noexcept override;
    /// Same as locate. [servo]
    LocateResult locateFrom(std::uint32_t leaf, const Vec3& point,
                            CursorStrategy strategy) const noexcept override;
    /// Every item (leaf 0). [servo]
    std::span<const std::uint32_t> leafObjects(std::uint32_t leaf) const noexcept override;
    /// The bounds (leaf 0). [servo]
    Aabb leafBounds(std::uint32_t leaf) const noexcept override;
    /// Its one leaf, for any non-empty box. [servo]
    bool visitLeaves(const Aabb& box, LeafVisitor visit, void* context) const noexcept override;

private:
    BruteForce(const IndexSpec& spec, const Scene& scene, std::vector<std::uint32_t> items);
    std::vector<std::uint32_t> mItems;
};

} // namespace hapto
