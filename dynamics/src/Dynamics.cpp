#include "hapto/dynamics/Dynamics.h"

#include <glm/gtc/quaternion.hpp>

namespace hapto {

// A first cut: gravity only, symplectic Euler. The solver (contacts, friction, restitution,
// sleeping) replaces it.
struct Dynamics::Impl {
    std::vector<Vec3> pendingImpulse; // by body (N s)
    std::vector<Vec3> pendingAngular; // by body (N m s)
};

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
    }
    mStats.resize(mBodies.size());
    mImpl->pendingImpulse.assign(mBodies.size(), Vec3(0.0));
    mImpl->pendingAngular.assign(mBodies.size(), Vec3(0.0));
}

Dynamics::~Dynamics() = default;

void Dynamics::step() noexcept {
    const Vec3 g = mScene->physics().gravity;
    for (std::size_t i = 0; i < mBodies.size(); ++i) {
        BodyState& b = mBodies[i];
        const double m = mScene->object(b.slot).body.massKg;
        b.velocity += mImpl->pendingImpulse[i] / m + g * mDtS;
        mImpl->pendingImpulse[i] = Vec3(0.0);
        mImpl->pendingAngular[i] = Vec3(0.0);
        b.position += b.velocity * mDtS;
    }
    ++mSteps;
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
    return 0.5 * m * glm::dot(b.velocity, b.velocity) -
           m * glm::dot(mScene->physics().gravity, b.position);
}

void Dynamics::objectPose(std::size_t i, Vec3& center, Quat& rotation) const noexcept {
    const BodyState& b = mBodies[i];
    rotation = b.orientation;
    center =
        b.position - glm::mat3_cast(b.orientation) * mScene->object(b.slot).body.centerOfMassLocal;
}

void Dynamics::applyImpulse(std::size_t i, const Vec3& linearNs, const Vec3& angularNms) noexcept {
    mImpl->pendingImpulse[i] += linearNs;
    mImpl->pendingAngular[i] += angularNms;
    mBodies[i].sleeping = false;
}

void Dynamics::wake(std::size_t i) noexcept {
    mBodies[i].sleeping = false;
}

} // namespace hapto
