#include "hapto/index/SpatialIndex.h"

#include "hapto/index/BruteForce.h"
#include "hapto/index/Octree.h"
#include "hapto/index/UniformGrid.h"

#include <cmath>
#include <limits>

namespace hapto {

SpatialIndex::SpatialIndex(const IndexSpec& spec, const Aabb& bounds, std::uint32_t objectCount)
    : mSpec(spec), mBounds(bounds), mObjectCount(objectCount) {
    mStats.index = spec.toString();
    mStats.objects = objectCount;
}

SpatialIndex::~SpatialIndex() = default;

bool SpatialIndex::inBounds(const Vec3& p) const noexcept {
    return p.x >= mBounds.min.x && p.x <= mBounds.max.x && p.y >= mBounds.min.y &&
           p.y <= mBounds.max.y && p.z >= mBounds.min.z && p.z <= mBounds.max.z;
}

Aabb partitionBounds(const Aabb& sceneBounds) {
    Aabb b = sceneBounds;
    for (int a = 0; a < 3; ++a) {
        double size = sceneBounds.max[a] - sceneBounds.min[a];
        while (sceneBounds.min[a] + size < sceneBounds.max[a]) {
            size = std::nextafter(size, std::numeric_limits<double>::infinity());
        }
        b.max[a] = sceneBounds.min[a] + size;
    }
    return b;
}

std::unique_ptr<SpatialIndex> buildIndex(const Scene& scene, const IndexSpec& spec) {
    switch (spec.kind) {
    case IndexSpec::Kind::BruteForce:
        return BruteForce::build(scene, spec);
    case IndexSpec::Kind::Grid:
        return UniformGrid::build(scene, spec);
    case IndexSpec::Kind::Octree:
        return Octree::build(scene, spec);
    }
    return BruteForce::build(scene, spec);
}

} // namespace hapto
