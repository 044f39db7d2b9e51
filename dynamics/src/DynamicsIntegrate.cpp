// Integration: the hands' impulses, gravity, and symplectic (semi-implicit) Euler on the
// poses, with world-frame inertia.
//
// Design note. Velocities are updated first (gravity, then the contact solve), and positions
// move with the new velocities: symplectic Euler, which keeps the energy of an undamped
// oscillator bounded where explicit Euler lets it grow (Hairer, Lubich and Wanner, Geometric
// Numerical Integration, 2nd ed., sec. I.1.2). The orientation integrates q' = q + dt/2 (0, w) q
// and is renormalised every step, so it stays a unit quaternion. The inverse inertia is used in
// world axes, R I^-1 R^T, recomputed once a pose changes. The gyroscopic term w x Iw is left
// out (as in Box2D and Catto 2005): for the nearly symmetric bodies here it is small, and
// leaving it out cannot add energy. Invariants: a sleeping body does not move; no allocation.

#include "DynamicsImpl.h"

#include <glm/gtc/quaternion.hpp>

namespace hapto::dyn {

void updateWorldInertia(std::span<const BodyState> bodies, std::vector<BodyWork>& work) noexcept {
    for (std::size_t i = 0; i < bodies.size(); ++i) {
        const Mat3 r = glm::mat3_cast(bodies[i].orientation);
        work[i].invInertiaWorld = r * work[i].invInertiaLocal * glm::transpose(r);
    }
}

// Kinetic energy of body i (J), from its inverse mass and world inverse inertia.
static double kineticJ(const BodyState& b, const BodyWork& w) noexcept {
    const Mat3 inertia = glm::inverse(w.invInertiaWorld);
    return 0.5 * glm::dot(b.velocity, b.velocity) / w.invMass +
           0.5 * glm::dot(b.angularVelocity, inertia * b.angularVelocity);
}

void applyPendingImpulses(std::span<BodyState> bodies, std::vector<BodyWork>& work) noexcept {
    for (std::size_t i = 0; i < bodies.size(); ++i) {
        BodyWork& w = work[i];
        if (w.pendingLinear == Vec3(0.0) && w.pendingAngular == Vec3(0.0)) {
            continue;
        }
        BodyState& b = bodies[i];
        const double before = kineticJ(b, w);
        b.velocity += w.pendingLinear * w.invMass;
        b.angularVelocity += w.invInertiaWorld * w.pendingAngular;
        w.handWorkJ += kineticJ(b, w) - before; // the hands' work is exactly this change
        w.pendingLinear = Vec3(0.0);
        w.pendingAngular = Vec3(0.0);
        b.sleeping = false;
        w.stillS = 0.0;
    }
}

void integrateVelocities(std::span<BodyState> bodies, const Vec3& gravity, double dtS) noexcept {
    for (BodyState& b : bodies) {
        if (moves(b)) {
            b.velocity += gravity * dtS;
        }
    }
}

void integratePositions(std::span<BodyState> bodies, std::vector<BodyWork>& work,
                        double dtS) noexcept {
    for (std::size_t i = 0; i < bodies.size(); ++i) {
        BodyState& b = bodies[i];
        BodyWork& w = work[i];
        if (moves(b)) {
            b.position += (b.velocity + w.pseudoV) * dtS;
            const Vec3 spin = b.angularVelocity + w.pseudoW;
            const Quat dq = Quat(0.0, spin.x, spin.y, spin.z) * b.orientation;
            b.orientation = glm::normalize(b.orientation + dq * (0.5 * dtS));
        }
        w.pseudoV = Vec3(0.0);
        w.pseudoW = Vec3(0.0);
    }
}

} // namespace hapto::dyn
