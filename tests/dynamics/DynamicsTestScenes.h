#pragma once
// Scenes for the dynamics tests, built in code: a static floor, static boxes (ramps, slabs,
// walls) and dynamic boxes and spheres with their mass properties, plus the Dynamics over them
// with the default index. Shared by DynamicsTests.cpp and DynamicsAllocationTests.cpp.

#include "hapto/dynamics/Dynamics.h"
#include "hapto/index/DefaultIndex.h"

#include <glm/gtc/quaternion.hpp>

#include <memory>
#include <string>
#include <vector>

namespace hapto::test {

/// Standard gravity (m/s^2), the scenes' default.
inline constexpr double kG = 9.81;

/// A material with Coulomb coefficients (static, dynamic).
inline Material frictionOf(double muS, double muD) {
    Material m;
    m.staticFriction = muS;
    m.dynamicFriction = muD;
    return m;
}

/// A static floor whose top face is the plane y = 0 (2 m square, 10 cm thick).
inline SceneObject floorBox(ObjectId id, Material m = frictionOf(0.8, 0.6)) {
    return makeBox(id, Vec3(0.0, -0.05, 0.0), Vec3(1.0, 0.05, 1.0), Quat(1, 0, 0, 0), m);
}

/// A dynamic solid box of mass `kg`; inertia m/3 (b^2 + c^2) per axis.
inline SceneObject dynamicBox(ObjectId id, Vec3 center, Vec3 half, double kg, Material m = {},
                              Quat rotation = Quat(1, 0, 0, 0), double restitution = 0.0) {
    SceneObject o = makeBox(id, center, half, rotation, m);
    o.body.dynamic = true;
    o.body.massKg = kg;
    const Vec3 h2 = half * half;
    o.body.inertia = Mat3(0.0);
    o.body.inertia[0][0] = kg / 3.0 * (h2.y + h2.z);
    o.body.inertia[1][1] = kg / 3.0 * (h2.x + h2.z);
    o.body.inertia[2][2] = kg / 3.0 * (h2.x + h2.y);
    o.body.restitution = restitution;
    return o;
}

/// A dynamic solid sphere of mass `kg`; inertia 2/5 m r^2.
inline SceneObject dynamicSphere(ObjectId id, Vec3 center, double radius, double kg,
                                 Material m = {}, double restitution = 0.0) {
    SceneObject o = makeSphere(id, center, radius, m);
    o.body.dynamic = true;
    o.body.massKg = kg;
    o.body.inertia = Mat3(0.4 * kg * radius * radius);
    o.body.restitution = restitution;
    return o;
}

/// A static mesh object with the 12 triangles of box `b`'s surface, wound outward (a closed
/// mesh: contacts push out of it only).
inline SceneObject meshOfBox(const SceneObject& b) {
    std::vector<Vec3> v;
    for (int k = 0; k < 8; ++k) {
        v.push_back(b.halfExtents * Vec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1));
    }
    std::vector<TriangleIndices> t{{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},
                                   {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                   {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    return makeMesh(b.id, b.center, TriangleMesh::make(std::move(v), std::move(t), {}, "box"),
                    b.rotation, b.material);
}

/// A scene over the objects with the given gravity (m/s^2) and rate (Hz), an index (the
/// default unless `indexSpec` names one) and the Dynamics stepping it.
struct World {
    std::shared_ptr<Scene> scene;
    std::unique_ptr<Dynamics> dynamics;

    explicit World(std::vector<SceneObject> objects, Vec3 gravity = Vec3(0.0, -kG, 0.0),
                   DynamicsOptions options = {}, double rateHz = 1000.0,
                   std::string indexSpec = {}) {
        scene = std::make_shared<Scene>(Scene::defaultBounds(objects), std::move(objects));
        ScenePhysics physics;
        physics.gravity = gravity;
        physics.rateHz = rateHz;
        scene->setPhysics(physics);
        std::shared_ptr<const SpatialIndex> index = buildIndex(
            *scene, IndexSpec::parse(indexSpec.empty() ? defaultIndexSpec(*scene) : indexSpec));
        dynamics = std::make_unique<Dynamics>(scene, index, options);
    }

    /// Steps for `seconds` (rounded to whole steps).
    void run(double seconds) {
        const auto n = static_cast<long>(seconds / dynamics->dtS() + 0.5);
        for (long k = 0; k < n; ++k) {
            dynamics->step();
        }
    }
    /// Body i's state.
    const BodyState& body(std::size_t i) const { return dynamics->bodies()[i]; }
};

/// Options with sleeping off: what the solver alone does.
inline DynamicsOptions awake() {
    DynamicsOptions o;
    o.sleepAfterS = 0.0;
    return o;
}

/// A closed 20 cm box of static walls (6 boxes, ids 1-6) with spheres and boxes bouncing
/// inside at e = 1 and e = 0.5, launched in different directions at up to 1.5 m/s.
inline std::vector<SceneObject> closedBoxScene() {
    std::vector<SceneObject> o;
    const double h = 0.1, t = 0.01;
    const Material wall = frictionOf(0.4, 0.3);
    o.push_back(makeBox(1, Vec3(0, -h - t, 0), Vec3(h + t, t, h + t), Quat(1, 0, 0, 0), wall));
    o.push_back(makeBox(2, Vec3(0, h + t, 0), Vec3(h + t, t, h + t), Quat(1, 0, 0, 0), wall));
    o.push_back(makeBox(3, Vec3(-h - t, 0, 0), Vec3(t, h, h + t), Quat(1, 0, 0, 0), wall));
    o.push_back(makeBox(4, Vec3(h + t, 0, 0), Vec3(t, h, h + t), Quat(1, 0, 0, 0), wall));
    o.push_back(makeBox(5, Vec3(0, 0, -h - t), Vec3(h, h, t), Quat(1, 0, 0, 0), wall));
    o.push_back(makeBox(6, Vec3(0, 0, h + t), Vec3(h, h, t), Quat(1, 0, 0, 0), wall));
    const Material mat = frictionOf(0.3, 0.2);
    for (int k = 0; k < 6; ++k) {
        const double e = k % 2 == 0 ? 1.0 : 0.5;
        const Vec3 c(-0.06 + 0.024 * k, 0.03 * ((k % 3) - 1), 0.02 * ((k % 2) ? 1 : -1));
        SceneObject b = k < 3
                            ? dynamicSphere(10 + k, c, 0.01, 0.05, mat, e)
                            : dynamicBox(10 + k, c, Vec3(0.008, 0.01, 0.009), 0.06, mat,
                                         glm::angleAxis(0.3 * k, glm::normalize(Vec3(1, 2, 3))), e);
        b.body.velocity = Vec3(1.5 * std::cos(1.1 * k), 0.8 * std::sin(0.7 * k), 0.5);
        b.body.angularVelocity = Vec3(0.0, 3.0 * k, 1.0);
        o.push_back(b);
    }
    return o;
}

} // namespace hapto::test
