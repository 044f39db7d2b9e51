#pragma once
/// A static scene: world bounds for the partitioned space and the objects in it.

#include "hapto/scenes/SceneObject.h"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace hapto {

/// The bit that marks an index item as a mesh triangle rather than an object slot.
inline constexpr std::uint32_t kTriangleItemBit = 0x80000000u;
/// The most triangles a scene may hold over all its meshes (item ids have 31 bits).
inline constexpr std::uint64_t kMaxSceneTriangles = kTriangleItemBit - 1;

/// True when an index item names a mesh triangle (kTriangleItemBit | scene triangle number).
constexpr bool isTriangleItem(std::uint32_t item) noexcept {
    return (item & kTriangleItemBit) != 0;
}

/// A scene triangle: which mesh object it belongs to and which of that mesh's triangles it is.
struct TriangleRef {
    std::uint32_t objectSlot = 0; ///< The mesh object's slot.
    std::uint32_t triangle = 0;   ///< The triangle's number in that object's TriangleMesh.
};

/// The render copy of one object: its pose and size as the servo path uses them, computed when
/// the scene is made or the object moves (on the control thread, never in a tick), so that no
/// tick turns a quaternion into a matrix or recomputes a bounding radius. 128 bytes.
struct RenderBody {
    Vec3 center{0.0};         ///< Box, sphere: the centre; mesh: its local origin (m, world).
    Vec3 halfExtents{0.0};    ///< Box: half size per own axis; sphere: the radius, thrice; mesh:
                              ///< unused (zero) (m).
    Mat3 axes{1.0};           ///< The rotation as a matrix: column i is own axis i (world). A
                              ///< sphere's is the identity.
    double radius = 0.0;      ///< Bounding sphere about `center` (m): SceneObject::radius().
    Shape shape = Shape::Box; ///< Box, sphere or mesh triangle.
    bool axisAligned = true;  ///< `axes` is exactly the identity: local = p - center, no product.

    /// A box's or sphere's oriented box (SceneObject::obb(), bit for bit). [any thread]
    Obb obb() const noexcept { return {center, halfExtents, axes}; }
    /// A world point in the object's own frame (m). [any thread]
    Vec3 toLocal(const Vec3& p) const noexcept {
        return axisAligned ? p - center : glm::transpose(axes) * (p - center);
    }
    /// A local point (or, with `center` left out, a direction) in world coordinates. [any thread]
    Vec3 toWorld(const Vec3& local) const noexcept {
        return axisAligned ? center + local : center + axes * local;
    }
    /// A local direction in world coordinates. [any thread]
    Vec3 rotate(const Vec3& local) const noexcept { return axisAligned ? local : axes * local; }
};

/// A triangle item's plane in world coordinates: {x : dot(normal, x) = offset}.
struct WorldFace {
    Vec3 normal{0.0};    ///< Outward unit normal; zero for a triangle with none (never touched).
    double offset = 0.0; ///< (m).
};

/// How the scene's dynamic bodies are simulated (scene format version 3: "gravity" and
/// "dynamics": {"rate_hz": ...}). Ignored by a scene without dynamic bodies.
struct ScenePhysics {
    /// Largest |gravity| a scene may give (m/s^2): 100, ten g.
    static constexpr double kMaxGravity = 100.0;
    /// The slowest dynamics step rate a scene may ask for (Hz).
    static constexpr double kMinRateHz = 100.0;
    /// The fastest dynamics step rate a scene may ask for (Hz).
    static constexpr double kMaxRateHz = 10'000.0;

    Vec3 gravity{0.0, -9.81, 0.0}; ///< Acceleration of gravity (m/s^2, world; y is up).
    double rateHz = 1000.0;        ///< Dynamics steps per second (Hz).

    /// Every field equal.
    bool operator==(const ScenePhysics&) const = default;
};

