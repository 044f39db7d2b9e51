#pragma once
/// One rigid object of a scene: an oriented box, a sphere or a triangle mesh, with an id and a
/// material.

#include "hapto/core/ConvexHull.h"
#include "hapto/core/Geometry.h"
#include "hapto/scenes/TriangleMesh.h"

#include <cstdint>
#include <memory>
#include <string_view>

namespace hapto {

/// A user-facing object id: unique in its scene, not necessarily dense. Outputs always use it.
using ObjectId = std::uint32_t;

/// The largest id a scene may use (ids are 32-bit; the last value is kept free as "none").
inline constexpr ObjectId kMaxObjectId = 0xFFFFFFFEu;

/// The shapes hapto renders.
enum class Shape : std::uint8_t { Box, Sphere, Mesh };

/// The name of a shape as scene files spell it ("box", "sphere", "mesh"). [any thread]
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

    /// Every coefficient equal.
    bool operator==(const Material&) const = default;
};

/// What makes an object a rigid body with mass (scene format version 3). A static object (the
/// default) has none of it: it never moves unless the application moves it.
///
/// The body's reference point is its centre of mass: `centerOfMassLocal` places it in the
/// object's own frame (a box's and a sphere's is 0; a mesh's is its volume centroid), and its
/// inertia is about that point, in the object's own axes.
struct BodyProperties {
    /// Largest mass a scene file may give (kg): 10^4, ten tonnes, far above anything a hand
    /// lifts, low enough that m g stays a small finite force.
    static constexpr double kMaxMassKg = 1e4;
    /// Largest density a scene file may give (kg/m^3): 10^5, above the densest element
    /// (osmium, 22,590 kg/m^3; CRC Handbook of Chemistry and Physics).
    static constexpr double kMaxDensityKgPerM3 = 1e5;
    /// Largest initial speed a scene file may give (m/s): 100, ten times a hard throw.
    static constexpr double kMaxSpeed = 100.0;
    /// Largest initial angular speed a scene file may give (rad/s): 10^4.
    static constexpr double kMaxAngularSpeed = 1e4;

    bool dynamic = false;        ///< Simulated by the dynamics thread (scene key "dynamic").
    double massKg = 0.0;         ///< Mass (kg), > 0 when dynamic.
    Mat3 inertia{0.0};           ///< Inertia tensor about the centre of mass, own axes
                                 ///< (kg m^2): symmetric positive definite when dynamic.
    Vec3 centerOfMassLocal{0.0}; ///< Centre of mass in the object's own frame (m).
    double restitution = 0.0;    ///< Coefficient of restitution e in [0, 1] (pair: the larger).
    Vec3 velocity{0.0};          ///< Initial linear velocity of the centre of mass (m/s, world).
    Vec3 angularVelocity{0.0};   ///< Initial angular velocity (rad/s, world).
    /// A dynamic mesh's convex hull (own frame): what it collides as. Null for a box, a
    /// sphere or a static object.
    std::shared_ptr<const ConvexHull> hull;

    /// Every field equal.
    bool operator==(const BodyProperties&) const = default;
};

/// An oriented box, a sphere or a triangle mesh, in world coordinates (m).
///
/// A mesh is placed like a box: a world point x of the mesh is center + rotation * v for a
/// local vertex v of `mesh` (scale already applied). Its triangles, not the object, are what an
/// index holds (see Scene's items); the object itself is what moves and is grasped.
struct SceneObject {
    ObjectId id = 0;           ///< Unique id within the scene.
    Shape shape = Shape::Box;  ///< Box, sphere or mesh.
    Vec3 center{0.0};          ///< Centre (m); a mesh's local origin.
    Vec3 halfExtents{0.0};     ///< Box: half size per own axis (m). Sphere: radius, thrice.
                               ///< Mesh: half size of its local bounds (m).
    Quat rotation{1, 0, 0, 0}; ///< Orientation, unit quaternion (w, x, y, z).
    Material material{};       ///< Stiffness and friction.
    std::shared_ptr<const TriangleMesh> mesh; ///< Mesh only: its triangles, local frame.
    BodyProperties body{}; ///< Mass and initial motion; `body.dynamic` false: a static object.

    /// Sphere radius (m); for a box, the radius of its bounding sphere; for a mesh, of its
    /// bounding sphere about `center`. [any thread]
    double radius() const;
    /// The object's oriented bounding box (a sphere's is its axis-aligned cube; a mesh's is its
    /// local bounds, placed). [any thread]
    Obb obb() const;
    /// The tightest world AABB of its OBB (m). [any thread]
    Aabb aabb() const;
    /// True when p lies in the solid (surface included). A mesh has a solid only when it is
    /// closed (TriangleMesh::closed); the test casts a ray through every triangle, O(triangles):
    /// for tools and tests, not for the servo path. [any thread]
    bool contains(const Vec3& p) const;

    /// Every field equal (a mesh compared by its pointer: the same loaded mesh).
    bool operator==(const SceneObject&) const = default;
};

/// Makes a box. [any thread]
SceneObject makeBox(ObjectId id, Vec3 center, Vec3 halfExtents, Quat rotation = Quat(1, 0, 0, 0),
                    Material material = {});
/// Makes a sphere. [any thread]
SceneObject makeSphere(ObjectId id, Vec3 center, double radius, Material material = {});
/// Places a mesh (which must not be null). [any thread]
SceneObject makeMesh(ObjectId id, Vec3 center, std::shared_ptr<const TriangleMesh> mesh,
                     Quat rotation = Quat(1, 0, 0, 0), Material material = {});

} // namespace hapto
