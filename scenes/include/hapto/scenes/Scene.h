#pragma once
/// A static scene: world bounds for the partitioned space and the objects in it.

#include "hapto/scenes/SceneObject.h"

#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace hapto {

/// Bounds and objects. Objects are addressed by a dense 32-bit slot (their position in
/// `objects()`), which indices use internally, and named by their `ObjectId` in every output.
class Scene {
public:
    /// An empty scene over the paper's 25 cm work cube.
    Scene();
    /// Takes the objects; throws std::invalid_argument on a duplicate id, an empty bounds box
    /// or one whose size overflows, or more objects than 32-bit slots allow. [control]
    Scene(Aabb bounds, std::vector<SceneObject> objects);

    /// The partitioned space (m). Objects may reach outside it. [any thread]
    const Aabb& bounds() const { return mBounds; }
    /// All objects, by slot. [any thread]
    std::span<const SceneObject> objects() const { return mObjects; }
    /// The object in slot i. [any thread]
    const SceneObject& object(std::uint32_t slot) const { return mObjects[slot]; }
    /// Number of objects. [any thread]
    std::uint32_t size() const { return static_cast<std::uint32_t>(mObjects.size()); }
    /// The slot of the object with this id, if any; O(log N). [any thread]
    std::optional<std::uint32_t> slotOf(ObjectId id) const;

    /// Moves one object (m, unit quaternion); the caller owns this copy of the scene. [control]
    void setPose(std::uint32_t slot, const Vec3& center, const Quat& rotation);

    /// Bounds that hold every object, padded by 5 % of the largest extent (at least 1 mm);
    /// the 25 cm cube around the origin when there are no objects. [any thread]
    static Aabb defaultBounds(std::span<const SceneObject> objects);

    bool operator==(const Scene& o) const {
        return mObjects == o.mObjects && mBounds.min == o.mBounds.min &&
               mBounds.max == o.mBounds.max;
    }

private:
    Aabb mBounds;
    std::vector<SceneObject> mObjects;
    std::vector<std::pair<ObjectId, std::uint32_t>> mSlotById; // sorted by id
};

} // namespace hapto
