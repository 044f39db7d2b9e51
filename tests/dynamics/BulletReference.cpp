// Bullet 3.24 (double precision) and hapto::Dynamics over the same Scene, and the reference
// scenarios. What each Bullet setting means and why: BulletReference.h's design note.
#include "BulletReference.h"

#include "hapto/index/DefaultIndex.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/MassProperties.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

namespace hapto::reference {
namespace {

static_assert(sizeof(btScalar) == sizeof(double), "the reference links Bullet's float64 build");

btVector3 toBullet(const Vec3& v) {
    return {v.x, v.y, v.z};
}
Vec3 fromBullet(const btVector3& v) {
    return {v.x(), v.y(), v.z()};
}

/// hapto's pair rule instead of Bullet's products (btManifoldResult.cpp): the smaller friction,
/// the larger restitution. Each object carries its own coefficient (setFriction/Restitution).
bool haptoMaterialRule(btManifoldPoint& cp, const btCollisionObjectWrapper* a, int, int,
                       const btCollisionObjectWrapper* b, int, int) {
    const btCollisionObject* oa = a->getCollisionObject();
    const btCollisionObject* ob = b->getCollisionObject();
    cp.m_combinedFriction = std::min(oa->getFriction(), ob->getFriction());
    cp.m_combinedRestitution = std::max(oa->getRestitution(), ob->getRestitution());
    return true;
}

/// The world and everything it owns; bodies leave the world before they are destroyed.
struct BulletWorld {
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher{&config};
    btDbvtBroadphase broadphase;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &config};
    std::vector<std::unique_ptr<btCollisionShape>> shapes;
    std::vector<std::unique_ptr<btRigidBody>> bodies;
    std::vector<std::size_t> dynamicBodies; // indices into `bodies`, slot order

