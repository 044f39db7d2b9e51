#include "hapto/scenes/SceneObject.h"

#include "hapto/core/ShapeGeometry.h"

#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <utility>

namespace hapto {

std::string_view shapeName(Shape shape) {
    switch (shape) {
    case Shape::Box:
        return "box";
    case Shape::Sphere:
        return "sphere";
    case Shape::Mesh:
        return "mesh";
    }
    return "unknown";
}

double SceneObject::radius() const {
    switch (shape) {
    case Shape::Sphere:
        return halfExtents.x;
    case Shape::Mesh:
        return mesh->boundingRadius();
    case Shape::Box:
        break;
    }
    return glm::length(halfExtents);
}

Obb SceneObject::obb() const {
    if (shape == Shape::Sphere) {
        return {center, halfExtents, Mat3(1.0)};
    }
    const Mat3 axes = glm::mat3_cast(rotation);
    if (shape == Shape::Mesh) {
        const Aabb& local = mesh->localBounds();
        return {center + axes * local.center(), local.halfExtents(), axes};
    }
    return {center, halfExtents, axes};
}

Aabb SceneObject::aabb() const {
    if (shape == Shape::Sphere) {
        return {center - halfExtents, center + halfExtents};
    }
    return obb().aabb();
}

namespace {

/// Ray parity: a ray from the local point along a fixed, irrational-looking direction crosses a
/// closed surface an odd number of times from inside. Points on the surface count as inside.
bool meshContains(const TriangleMesh& mesh, const Vec3& local) {
    const Vec3 dir =
        glm::normalize(Vec3(0.3141592653589793, 0.2718281828459045, 0.9092974268256817));
    bool inside = false;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const auto [a, b, c] = mesh.corners(t);
        const Vec3 e1 = b - a;
        const Vec3 e2 = c - a;
        const Vec3 n = glm::cross(e1, e2);
        const double dist = glm::dot(n, local - a);
        const double n2 = glm::dot(n, n);
        // On the triangle's plane and inside it: on the surface.
        if (dist * dist <= 1e-24 * n2) {
            const Vec3 q = local - a;
            const double d00 = glm::dot(e1, e1), d01 = glm::dot(e1, e2), d11 = glm::dot(e2, e2);
            const double d20 = glm::dot(q, e1), d21 = glm::dot(q, e2);
            const double den = d00 * d11 - d01 * d01;
            const double v = (d11 * d20 - d01 * d21) / den;
            const double w = (d00 * d21 - d01 * d20) / den;
            if (v >= 0.0 && w >= 0.0 && v + w <= 1.0) {
                return true;
            }
        }
        // Moeller-Trumbore.
        const Vec3 pv = glm::cross(dir, e2);
        const double det = glm::dot(e1, pv);
        if (std::abs(det) < 1e-300) {
            continue;
        }
        const double inv = 1.0 / det;
        const Vec3 tv = local - a;
        const double u = glm::dot(tv, pv) * inv;
        if (u < 0.0 || u > 1.0) {
            continue;
        }
        const Vec3 qv = glm::cross(tv, e1);
        const double v = glm::dot(dir, qv) * inv;
        if (v < 0.0 || u + v > 1.0) {
            continue;
        }
        if (glm::dot(e2, qv) * inv > 0.0) {
            inside = !inside;
        }
    }
    return inside;
}

} // namespace

bool SceneObject::contains(const Vec3& p) const {
    switch (shape) {
    case Shape::Sphere:
        return sphereContains(center, halfExtents.x, p);
    case Shape::Mesh:
        return mesh->closed() && obb().contains(p) &&
               meshContains(*mesh, glm::conjugate(rotation) * (p - center));
    case Shape::Box:
        break;
    }
    return obb().contains(p);
}

SceneObject makeBox(ObjectId id, Vec3 center, Vec3 halfExtents, Quat rotation, Material material) {
    return {id, Shape::Box, center, halfExtents, glm::normalize(rotation), material, nullptr};
}

SceneObject makeSphere(ObjectId id, Vec3 center, double radius, Material material) {
    return {id, Shape::Sphere, center, Vec3(radius), Quat(1, 0, 0, 0), material, nullptr};
}

SceneObject makeMesh(ObjectId id, Vec3 center, std::shared_ptr<const TriangleMesh> mesh,
                     Quat rotation, Material material) {
    const Vec3 half = mesh->localBounds().halfExtents();
    return {id, Shape::Mesh, center, half, glm::normalize(rotation), material, std::move(mesh)};
}

} // namespace hapto
