#include "hapto/index/Overlap.h"

#include <algorithm>
#include <cmath>

namespace hapto {
namespace {

double maxAbs(const Vec3& v) {
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}
double sum(const Vec3& v) {
    return v.x + v.y + v.z;
}

// The separating-axis test proper, in A's frame: R[i][j] = A_i . B_j, t = B.c - A.c in A's
// frame, tol in metres. Returns true when some axis separates the boxes by more than tol.
bool separated(const Vec3& a, const Vec3& b, const double (&r)[3][3], const Vec3& t, double tol) {
    double absR[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            absR[i][j] = std::abs(r[i][j]) + kParallelEpsilon;
        }
    }
    // A's face axes.
    for (int i = 0; i < 3; ++i) {
        const double rb = b[0] * absR[i][0] + b[1] * absR[i][1] + b[2] * absR[i][2];
        if (std::abs(t[i]) > a[i] + rb + tol) {
            return true;
        }
    }
    // B's face axes.
    for (int j = 0; j < 3; ++j) {
        const double ra = a[0] * absR[0][j] + a[1] * absR[1][j] + a[2] * absR[2][j];
        const double tl = t[0] * r[0][j] + t[1] * r[1][j] + t[2] * r[2][j];
        if (std::abs(tl) > ra + b[j] + tol) {
            return true;
        }
    }
    // The nine edge-edge axes A_i x B_j (not normalised: |L| <= 1, so tol only grows).
    for (int i = 0; i < 3; ++i) {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
        for (int j = 0; j < 3; ++j) {
            const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            const double ra = a[i1] * absR[i2][j] + a[i2] * absR[i1][j];
            const double rb = b[j1] * absR[i][j2] + b[j2] * absR[i][j1];
            const double tl = t[i2] * r[i1][j] - t[i1] * r[i2][j];
            if (std::abs(tl) > ra + rb + tol) {
                return true;
            }
        }
    }
    return false;
}

double tolerance(double scaleA, double scaleB) {
    return kOverlapTolerance * (scaleA + scaleB);
}

double cellScale(const Aabb& cell) {
    return maxAbs(cell.center()) +
           std::max({cell.max.x - cell.min.x, cell.max.y - cell.min.y, cell.max.z - cell.min.z});
}

} // namespace

OverlapShape OverlapShape::of(const SceneObject& object) {
    OverlapShape s;
    s.obb = object.obb();
    s.sphere = object.shape == Shape::Sphere;
    s.aabb = s.sphere ? object.aabb() : s.obb.aabb();
    s.radius = s.sphere ? object.halfExtents.x : 0.0;
    s.scale = maxAbs(object.center) +
              std::max({object.halfExtents.x, object.halfExtents.y, object.halfExtents.z});
    return s;
}

bool overlapsObbObb(const Obb& a, const Obb& b) noexcept {
    double r[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            r[i][j] = glm::dot(a.axes[i], b.axes[j]);
        }
    }
    const Vec3 d = b.center - a.center;
    const Vec3 t(glm::dot(d, a.axes[0]), glm::dot(d, a.axes[1]), glm::dot(d, a.axes[2]));
    const double tol =
        tolerance(maxAbs(a.center) + sum(a.halfExtents), maxAbs(b.center) + sum(b.halfExtents));
    return !separated(a.halfExtents, b.halfExtents, r, t, tol);
}

bool overlapsObbAabb(const Obb& box, const Aabb& cell) noexcept {
    // A is the cell (identity axes), so R[i][j] is component i of the box's axis j.
    double r[3][3];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            r[i][j] = box.axes[j][i];
        }
    }
    const Vec3 t = box.center - cell.center();
    const double tol = tolerance(maxAbs(box.center) + sum(box.halfExtents), cellScale(cell));
    return !separated(cell.halfExtents(), box.halfExtents, r, t, tol);
}

bool overlapsSphereAabb(const Vec3& center, double radius, const Aabb& cell) noexcept {
    const Vec3 d = glm::max(glm::max(cell.min - center, center - cell.max), Vec3(0.0));
    const double reach = radius + tolerance(maxAbs(center) + radius, cellScale(cell));
    return glm::dot(d, d) <= reach * reach;
}

bool overlapsAabbAabb(const Aabb& a, const Aabb& b) noexcept {
    const double tol = tolerance(cellScale(a), cellScale(b));
    return a.min.x <= b.max.x + tol && a.max.x + tol >= b.min.x && a.min.y <= b.max.y + tol &&
           a.max.y + tol >= b.min.y && a.min.z <= b.max.z + tol && a.max.z + tol >= b.min.z;
}

OverlapCell OverlapCell::of(const Aabb& box) noexcept {
    return {box, cellScale(box)};
}

double overlapTolerance(const OverlapShape& shape, const OverlapCell& cell) noexcept {
    return tolerance(shape.scale, cell.scale);
}

bool overlaps(const OverlapShape& shape, const Aabb& cell, OverlapMode mode) noexcept {
    return overlaps(shape, OverlapCell::of(cell), mode);
}

bool overlaps(const OverlapShape& shape, const OverlapCell& prepared, OverlapMode mode) noexcept {
    const double tol = tolerance(shape.scale, prepared.scale);
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