    ~BulletWorld() {
        for (auto& body : bodies) {
            world.removeRigidBody(body.get());
        }
    }
};

std::string objectName(const SceneObject& o) {
    return "object " + std::to_string(o.id);
}

std::unique_ptr<btCollisionShape> shapeOf(const SceneObject& o, double marginM) {
    if (o.shape == Shape::Sphere) {
        return std::make_unique<btSphereShape>(o.halfExtents.x); // margin = radius: exact
    }
    if (o.shape != Shape::Box) {
        throw std::invalid_argument("runBullet: " + objectName(o) +
                                    " is a mesh; the reference takes boxes and spheres");
    }
    auto box = std::make_unique<btBoxShape>(toBullet(o.halfExtents));
    box->setMargin(marginM); // keeps the outer half extents (btBoxShape::setMargin)
    return box;
}

/// The principal moments of a dynamic object's inertia (kg m^2); throws unless diagonal.
btVector3 principalInertia(const SceneObject& o) {
    const Mat3& i = o.body.inertia;
    if (i[0][1] != 0.0 || i[0][2] != 0.0 || i[1][2] != 0.0 || i[1][0] != 0.0 || i[2][0] != 0.0 ||
        i[2][1] != 0.0) {
        throw std::invalid_argument(
            "runBullet: " + objectName(o) +
            " has off-diagonal inertia; the reference takes principal axes");
    }
    if (o.body.centerOfMassLocal != Vec3(0.0)) {
        throw std::invalid_argument("runBullet: " + objectName(o) +
                                    " has its centre of mass off its centre");
    }
    return {i[0][0], i[1][1], i[2][2]};
}

void addObject(BulletWorld& w, const SceneObject& o, const BulletSettings& settings) {
    w.shapes.push_back(shapeOf(o, settings.marginM));
    const bool dynamic = o.body.dynamic;
    const double mass = dynamic ? o.body.massKg : 0.0;
    const btVector3 inertia = dynamic ? principalInertia(o) : btVector3(0, 0, 0);
    btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, w.shapes.back().get(), inertia);
    const Quat& q = o.rotation;
    info.m_startWorldTransform = btTransform(btQuaternion(q.x, q.y, q.z, q.w), toBullet(o.center));
    info.m_friction = o.material.dynamicFriction; // one coefficient: see the header
    info.m_restitution = o.body.restitution;
    info.m_linearDamping = 0.0;
    info.m_angularDamping = 0.0;
    auto body = std::make_unique<btRigidBody>(info);
    if (dynamic) {
        body->setLinearVelocity(toBullet(o.body.velocity));
        body->setAngularVelocity(toBullet(o.body.angularVelocity));
        body->setActivationState(DISABLE_DEACTIVATION);
        body->setCollisionFlags(body->getCollisionFlags() |
                                btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
        w.dynamicBodies.push_back(w.bodies.size());
    }
    w.world.addRigidBody(body.get());
    w.bodies.push_back(std::move(body));
}

BodySample sampleOf(const btRigidBody& body, double timeS) {
    const btTransform& t = body.getWorldTransform();
    const btQuaternion r = t.getRotation();
    return {timeS, fromBullet(t.getOrigin()), Quat(r.w(), r.x(), r.y(), r.z()),
            fromBullet(body.getLinearVelocity()), fromBullet(body.getAngularVelocity())};
}

/// Sets Bullet's two globals for the run (the material rule, the contact breaking factor) and
/// restores them after it.
struct BulletGlobalsScope {
    ContactAddedCallback previousRule = gContactAddedCallback;
    btScalar previousBreaking = gContactBreakingThreshold;
    explicit BulletGlobalsScope(double breakingFactor) {
        gContactAddedCallback = haptoMaterialRule;
        gContactBreakingThreshold = breakingFactor;
    }
    ~BulletGlobalsScope() {
        gContactAddedCallback = previousRule;
        gContactBreakingThreshold = previousBreaking;
    }
    BulletGlobalsScope(const BulletGlobalsScope&) = delete;
    BulletGlobalsScope& operator=(const BulletGlobalsScope&) = delete;
};

/// A dynamic box of kBoxEdgeM and kBoxMassKg (inertia from its solid: MassProperties.h).
SceneObject dynamicBox(ObjectId id, Vec3 center, Quat rotation, Material material) {
    SceneObject box = makeBox(id, center, Vec3(kBoxEdgeM / 2), rotation, material);
    box.body.dynamic = true;
    fillMassProperties(box, kBoxMassKg, std::nullopt, std::nullopt);
    return box;
}

Material frictionOf(double staticFriction, double dynamicFriction) {
    Material m;
    m.staticFriction = staticFriction;
    m.dynamicFriction = dynamicFriction;
    return m;
}

SceneObject floorBox(ObjectId id, Material material) {
    return makeBox(id, Vec3(0.0, kFloorTopY - 0.05, 0.0), Vec3(1.0, 0.05, 1.0), Quat(1, 0, 0, 0),
                   material);
}

Scene sceneOf(std::vector<SceneObject> objects) {
    Scene scene(Aabb{Vec3(-1.0, -0.5, -1.0), Vec3(1.0, 1.0, 1.0)}, std::move(objects));
    scene.setPhysics(ScenePhysics{}); // 1 kHz, g = 9.81 m/s^2 down -y
    return scene;
}

} // namespace

std::vector<Trajectory> runBullet(const Scene& scene, int steps, const BulletSettings& settings) {
    const BulletGlobalsScope globals(settings.contactBreakingFactor); // before any manifold
    BulletWorld w;
    w.world.setGravity(toBullet(scene.physics().gravity));
    btContactSolverInfo& solver = w.world.getSolverInfo();
    solver.m_numIterations = settings.solverIterations;
    solver.m_splitImpulse = 1;
    solver.m_splitImpulsePenetrationThreshold = 0.0; // every penetration by split impulse
    solver.m_erp2 = settings.positionErp;
    for (const SceneObject& o : scene.objects()) {
        addObject(w, o, settings);
    }
    std::vector<Trajectory> out;
    for (std::size_t i : w.dynamicBodies) {
        Trajectory t;
        t.id = scene.object(static_cast<std::uint32_t>(i)).id;
        t.samples.reserve(static_cast<std::size_t>(steps) + 1);
        t.samples.push_back(sampleOf(*w.bodies[i], 0.0));
        out.push_back(std::move(t));
    }
    const double dt = 1.0 / scene.physics().rateHz;
    for (int s = 1; s <= steps; ++s) {
        w.world.stepSimulation(dt, 0); // one internal step of exactly dt
        for (std::size_t k = 0; k < out.size(); ++k) {
            out[k].samples.push_back(sampleOf(*w.bodies[w.dynamicBodies[k]], s * dt));
        }
    }
    return out;
}

