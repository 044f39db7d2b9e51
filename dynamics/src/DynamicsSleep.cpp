// After the move: each friction patch's state for the next step, sleeping and waking.
//
// Design note. Each friction patch decides whether it sticks next step (finishPatches). A
// speculative contact that stopped a
// fast approach hands the approach speed to the next step (bounceVelocity), where the body
// touches and restitution acts on it. A body
// falls asleep after sleepAfterS below both sleep thresholds (its velocities are then zeroed
// and it acts as a static object: infinite mass in every contact) and wakes when an impulse
// reaches it (applyImpulse) or when a moving awake body touches it (separation <= 0 after the
// step). Sleeping is per body (no islands): a body resting on a sleeping one is supported as
// by the floor. A sleeping body's resting manifolds are carried from step to step unchanged
// (carrySleepingPatches), so it wakes warm started. Invariants: no allocation; this step's contacts
// become `previous` by a swap of two vectors of equal capacity.

#include "DynamicsImpl.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace hapto::dyn {

namespace {

// The normal velocity (< 0) at which a contact stopped short by its speculative constraint
// would have reached the surface: its approach before this step's gravity, v0, accelerated
// over the gap s by the gravity along the normal, gn (v^2 = v0^2 - 2 gn s; gn counts only
// when b cannot fall with a). Reflecting this speed, not the one after the step's gravity,
// keeps a bounce at e = 1 from gaining g dt of speed.
double arrivalVelocity(const ContactWork& c, std::span<const BodyState> bodies, const Vec3& g,
                       double dtS) noexcept {
    const bool bFalls = c.b != kStaticSide && moves(bodies[c.b]);
    const double gn = bFalls ? 0.0 : glm::dot(g, c.normal);
    const double v0 = c.preNormalVelocity - gn * dtS;
    return -std::sqrt(std::max(v0 * v0 - 2.0 * gn * c.startSeparation, 0.0));
}

// A sleeping body keeps the manifolds it rested on (against static items or other sleeping
// bodies) as they were when it fell asleep: the broad phase skips it, so without this they
// would be gone when it wakes, and its first step awake would solve its supports cold (no
// warm start, new friction anchors), a jolt of a few nanometres sideways. Carried within the
// arrays' capacity, in patch order.
void carrySleepingPatches(std::span<const BodyState> bodies, Dynamics::Impl& impl) noexcept {
    for (const FrictionPatch& p : impl.previousPatches) {
        const bool asleep = bodies[p.a].sleeping && (p.b == kStaticSide || bodies[p.b].sleeping);
        if (!asleep || impl.patches.size() == impl.patches.capacity() ||
            impl.contacts.size() + p.count > impl.contacts.capacity()) {
            continue;
        }
        FrictionPatch kept = p;
        kept.first = static_cast<std::uint32_t>(impl.contacts.size());
        for (std::uint32_t k = p.first; k < p.first + p.count; ++k) {
            impl.contacts.push_back(impl.previous[k]);
            impl.contacts.back().bounceVelocity = 0.0;
        }
        impl.patches.push_back(kept);
    }
}

} // namespace

void finishContacts(std::span<const BodyState> bodies, Dynamics::Impl& impl,
                    const DynamicsOptions& options, double dtS) noexcept {
    finishPatches(bodies, impl, options);
    const Vec3 g = impl.scene->physics().gravity;
    for (ContactWork& c : impl.contacts) {
        c.bounceVelocity = 0.0;
        if (c.startSeparation > kTouchM && c.normalImpulse > 0.0 && c.restitution > 0.0) {
            c.bounceVelocity = arrivalVelocity(c, bodies, g, dtS);
        }
    }
    carrySleepingPatches(bodies, impl);
    std::swap(impl.contacts, impl.previous);
    std::swap(impl.patches, impl.previousPatches);
    impl.contacts.clear();
    impl.patches.clear();
}

namespace {

bool isStill(const BodyState& b, const DynamicsOptions& o) noexcept {
    return glm::length(b.velocity) < o.sleepSpeedMPerS &&
           glm::length(b.angularVelocity) < o.sleepAngularRadPerS;
}

// Wakes a sleeping side of c when the other side is an awake, moving body touching it.
void wakeByTouch(const ContactWork& c, std::span<BodyState> bodies,
                 std::vector<BodyWork>& work) noexcept {
    if (c.b == kStaticSide || c.separation > 0.0) {
        return;
    }
    auto touch = [&](std::uint32_t sleeper, std::uint32_t toucher) {
        if (bodies[sleeper].sleeping && !bodies[toucher].sleeping && work[toucher].stillS == 0.0) {
            bodies[sleeper].sleeping = false;
            work[sleeper].stillS = 0.0;
        }
    };
    touch(c.a, c.b);
    touch(c.b, c.a);
}

} // namespace

void updateSleep(std::span<BodyState> bodies, Dynamics::Impl& impl, const DynamicsOptions& options,
                 double dtS) noexcept {
    for (std::size_t i = 0; i < bodies.size(); ++i) {
        BodyState& b = bodies[i];
        BodyWork& w = impl.work[i];
        if (b.sleeping) {
            continue;
        }
        w.stillS = isStill(b, options) ? w.stillS + dtS : 0.0;
        if (options.sleepAfterS > 0.0 && w.stillS >= options.sleepAfterS) {
            b.sleeping = true;
            b.velocity = Vec3(0.0);
            b.angularVelocity = Vec3(0.0);
        }
    }
    for (const ContactWork& c : impl.previous) {
        wakeByTouch(c, bodies, impl.work);
    }
}

} // namespace hapto::dyn
