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

std::optional<std::uint32_t> Scene::slotOf(ObjectId id) const {
    const auto it = std::lower_bound(mSlotById.begin(), mSlotById.end(),
                                     std::pair<ObjectId, std::uint32_t>(id, 0));
    if (it == mSlotById.end() || it->first != id) {
        return std::nullopt;
    }
    return it->second;
}

void Scene::setPose(std::uint32_t slot, const Vec3& center, const Quat& rotation) {
    mObjects.at(slot).center = center;
    mObjects.at(slot).rotation = glm::normalize(rotation);
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
