#include "hapto/scenes/SceneObject.h"

#include "hapto/core/ShapeGeometry.h"

#include <glm/gtc/quaternion.hpp>

namespace hapto {

std::string_view shapeName(Shape shape) {
    switch (shape) {
    case Shape::Box:
        return "box";
    case Shape::Sphere:
        return "sphere";
    }
    return "unknown";
}

double SceneObject::radius() const {
    return shape == Shape::Sphere ? halfExtents.x : glm::length(halfExtents);
}

Obb SceneObject::obb() const {
    if (shape == Shape::Sphere) {
        return {center, halfExtents, Mat3(1.0)};
    }
    return {center, halfExtents, glm::mat3_cast(rotation)};
}

Aabb SceneObject::aabb() const {
    if (shape == Shape::Sphere) {
        return {center - halfExtents, center + halfExtents};
    }
    return obb().aabb();
}

bool SceneObject::contains(const Vec3& p) const {
    return shape == Shape::Sphere ? sphereContains(center, halfExtents.x, p) : obb().contains(p);
}

SceneObject makeBox(ObjectId id, Vec3 center, Vec3 halfExtents, Quat rotation, Material material) {
    return {id, Shape::Box, center, halfExtents, glm::normalize(rotation), material};
}

SceneObject makeSphere(ObjectId id, Vec3 center, double radius, Material material) {
    return {id, Shape::Sphere, center, Vec3(radius), Quat(1, 0, 0, 0), material};
}

} // namespace hapto
