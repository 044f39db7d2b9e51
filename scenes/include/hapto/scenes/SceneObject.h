#pragma once
/// One rigid object of a scene: an oriented box or a sphere with an id and a material.

#include "hapto/core/Geometry.h"

#include <cstdint>
#include <string_view>

namespace hapto {

/// A user-facing object id: unique in its scene, not necessarily dense. Outputs always use it.
using ObjectId = std::uint32_t;

/// The largest id a scene may use (ids are 32-bit; the last value is kept free as "none").
inline constexpr ObjectId kMaxObjectId = 0xFFFFFFFEu;

/// The shapes hapto renders.
enum class Shape : std::uint8_t { Box, Sphere };

/// The name of a shape as scene files spell it ("box", "sphere"). [any thread]
std::string_view shapeName(Shape shape);

/// How an object feels.
struct Material {
    /// Default surface stiffness (N/m): firm but well inside what a PHANToM 1.0 renders stably.
    static constexpr double kDefaultStiffness = 800.0;
    /// Largest stiffness a scene file may give (N/m): 10^6, far above what any desktop device
    /// renders stably (a PHANToM Premium manages a few thousand N/m), low enough that k times
    /// any penetration inside a scene stays a finite force for ForceSafety to clamp.
    static constexpr double kMaxStiffness = 1e6;
    /// Largest Coulomb coefficient a scene file may give: 10 (real materials stay below about
    /// 2; rubber on rubber); the friction cone's radius mu * |F| then stays finite.
    static constexpr double kMaxFriction = 10.0;

    double stiffness = kDefaultStiffness; ///< Surface stiffness k (N/m), > 0.
    double staticFriction = 0.0;          ///< Coulomb static coefficient mu_s (unitless), >= 0.
    double dynamicFriction = 0.0;         ///< Coulomb dynamic coefficient mu_d, 0 <= mu_d <= mu_s.

    bool operator==(const Material&) const = default;
};

/// An oriented box or a sphere, in world coordinates (m).
struct SceneObject {
    ObjectId id = 0;           ///< Unique id within the scene.
    Shape shape = Shape::Box;  ///< Box or sphere.
    Vec3 center{0.0};          ///< Centre (m).
    Vec3 halfExtents{0.0};     ///< Box: half size per own axis (m). Sphere: radius, thrice.
    Quat rotation{1, 0, 0, 0}; ///< Orientation, unit quaternion (w, x, y, z).
    Material material{};       ///< Stiffness and friction.

    /// Sphere radius (m); for a box, the radius of its bounding sphere. [any thread]
    double radius() const;
    /// The object's oriented bounding box (a sphere's is its axis-aligned cube). [any thread]
    Obb obb() const;
    /// The tightest world AABB (m). [any thread]
    Aabb aabb() const;
    /// True when p lies in the solid (surface included). [any thread]
    bool contains(const Vec3& p) const;

    bool operator==(const SceneObject&) const = default;
};

/// Makes a box. [any thread]
SceneObject makeBox(ObjectId id, Vec3 center, Vec3 halfExtents, Quat rotation = Quat(1, 0, 0, 0),
                    Material material = {});
/// Makes a sphere. [any thread]
SceneObject makeSphere(ObjectId id, Vec3 center, double radius, Material material = {});

} // namespace hapto
