// The contact solve: sequential impulses with accumulated clamping on the velocities, then
// restitution, then split impulses on the positions.
//
// Design note. Velocity passes (Catto, "Iterative Dynamics with Temporal Coherence", GDC
// 2005): each pass visits every contact in order, friction first, then the normal. The normal
// impulse accumulated over the passes is clamped to >= 0 (a contact pushes, never pulls), and
// its target is vn >= -separation/dt for a speculative contact (apart) or vn >= 0 for a
// touching one. Friction is solved per manifold before its points' normals
// (DynamicsFriction.cpp). Restitution runs after the passes, on touching contacts
// that closed faster than the threshold and pushed: the normal velocity is driven to -e vn_before
// (Box2D v3's relax-then-restitute order), so e <= 1 cannot return more than the approach
// speed. Position passes (split impulse, as Bullet's btSequentialImpulseConstraintSolver):
// overlap beyond the slop is removed by a fraction per step through pseudo velocities, which
// move the bodies this step and are then discarded, so correction adds no kinetic energy; a
// sticking patch's drift from its static anchor is corrected the same way. Invariants: no
// allocation; the order of visits is the contact array's, so runs are bit-identical.

#include "DynamicsImpl.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>

namespace hapto::dyn {

namespace {

// One normal step on c towards normal velocity `target` (pseudo or real).
void solveNormal(ContactWork& c, std::span<BodyState> bodies, std::vector<BodyWork>& work,
                 bool pseudo, double target) noexcept {
    const double vn = glm::dot(relativeVelocity(c, bodies, work, pseudo), c.normal);
    double& acc = pseudo ? c.pseudoImpulse : c.normalImpulse;
    const double old = acc;
    acc = std::max(old + c.normalMass * (target - vn), 0.0);
    applyImpulse(c, (acc - old) * c.normal, bodies, work, pseudo);
}

} // namespace

void solveVelocities(std::span<BodyState> bodies, Dynamics::Impl& impl,
                     const DynamicsOptions& options) noexcept {
    for (int pass = 0; pass < options.velocityIterations; ++pass) {
        for (FrictionPatch& f : impl.patches) {
            solvePatchFriction(f, bodies, impl);
            for (std::uint32_t k = f.first; k < f.first + f.count; ++k) {
                ContactWork& c = impl.contacts[k];
                solveNormal(c, bodies, impl.work, false, c.speculativeTarget);
            }
        }
    }
    for (ContactWork& c : impl.contacts) {
        // Only once touching: a speculative stop leaves the body at the surface and hands its
        // approach speed to the next step (finishContacts), so a bounce starts from the
        // surface, not from up to v dt above it (which would gain up to 2 m g v dt).
        if (c.restitution > 0.0 && c.normalImpulse > 0.0 && c.separation <= kTouchM &&
            c.restitutionVelocity < -options.restitutionThresholdMPerS) {
            solveNormal(c, bodies, impl.work, false, -c.restitution * c.restitutionVelocity);
        }
    }
}

void solvePositions(std::span<BodyState> bodies, Dynamics::Impl& impl,
                    const DynamicsOptions& options, double dtS) noexcept {
    const double rate = options.positionCorrection / dtS;
    for (int pass = 0; pass < options.velocityIterations; ++pass) {
        for (FrictionPatch& f : impl.patches) {
            solvePatchAnchor(f, bodies, impl, rate);
            for (std::uint32_t k = f.first; k < f.first + f.count; ++k) {
                ContactWork& c = impl.contacts[k];
                const double overlap = -c.separation - options.penetrationSlopM;
                if (overlap > 0.0) {
                    solveNormal(c, bodies, impl.work, true, rate * overlap);
                }
            }
        }
    }
    for (ContactWork& c : impl.contacts) { // the separation the step will leave
        const Vec3 v = relativeVelocity(c, bodies, impl.work, false) +
                       relativeVelocity(c, bodies, impl.work, true);
        c.separation += glm::dot(v, c.normal) * dtS;
    }
}

} // namespace hapto::dyn
