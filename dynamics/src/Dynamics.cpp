// The dynamics' public face: building the bodies from the scene, the order of one step, the
// energy and penetration book-keeping, and the hands' impulses.
//
// Design note. A step is, in order (Catto, "Iterative Dynamics with Temporal Coherence", GDC
// 2005; Box2D's layout): the hands' pending impulses, gravity into the velocities, the broad
// phase (DynamicsBroadPhase.cpp), the narrow phase and contact preparation with warm starting
// (DynamicsContacts.cpp, DynamicsFriction.cpp), the sequential-impulse velocity passes and
// restitution, the split- impulse position passes (DynamicsSolver.cpp), symplectic Euler on the
// positions (DynamicsIntegrate.cpp), then contact states, sleeping and the statistics
// (DynamicsSleep.cpp). Invariants: the constructor sizes every buffer; step() allocates, locks,
// logs and throws nothing and is a pure function of the state it starts from (bit-identical runs).

#include "DynamicsImpl.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>

namespace hapto {

namespace {

// The inertia tensor of a solid box or sphere about its centre (own axes, kg m^2), for a
// body whose scene gave none: I = m/3 (b^2 + c^2) per axis for half extents a, b, c and
// I = 2/5 m r^2 for a sphere (e.g. Goldstein, Classical Mechanics, 3rd ed., sec. 5.3).
Mat3 solidInertia(const SceneObject& o) {
    const double m = o.body.massKg;
    if (o.shape == Shape::Sphere) {
        return Mat3(0.4 * m * o.halfExtents.x * o.halfExtents.x);
    }
    const Vec3 h2 = o.halfExtents * o.halfExtents;
    Mat3 inertia(0.0);
    inertia[0][0] = m / 3.0 * (h2.y + h2.z);
    inertia[1][1] = m / 3.0 * (h2.x + h2.z);
    inertia[2][2] = m / 3.0 * (h2.x + h2.y);
    return inertia;
}

// The body's constants: inverse mass and inertia, shape, material.
dyn::BodyWork bodyWorkOf(const SceneObject& o) {
    dyn::BodyWork w;
    w.invMass = 1.0 / o.body.massKg;
    const bool given = o.body.inertia[0][0] > 0.0;
    w.invInertiaLocal = glm::inverse(given ? o.body.inertia : solidInertia(o));
    w.comLocal = o.body.centerOfMassLocal;
    w.staticFriction = o.material.staticFriction;
    w.dynamicFriction = o.material.dynamicFriction;
    w.restitution = o.body.restitution;
    if (o.shape == Shape::Sphere) {
        w.shapeTemplate = ConvexShape::sphere(Vec3(0.0), o.halfExtents.x);
    } else if (o.shape == Shape::Box) {
        w.shapeTemplate = ConvexShape::box(Vec3(0.0), Mat3(1.0), o.halfExtents);
    } else {
        // A mesh collides as its convex hull; one without a hull (none given) collides as
        // nothing: no bounding-box stand-in.
        w.shapeTemplate.kind = ConvexShape::Kind::Hull;
        w.shapeTemplate.hull = o.body.hull.get();
    }
    return w;
}

} // namespace

Dynamics::Dynamics(std::shared_ptr<const Scene> scene, std::shared_ptr<const SpatialIndex> index,
                   DynamicsOptions options)
    : mScene(std::move(scene)), mIndex(std::move(index)), mOptions(options),
      mDtS(1.0 / mScene->physics().rateHz), mImpl(std::make_unique<Impl>()) {
    for (std::uint32_t slot = 0; slot < mScene->size(); ++slot) {
        const SceneObject& o = mScene->object(slot);
        if (!o.body.dynamic) {
            continue;
        }
        BodyState b;
        b.id = o.id;
        b.slot = slot;
        b.orientation = o.rotation;
        b.position = o.center + glm::mat3_cast(o.rotation) * o.body.centerOfMassLocal;
        b.velocity = o.body.velocity;
        b.angularVelocity = o.body.angularVelocity;
        mBodies.push_back(b);
        mImpl->work.push_back(bodyWorkOf(o));
    }
    mImpl->scene = mScene.get();
    mImpl->index = mIndex.get();
    mImpl->seenStamp.assign(mScene->itemCount(), 0);
    const std::size_t n = std::max<std::size_t>(mBodies.size(), 1);
    mStats.resize(mBodies.size());
    mImpl->candidates.reserve(n * dyn::kCandidatesPerBody);
    mImpl->contacts.reserve(n * dyn::kContactsPerBody);
    mImpl->previous.reserve(n * dyn::kContactsPerBody);
    mImpl->patches.reserve(n * dyn::kContactsPerBody);
    mImpl->previousPatches.reserve(n * dyn::kContactsPerBody);
    dyn::updateWorldInertia(mBodies, mImpl->work);
    updateEnergyStats();
}

Dynamics::~Dynamics() = default;

void Dynamics::step() noexcept {
    Impl& impl = *mImpl;
    const double dt = mDtS;
    dyn::applyPendingImpulses(mBodies, impl.work);
    dyn::integrateVelocities(mBodies, mScene->physics().gravity, dt);
    dyn::gatherCandidates(*mScene, mBodies, impl, mOptions, dt);
    dyn::findContacts(*mScene, mBodies, impl, mOptions, dt);
    dyn::prepareContacts(mBodies, impl, mOptions, dt);
    dyn::preparePatches(mBodies, impl, mOptions);
    dyn::solveVelocities(mBodies, impl, mOptions);
    dyn::solvePositions(mBodies, impl, mOptions, dt);
    dyn::integratePositions(mBodies, impl.work, dt);
    dyn::updateWorldInertia(mBodies, impl.work);
    dyn::finishContacts(mBodies, impl, mOptions, dt);
    recordPenetration();
    dyn::updateSleep(mBodies, impl, mOptions, dt);
    updateEnergyStats();
    ++mSteps;
}

void Dynamics::recordPenetration() noexcept {
    for (const dyn::ContactWork& c : mImpl->previous) { // finishContacts kept this step's here
        const double depth = -c.separation;
        mStats[c.a].deepestPenetrationM = std::max(mStats[c.a].deepestPenetrationM, depth);
        if (c.b != dyn::kStaticSide) {
            mStats[c.b].deepestPenetrationM = std::max(mStats[c.b].deepestPenetrationM, depth);
        }
    }
}

void Dynamics::updateEnergyStats() noexcept {
    for (std::size_t i = 0; i < mBodies.size(); ++i) {
        dyn::BodyWork& w = mImpl->work[i];
        const double net = energyJ(i) - w.handWorkJ;
        if (!w.energySeen || net < w.minNetEnergyJ) {
            w.minNetEnergyJ = net;
            w.energySeen = true;
        }
        mStats[i].largestEnergyGainJ =
            std::max(mStats[i].largestEnergyGainJ, net - w.minNetEnergyJ);
    }
}

std::optional<std::size_t> Dynamics::bodyOf(ObjectId id) const noexcept {
    for (std::size_t i = 0; i < mBodies.size(); ++i) {
        if (mBodies[i].id == id) {
            return i;
        }
    }
    return std::nullopt;
}

double Dynamics::energyJ(std::size_t i) const noexcept {
    const BodyState& b = mBodies[i];
    const double m = mScene->object(b.slot).body.massKg;
    const Mat3 inertia = glm::inverse(mImpl->work[i].invInertiaWorld);
    return 0.5 * m * glm::dot(b.velocity, b.velocity) +
           0.5 * glm::dot(b.angularVelocity, inertia * b.angularVelocity) -
           m * glm::dot(mScene->physics().gravity, b.position);
}

void Dynamics::objectPose(std::size_t i, Vec3& center, Quat& rotation) const noexcept {
    const BodyState& b = mBodies[i];
    rotation = b.orientation;
    center =
        b.position - glm::mat3_cast(b.orientation) * mScene->object(b.slot).body.centerOfMassLocal;
}

void Dynamics::applyImpulse(std::size_t i, const Vec3& linearNs, const Vec3& angularNms) noexcept {
    // A zero impulse (the runtime hands every body its sum each step, most often nothing)
    // changes nothing and wakes nothing: a body the hands leave alone may fall asleep.
    if (linearNs == Vec3(0.0) && angularNms == Vec3(0.0)) {
        return;
    }
    mImpl->work[i].pendingLinear += linearNs;
    mImpl->work[i].pendingAngular += angularNms;
    wake(i);
}

void Dynamics::wake(std::size_t i) noexcept {
    mBodies[i].sleeping = false;
    mImpl->work[i].stillS = 0.0;
}

std::uint64_t Dynamics::droppedContacts() const noexcept {
    return mImpl->droppedContacts + mImpl->droppedCandidates;
}

} // namespace hapto
