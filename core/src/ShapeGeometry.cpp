#include "hapto/core/ShapeGeometry.h"

#include <algorithm>
#include <cmath>

namespace hapto {
namespace {

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

} // namespace

double boxSignedDistance(const Obb& box, const Vec3& p, double inflateM) noexcept {
    const Vec3 q = glm::abs(box.toLocal(p)) - (box.halfExtents + Vec3(inflateM));
    const Vec3 outside = glm::max(q, Vec3(0.0));
    return glm::length(outside) + std::min(std::max({q.x, q.y, q.z}), 0.0);
}

double sphereSignedDistance(const Vec3& center, double radius, const Vec3& p) noexcept {
    return glm::length(p - center) - radius;
}

double boxDistanceOutside(const Obb& box, const Vec3& p, double inflateM) noexcept {
    return boxDistanceOutsideLocal(box.halfExtents, box.toLocal(p), inflateM);
}

bool boxStrictlyContains(const Obb& box, const Vec3& p, double inflateM) noexcept {
    return boxStrictlyContainsLocal(box.halfExtents, box.toLocal(p), inflateM);
}

bool sphereContains(const Vec3& center, double radius, const Vec3& p) noexcept {
    const Vec3 d = p - center;
    return glm::dot(d, d) <= radius * radius;
}

bool sphereStrictlyContains(const Vec3& center, double radius, const Vec3& p) noexcept {
    const Vec3 d = p - center;
    return glm::dot(d, d) < radius * radius;
}

int dominantFaceAxis(const Vec3& local, const Vec3& halfExtents) noexcept {
    int axis = 0;
    double best = -1e300;
    for (int i = 0; i < 3; ++i) {
        const double beyond = std::abs(local[i]) - halfExtents[i];
        if (beyond > best) {
            best = beyond;
            axis = i;
        }
    }
    return axis;
}

double maxAbsComponent(const Vec3& v) noexcept {
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}

double aabbScale(const Aabb& box) noexcept {
    return maxAbsComponent(box.center()) +
           std::max({box.max.x - box.min.x, box.max.y - box.min.y, box.max.z - box.min.z});
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
    const double tol = overlapToleranceFor(maxAbsComponent(a.center) + sum(a.halfExtents),
                                           maxAbsComponent(b.center) + sum(b.halfExtents));
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
    const double tol =
        overlapToleranceFor(maxAbsComponent(box.center) + sum(box.halfExtents), aabbScale(cell));
    return !separated(cell.halfExtents(), box.halfExtents, r, t, tol);
}

bool overlapsSphereAabb(const Vec3& center, double radius, const Aabb& cell) noexcept {
    const Vec3 d = glm::max(glm::max(cell.min - center, center - cell.max), Vec3(0.0));
    const double reach =
        radius + overlapToleranceFor(maxAbsComponent(center) + radius, aabbScale(cell));
    return glm::dot(d, d) <= reach * reach;
}

bool overlapsAabbAabb(const Aabb& a, const Aabb& b) noexcept {
    const double tol = overlapToleranceFor(aabbScale(a), aabbScale(b));
    return a.min.x <= b.max.x + tol && a.max.x + tol >= b.min.x && a.min.y <= b.max.y + tol &&
           a.max.y + tol >= b.min.y && a.min.z <= b.max.z + tol && a.max.z + tol >= b.min.z;
}

Aabb triangleAabb(const TriangleCorners& t) noexcept {
    return {glm::min(glm::min(t[0], t[1]), t[2]), glm::max(glm::max(t[0], t[1]), t[2])};
}

bool overlapsTriangleAabb(const TriangleCorners& t, const Aabb& box, double tol) noexcept {
    // In the box's frame: corners relative to its centre, h its half extents. An axis L
    // separates when the triangle's projection interval [lo, hi] lies beyond the box's
    // [-r, r], r = h . |L|, by more than tol * |L| (compared squared, no square root).
    const Vec3 c = box.center();
    const Vec3 h = box.halfExtents();
    const Vec3 v0 = t[0] - c, v1 = t[1] - c, v2 = t[2] - c;
    const auto separates = [&](const Vec3& axis) {
        const double p0 = glm::dot(v0, axis), p1 = glm::dot(v1, axis), p2 = glm::dot(v2, axis);
        const double lo = std::min({p0, p1, p2}), hi = std::max({p0, p1, p2});
        const double r = glm::dot(h, glm::abs(axis));
        const double gap = std::max(lo - r, -r - hi); // > 0: the intervals are apart
        return gap > 0.0 && gap * gap > tol * tol * glm::dot(axis, axis);
    };
    // The box's face normals: the triangle's AABB against the box.
    for (int a = 0; a < 3; ++a) {
        const double lo = std::min({v0[a], v1[a], v2[a]}), hi = std::max({v0[a], v1[a], v2[a]});
        if (lo > h[a] + tol || hi < -h[a] - tol) {
            return false;
        }
    }
    // The triangle's normal.
    const Vec3 e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
    if (separates(glm::cross(e0, e1))) {
        return false;
    }
    // The nine edge axes: unit axis a x edge is exact (a permutation of the edge's
    // components), so only the projections round, and tol * |L| covers that.
    const Vec3 edges[3] = {e0, e1, e2};
    for (const Vec3& e : edges) {
        if (separates(Vec3(0.0, -e.z, e.y)) || separates(Vec3(e.z, 0.0, -e.x)) ||
            separates(Vec3(-e.y, e.x, 0.0))) {
            return false;
        }
    }
    return true;
}

bool overlapsTriangleAabb(const TriangleCorners& t, const Aabb& box) noexcept {
    return overlapsTriangleAabb(t, box,
                                overlapToleranceFor(aabbScale(triangleAabb(t)), aabbScale(box)));
}

} // namespace hapto