std::vector<Trajectory> runHapto(std::shared_ptr<const Scene> scene, int steps,
                                 const DynamicsOptions& options) {
    std::shared_ptr<const SpatialIndex> index =
        buildIndex(*scene, IndexSpec::parse(defaultIndexSpec(*scene)));
    Dynamics dynamics(scene, index, options);
    std::vector<Trajectory> out(dynamics.bodyCount());
    auto record = [&](double timeS) {
        for (std::size_t i = 0; i < out.size(); ++i) {
            const BodyState& b = dynamics.bodies()[i];
            out[i].samples.push_back(
                {timeS, b.position, b.orientation, b.velocity, b.angularVelocity});
        }
    };
    for (std::size_t i = 0; i < out.size(); ++i) {
        out[i].id = dynamics.bodies()[i].id;
        out[i].samples.reserve(static_cast<std::size_t>(steps) + 1);
    }
    record(0.0);
    for (int s = 1; s <= steps; ++s) {
        dynamics.step();
        record(s * dynamics.dtS());
    }
    return out;
}

Scene dropScene(Shape shape, double heightM, double restitution) {
    const Material mu = frictionOf(0.5, 0.5);
    SceneObject body;
    if (shape == Shape::Sphere) {
        body = makeSphere(1, Vec3(0.0, kFloorTopY + heightM + kSphereRadiusM, 0.0), kSphereRadiusM,
                          mu);
        body.body.dynamic = true;
        fillMassProperties(body, kSphereMassKg, std::nullopt, std::nullopt);
    } else {
        body = dynamicBox(1, Vec3(0.0, kFloorTopY + heightM + kBoxEdgeM / 2, 0.0), Quat(1, 0, 0, 0),
                          mu);
    }
    body.body.restitution = restitution;
    return sceneOf({floorBox(0, mu), body});
}

Vec3 rampDownhill(double angleRad) {
    return -Vec3(std::cos(angleRad), std::sin(angleRad), 0.0);
}

Scene rampScene(double angleRad, double staticFriction, double dynamicFriction) {
    const Material mu = frictionOf(staticFriction, dynamicFriction);
    const Quat tilt = glm::angleAxis(angleRad, Vec3(0.0, 0.0, 1.0));
    const Vec3 up = tilt * Vec3(0.0, 1.0, 0.0);
    const double rampHalfThickness = 0.02;
    const SceneObject ramp = makeBox(0, Vec3(0.0), Vec3(0.6, rampHalfThickness, 0.2), tilt, mu);
    const Vec3 start = -0.4 * rampDownhill(angleRad) + up * (rampHalfThickness + kBoxEdgeM / 2);
    return sceneOf({ramp, dynamicBox(1, start, tilt, mu)});
}

Scene stackScene() {
    const Material mu = frictionOf(0.5, 0.5);
    std::vector<SceneObject> objects{floorBox(0, mu)};
    for (int k = 0; k < 3; ++k) {
        const double y = kFloorTopY + kBoxEdgeM * (k + 0.5);
        objects.push_back(
            dynamicBox(static_cast<ObjectId>(k + 1), Vec3(0.0, y, 0.0), Quat(1, 0, 0, 0), mu));
    }
    return sceneOf(std::move(objects));
}

} // namespace hapto::reference
