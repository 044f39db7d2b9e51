#pragma once
/// The e-Touch "standard" renderer as an index: every object is a candidate everywhere.

#include "hapto/index/SpatialIndex.h"

#include <memory>
#include <vector>

namespace hapto {

/// One leaf, the whole bounds, holding every object.
class BruteForce final : public SpatialIndex {
public:
    /// Builds it (a list of all slots). [control]
    static std::unique_ptr<BruteForce> build(const Scene& scene, const IndexSpec& spec);

    /// Every object, for any point in the bounds. [servo]
    LocateResult locate(const Vec3& point) const noexcept override;
    /// Same as locate. [servo]
    LocateResult locateFrom(std::uint32_t leaf, const Vec3& point,
                            CursorStrategy strategy) const noexcept override;
    /// Every object (leaf 0). [servo]
    std::span<const std::uint32_t> leafObjects(std::uint32_t leaf) const noexcept override;
    /// The bounds (leaf 0). [servo]
    Aabb leafBounds(std::uint32_t leaf) const noexcept override;

private:
    BruteForce(const IndexSpec& spec, const Scene& scene);
    std::vector<std::uint32_t> mSlots;
};

} // namespace hapto
