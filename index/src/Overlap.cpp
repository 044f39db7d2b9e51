#include "hapto/index/Overlap.h"

#include <algorithm>
#include <cmath>

namespace hapto {

OverlapShape OverlapShape::of(const SceneObject& object) {
    OverlapShape s;
    s.obb = object.obb();
    s.sphere = object.shape == Shape::Sphere;
    s.aabb = s.sphere ? object.aabb() : s.obb.aabb();
    s.radius = s.sphere ? object.halfExtents.x : 0.0;
    s.scale = maxAbsComponent(object.center) +
              std::max({object.halfExtents.x, object.halfExtents.y, object.halfExtents.z});
    return s;
}

OverlapCell OverlapCell::of(const Aabb& box) noexcept {
    return {box, aabbScale(box)};
}

double overlapTolerance(const OverlapShape& shape, const OverlapCell& cell) noexcept {
    return overlapToleranceFor(shape.scale, cell.scale);
}

bool overlaps(const OverlapShape& shape, const Aabb& cell, OverlapMode mode) noexcept {
    return overlaps(shape, OverlapCell::of(cell), mode);
}

bool overlaps(const OverlapShape& shape, const OverlapCell& prepared, OverlapMode mode) noexcept {
    const double tol = overlapToleranceFor(shape.scale, prepared.scale);
    const Aabb& a = shape.aabb;
    const Aabb& cell = prepared.box;
    if (!(a.min.x <= cell.max.x + tol && a.max.x + tol >= cell.min.x &&
          a.min.y <= cell.max.y + tol && a.max.y + tol >= cell.min.y &&
          a.min.z <= cell.max.z + tol && a.max.z + tol >= cell.min.z)) {
        return false;
    }
    if (mode == OverlapMode::Aabb) {
        return true;
    }
    // The centre in the cell, or the AABB inside it: an overlap for sure.
    const Vec3& c = shape.obb.center;
    if ((c.x >= cell.min.x && c.x <= cell.max.x && c.y >= cell.min.y && c.y <= cell.max.y &&
         c.z >= cell.min.z && c.z <= cell.max.z) ||
        (a.min.x >= cell.min.x && a.max.x <= cell.max.x && a.min.y >= cell.min.y &&
         a.max.y <= cell.max.y && a.min.z >= cell.min.z && a.max.z <= cell.max.z)) {
        return true;
    }
    return shape.sphere ? overlapsSphereAabb(shape.obb.center, shape.radius, cell)
                        : overlapsObbAabb(shape.obb, cell);
}

} // namespace hapto
