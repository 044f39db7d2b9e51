#include "hapto/scenes/Scene.h"

#include "hapto/core/Finite.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hapto {

Scene::Scene() : mBounds(defaultBounds({})) {}

Scene::Scene(Aabb bounds, std::vector<SceneObject> objects)
    : mBounds(bounds), mObjects(std::move(objects)) {
    if (!(bounds.min.x < bounds.max.x && bounds.min.y < bounds.max.y &&
          bounds.min.z < bounds.max.z)) {
        throw std::invalid_argument("scene bounds must have min < max on every axis");
    }
    const Vec3 size = bounds.max - bounds.min;
    if (!finite(size)) {
        throw std::invalid_argument("scene bounds must have a finite size on every axis");
    }
    if (mObjects.size() >= std::numeric_limits<std::uint32_t>::max()) {
        throw std::invalid_argument("a scene holds at most 2^32 - 1 objects");
    }
    std::uint64_t triangles = 0;
    for (std::uint32_t i = 0; i < mObjects.size(); ++i) {
        const SceneObject& o = mObjects[i];
        if (o.shape != Shape::Mesh) {
            continue;
        }
        if (!o.mesh) {
            throw std::invalid_argument("mesh object " + std::to_string(o.id) +
                                        " has no triangles");
        }
        mMeshes.push_back({static_cast<std::uint32_t>(triangles), i});
        triangles += o.mesh->triangleCount();
        if (triangles > kMaxSceneTriangles) {
            throw std::invalid_argument("a scene holds at most 2^31 - 1 triangles over all meshes");
        }
    }
    mTriangleCount = static_cast<std::uint32_t>(triangles);
    mBodies.reserve(mObjects.size());
    for (const SceneObject& o : mObjects) {
        mBodies.push_back(bodyOf(o));
    }
    if (std::uint64_t(mObjects.size()) + triangles >= std::numeric_limits<std::uint32_t>::max()) {
        throw std::invalid_argument("a scene holds at most 2^32 - 1 objects and triangles");
    }
    mSlotById.reserve(mObjects.size());
    for (std::uint32_t i = 0; i < mObjects.size(); ++i) {
        mSlotById.emplace_back(mObjects[i].id, i);
    }
    std::sort(mSlotById.begin(), mSlotById.end());
    const auto dup = std::adjacent_find(mSlotById.begin(), mSlotById.end(),
                                        [](auto& a, auto& b) { return a.first == b.first; });
    if (dup != mSlotById.end()) {
        throw std::invalid_argument("duplicate object id " + std::to_string(dup->first));
    }
}

bool Scene::hasDynamicBodies() const {
    return std::any_of(mObjects.begin(), mObjects.end(),
                       [](const SceneObject& o) { return o.body.dynamic; });
}

std::optional<std::uint32_t> Scene::slotOf(ObjectId id) const {
    const auto it = std::lower_bound(mSlotById.begin(), mSlotById.end(),
                                     std::pair<ObjectId, std::uint32_t>(id, 0));
    if (it == mSlotById.end() || it->first != id) {
        return std::nullopt;
    }
    return it->second;
}

TriangleRef Scene::triangle(std::uint32_t item) const noexcept {
    const std::uint32_t n = item & ~kTriangleItemBit;
    const auto it =
        std::upper_bound(mMeshes.begin(), mMeshes.end(), n,
                         [](std::uint32_t v, const MeshRange& m) { return v < m.firstTriangle; });
    const MeshRange& m = *(it - 1);
    return {m.objectSlot, n - m.firstTriangle};
}

RenderBody Scene::bodyOf(const SceneObject& o) {
    RenderBody b;
    b.center = o.center;
    b.shape = o.shape;
    b.radius = o.radius();
    if (o.shape != Shape::Mesh) {
        b.halfExtents = o.halfExtents;
    }
    if (o.shape != Shape::Sphere) {
        b.axes = glm::mat3_cast(o.rotation);
    }
    b.axisAligned = b.axes == Mat3(1.0);
    return b;
}

void Scene::setPose(std::uint32_t slot, const Vec3& center, const Quat& rotation) {
    SceneObject& o = mObjects.at(slot);
    o.center = center;
    o.rotation = glm::normalize(rotation);
    mBodies[slot] = bodyOf(o);
}

Aabb Scene::defaultBounds(std::span<const SceneObject> objects) {
    if (objects.empty()) {
        return {Vec3(-0.125), Vec3(0.125)};
    }
    Aabb box = Aabb::empty();
    for (const SceneObject& o : objects) {
        box.expand(o.aabb());
    }
    const Vec3 size = box.size();
    const double pad = std::max(0.001, 0.05 * std::max({size.x, size.y, size.z}));
    box.min -= Vec3(pad);
    box.max += Vec3(pad);
    return box;
}

} // namespace hapto
