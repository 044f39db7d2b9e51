// Contacts: the narrow phase over the broad phase's pairs, then each contact's constants for
// the solve (effective masses, tangents, speculative target), warm started from the previous
// step.
//
// Design note. Every candidate pair goes through collide() (Contact.h) with a margin of the
// speculative margin plus the distance the pair can close in one step, so a contact exists
// before the surfaces meet and its constraint vn >= -separation/dt lets a body arrive exactly
// at the surface but never through it, whatever its speed (speculative contacts: Catto,
// "Continuous Collision", GDC 2013; no tunnelling at 2 m/s into a 2 mm slab). A contact is
// matched to last step's by its pair, its feature and the nearest point (within 2 mm): the
// match carries the accumulated normal impulse (warm starting, Catto 2005) and an approach
// speed a speculative stop left for restitution; friction is per manifold (DynamicsFriction).
// Pair values: friction coefficients are the smaller of the two materials'
// (static and dynamic separately, as the scene format defines for hands); restitution is the
// larger of the two (BodyProperties: a static object's is 0, so a bouncy body bounces on any
// floor). Invariants: contacts are appended in body, candidate, manifold order; the arrays
// never grow past their constructor capacity.

#include "DynamicsImpl.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>

namespace hapto::dyn {

namespace {

// How far a body's surface can move in one step (m): (|v| + |w| r) dt.
double reachM(const BodyWork& w, const BodyState& b, double dtS) noexcept {
    if (!moves(b) || w.sweptBox.isEmpty()) {
        return 0.0;
    }
    const double r = glm::length(w.sweptBox.halfExtents());
    return (glm::length(b.velocity) + glm::length(b.angularVelocity) * r) * dtS;
}

void appendManifold(const ContactManifold& m, std::uint32_t a, std::uint32_t b, std::uint32_t item,
                    Dynamics::Impl& impl) noexcept {
    FrictionPatch patch;
    patch.a = a;
    patch.b = b;
    patch.item = item;
    patch.first = static_cast<std::uint32_t>(impl.contacts.size());
    for (int k = 0; k < m.count; ++k) {
        if (impl.contacts.size() == impl.contacts.capacity()) {
            ++impl.droppedContacts;
            continue;
        }
        ContactWork c;
        c.a = a;
        c.b = b;
        c.item = item;
        c.feature = m.points[k].feature;
        c.point = m.points[k].position;
        c.normal = m.points[k].normal;
        c.separation = m.points[k].separation;
        c.startSeparation = c.separation;
        impl.contacts.push_back(c);
    }
    patch.count = static_cast<std::uint32_t>(impl.contacts.size()) - patch.first;
    if (patch.count > 0) {
        impl.patches.push_back(patch); // as many patches as contacts at most: room enough
    }
}

} // namespace

void findContacts(const Scene& scene, std::span<const BodyState> bodies, Dynamics::Impl& impl,
                  const DynamicsOptions& options, double dtS) noexcept {
    impl.contacts.clear();
    impl.patches.clear();
    ContactManifold manifold;
    for (const Candidate& c : impl.candidates) {
        const BodyWork& w = impl.work[c.body];
        const double margin = options.speculativeMarginM + reachM(w, bodies[c.body], dtS);
        collide(placeShape(w, bodies[c.body]), staticShape(scene, c.item), margin, manifold);
        appendManifold(manifold, c.body, kStaticSide, c.item, impl);
    }
    for (std::uint32_t i = 0; i < bodies.size(); ++i) {
        for (std::uint32_t j = i + 1; j < bodies.size(); ++j) {
            if ((!moves(bodies[i]) && !moves(bodies[j])) ||
                !sweptBoxesOverlap(impl.work[i], impl.work[j])) {
                continue;
            }
            const double margin = options.speculativeMarginM +
                                  reachM(impl.work[i], bodies[i], dtS) +
                                  reachM(impl.work[j], bodies[j], dtS);
            collide(placeShape(impl.work[i], bodies[i]), placeShape(impl.work[j], bodies[j]),
                    margin, manifold);
            appendManifold(manifold, i, j, 0, impl);
        }
    }
}

namespace {

// 1 / (the inverse effective mass along n at the contact).
double normalMassOf(const ContactWork& c, const BodySide& a, const BodySide& b) noexcept {
    const Vec3 ra = glm::cross(c.rA, c.normal), rb = glm::cross(c.rB, c.normal);
    const double k =
        a.invMass + b.invMass + glm::dot(ra, a.invInertia * ra) + glm::dot(rb, b.invInertia * rb);
    return k > 0.0 ? 1.0 / k : 0.0;
}

// The previous step's contact that matches c, or null.
const ContactWork* matchOf(const ContactWork& c,
                           const std::vector<ContactWork>& previous) noexcept {
    constexpr double kMatchM = 2e-3; // a contact point moves far less than this in one step
    const ContactWork* best = nullptr;
    double bestD2 = kMatchM * kMatchM;
    for (const ContactWork& p : previous) {
        if (p.a != c.a || p.b != c.b || p.item != c.item || p.feature != c.feature) {
            continue;
        }
        const Vec3 d = p.point - c.point;
        const double d2 = glm::dot(d, d);
        if (d2 < bestD2) {
            bestD2 = d2;
            best = &p;
        }
    }
    return best;
}

} // namespace

void prepareContacts(std::span<BodyState> bodies, Dynamics::Impl& impl, const DynamicsOptions&,
                     double dtS) noexcept {
    for (ContactWork& c : impl.contacts) {
        c.rA = c.point - bodies[c.a].position;
        c.rB = c.b == kStaticSide ? Vec3(0.0) : c.point - bodies[c.b].position;
        c.normalMass =
            normalMassOf(c, sideOf(bodies, impl.work, c.a), sideOf(bodies, impl.work, c.b));
        const double otherE =
            c.b == kStaticSide ? staticMaterial(impl, c.item).z : impl.work[c.b].restitution;
        c.restitution = std::max(impl.work[c.a].restitution, otherE);
        c.preNormalVelocity = glm::dot(relativeVelocity(c, bodies, impl.work, false), c.normal);
        c.restitutionVelocity = c.preNormalVelocity;
        c.speculativeTarget = c.separation > 0.0 ? -c.separation / dtS : 0.0;
        if (const ContactWork* p = matchOf(c, impl.previous)) {
            c.normalImpulse = p->normalImpulse;
            c.restitutionVelocity = std::min(c.preNormalVelocity, p->bounceVelocity);
        }
        applyImpulse(c, c.normalImpulse * c.normal, bodies, impl.work, false);
    }
}

} // namespace hapto::dyn