/// Bounds and objects. Objects are addressed by a dense 32-bit slot (their position in
/// `objects()`) and named by their `ObjectId` in every output.
///
/// Items. What a spatial index holds are *items*: every box and sphere by its slot, and every
/// triangle of every mesh as `kTriangleItemBit | n`, where n numbers the scene's triangles
/// mesh by mesh in slot order (a mesh object itself is not an item: its triangles are). Items
/// are enumerated densely by `item(i)` for i < itemCount(): the object slots first, then the
/// triangles. Appending an object keeps every existing item's id, so an index built before
/// still names the same objects and triangles.
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

    /// Triangles over all mesh objects. [any thread]
    std::uint32_t triangleCount() const { return mTriangleCount; }
    /// Number of dense item positions: size() + triangleCount() (mesh objects' own positions
    /// included; isIndexed() tells them apart). [any thread]
    std::uint32_t itemCount() const { return size() + mTriangleCount; }
    /// The item at dense position i < itemCount(). [any thread]
    std::uint32_t item(std::uint32_t i) const noexcept {
        return i < size() ? i : kTriangleItemBit | (i - size());
    }
    /// False for a mesh object's own slot (its triangles are indexed instead). [any thread]
    bool isIndexed(std::uint32_t item) const noexcept {
        return isTriangleItem(item) || mObjects[item].shape != Shape::Mesh;
    }
    /// The triangle an item names (the item must be a triangle item of this scene); O(log
    /// meshes). [any thread]
    TriangleRef triangle(std::uint32_t item) const noexcept;
    /// The object an item belongs to: its own slot, or its mesh's slot. [any thread]
    std::uint32_t objectSlotOf(std::uint32_t item) const noexcept {
        return isTriangleItem(item) ? triangle(item).objectSlot : item;
    }
    /// A triangle item's corners in world coordinates (m), at its mesh's current pose. [any
    /// thread]
    std::array<Vec3, 3> triangleCorners(std::uint32_t item) const noexcept {
        const TriangleRef ref = triangle(item);
        const RenderBody& b = mBodies[ref.objectSlot];
        const auto [p, q, r] = mObjects[ref.objectSlot].mesh->corners(ref.triangle);
        return {b.toWorld(p), b.toWorld(q), b.toWorld(r)};
    }
    /// A triangle item's plane in world coordinates, at its mesh's current pose. [any thread]
    WorldFace triangleFace(std::uint32_t item) const noexcept {
        const TriangleRef ref = triangle(item);
        const RenderBody& b = mBodies[ref.objectSlot];
        const TriangleFace& f = mObjects[ref.objectSlot].mesh->face(ref.triangle);
        const Vec3 n = b.rotate(f.normal);
        return {n, f.offset + glm::dot(n, b.center)};
    }
    /// The render copy of the object in slot i. [any thread]
    const RenderBody& body(std::uint32_t slot) const noexcept { return mBodies[slot]; }
    /// The render copy of an object (what body() holds for it). [any thread]
    static RenderBody bodyOf(const SceneObject& o);

    /// Moves one object (m, unit quaternion); the caller owns this copy of the scene. [control]
    void setPose(std::uint32_t slot, const Vec3& center, const Quat& rotation);

    /// Bounds that hold every object, padded by 5 % of the largest extent (at least 1 mm);
    /// the 25 cm cube around the origin when there are no objects. [any thread]
    static Aabb defaultBounds(std::span<const SceneObject> objects);

    /// Gravity and the dynamics rate. [any thread]
    const ScenePhysics& physics() const { return mPhysics; }
    /// Sets gravity and the dynamics rate (unchecked: the scene file's reader checks). [control]
    void setPhysics(const ScenePhysics& physics) { mPhysics = physics; }
    /// True when some object is dynamic (BodyProperties::dynamic). [any thread]
    bool hasDynamicBodies() const;

    /// The same objects in the same order, the same bounds and the same physics.
    bool operator==(const Scene& o) const {
        return mObjects == o.mObjects && mBounds.min == o.mBounds.min &&
               mBounds.max == o.mBounds.max && mPhysics == o.mPhysics;
    }

private:
    /// Where each mesh's triangles start in the scene's triangle numbering.
    struct MeshRange {
        std::uint32_t firstTriangle;
        std::uint32_t objectSlot;
    };

    Aabb mBounds;
    ScenePhysics mPhysics;
    std::vector<SceneObject> mObjects;
    std::vector<RenderBody> mBodies; // by slot: the render copy
    std::vector<MeshRange> mMeshes;  // by firstTriangle, ascending
    std::uint32_t mTriangleCount = 0;
    std::vector<std::pair<ObjectId, std::uint32_t>> mSlotById; // sorted by id
};

} // namespace hapto
