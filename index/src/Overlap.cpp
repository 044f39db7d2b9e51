#include "hapto/index/Overlap.h"

#include <algorithm>
#include <cmath>

namespace hapto {

OverlapShape OverlapShape::of(const SceneObject& object) {
    return of(Scene::bodyOf(object));
}

namespace {

/// A box's or sphere's tightest world AABB, given its oriented box.
Aabb bodyAabb(const RenderBody& body, const Obb& obb) noexcept {
    return body.shape == Shape::Sphere
               ? Aabb{body.center - body.halfExtents, body.center + body.halfExtents}
               : obb.aabb();
}

/// A box's or sphere's tolerance scale: largest |centre| coordinate plus largest half extent.
double bodyScale(const RenderBody& body) noexcept {
    return maxAbsComponent(body.center) +
           std::max({body.halfExtents.x, body.halfExtents.y, body.halfExtents.z});
}

OverlapBounds triangleBounds(const TriangleCorners& corners) noexcept {
    const Aabb aabb = triangleAabb(corners);
    return {aabb, aabbScale(aabb)};
}

} // namespace

OverlapShape OverlapShape::of(const RenderBody& body) noexcept {
    OverlapShape s;
    s.obb = body.obb();
    const bool sphere = body.shape == Shape::Sphere;
    s.kind = sphere ? OverlapShape::Kind::Sphere : OverlapShape::Kind::Box;
    s.aabb = bodyAabb(body, s.obb);
    s.radius = sphere ? body.halfExtents.x : 0.0;
    s.scale = bodyScale(body);
    s.axisAligned = !sphere;
    for (int i = 0; i < 3 && s.axisAligned && !body.axisAligned; ++i) {
        // each axis one of +-x, +-y, +-z, exactly (a quarter turn whose matrix came out exact)
        const Vec3 m = glm::abs(s.obb.axes[i]);
        s.axisAligned = m.x + m.y + m.z == 1.0 && std::max({m.x, m.y, m.z}) == 1.0;
    }
    return s;
}

OverlapShape OverlapShape::ofTriangle(const TriangleCorners& corners) noexcept {
    OverlapShape s;
    s.triangle = corners;
    s.kind = OverlapShape::Kind::Triangle;
    const OverlapBounds b = triangleBounds(corners);
    s.aabb = b.aabb;
    s.scale = b.scale;
    return s;
}

OverlapShape OverlapShape::of(const Scene& scene, std::uint32_t item) {
    return isTriangleItem(item) ? ofTriangle(scene.triangleCorners(item)) : of(scene.body(item));
}

Aabb itemAabb(const Scene& scene, std::uint32_t item) noexcept {
    if (isTriangleItem(item)) {
        return triangleAabb(scene.triangleCorners(item));
    }
    // SceneObject::aabb() from the render copy (the same oriented box, bit for bit).
    const RenderBody& b = scene.body(item);
    return bodyAabb(b, b.obb());
}

OverlapBounds overlapBounds(const Scene& scene, std::uint32_t item) noexcept {
    if (isTriangleItem(item)) {
        return triangleBounds(scene.triangleCorners(item));
    }
    const RenderBody& b = scene.body(item);
    return {bodyAabb(b, b.obb()), bodyScale(b)};
}

Vec3 itemCenter(const Scene& scene, std::uint32_t item) noexcept {
    if (isTriangleItem(item)) {
        const TriangleCorners t = scene.triangleCorners(item);
        return (t[0] + t[1] + t[2]) / 3.0;
    }
    return scene.object(item).center;
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

bool overlapsAabb(const Aabb& a, double scale, const OverlapCell& prepared) noexcept {
    const double tol = overlapToleranceFor(scale, prepared.scale);
    const Aabb& cell = prepared.box;
    return a.min.x <= cell.max.x + tol && a.max.x + tol >= cell.min.x &&
           a.min.y <= cell.max.y + tol && a.max.y + tol >= cell.min.y &&
           a.min.z <= cell.max.z + tol && a.max.z + tol >= cell.min.z;
}

bool overlaps(const OverlapShape& shape, const OverlapCell& prepared, OverlapMode mode) noexcept {
    if (!overlapsAabb(shape.aabb, shape.scale, prepared)) {
        return false;
    }
    const Aabb& a = shape.aabb;
    const Aabb& cell = prepared.box;
    if (mode == OverlapMode::Aabb || shape.axisAligned) {
        return true;
    }
    // The centre (a triangle: its centroid) in the cell, or the AABB inside it: an overlap for
    // sure.
    const bool triangle = shape.kind == OverlapShape::Kind::Triangle;
    const Vec3 c = triangle ? (shape.triangle[0] + shape.triangle[1] + shape.triangle[2]) / 3.0
                            : shape.obb.center;
    if ((c.x >= cell.min.x && c.x <= cell.max.x && c.y >= cell.min.y && c.y <= cell.max.y &&
         c.z >= cell.min.z && c.z <= cell.max.z) ||
        (a.min.x >= cell.min.x && a.max.x <= cell.max.x && a.min.y >= cell.min.y &&
         a.max.y <= cell.max.y && a.min.z >= cell.min.z && a.max.z <= cell.max.z)) {
        return true;
    }
    switch (shape.kind) {
    case OverlapShape::Kind::Sphere:
        return overlapsSphereAabb(shape.obb.center, shape.radius, cell);
    case OverlapShape::Kind::Triangle:
        return overlapsTriangleAabb(shape.triangle, cell, overlapTolerance(shape, prepared));
    case OverlapShape::Kind::Box:
        break;
    }
    return overlapsObbAabb(shape.obb, cell);
}

} // namespace hapto
