// Friction: one Coulomb cone and one torsional limit per manifold (patch friction), static
// anchors, and whether each patch sticks or slides.
//
// Design note. A patch sits at the centroid of its manifold's points with the mean normal.
// Its tangential impulse (two tangents) is clamped to the disc mu sum(lambda_n) and its twist
// impulse about the normal to mu sum(lambda_n) r, r the points' mean distance from the
// centroid (a uniform pressure over a disc of radius R gives 2/3 mu N R; the mean distance of
// points on its rim is R, so this is the rim's bound, a little above the disc's). mu is the
// static coefficient while the patch sticks and the dynamic one while it slides. A sticking
// patch remembers where it stuck (its anchor, in both bodies' frames) and the position pass
// pulls drift back towards it with pseudo impulses bounded by mu_s sum(lambda_n), so resting
// and held bodies do not creep. State: a sticking patch slides once friction reaches the cone's
// edge; a sliding one sticks once friction stayed inside the cone and the centroid's
// tangential speed fell below stickSpeedMPerS. Patches are matched to last step's by pair
// (bodies and item): a pair makes one manifold. Invariants: no allocation; the patch order is
// the contact order.

#include "DynamicsImpl.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cmath>

namespace hapto::dyn {

namespace {

// Unit tangents t1, t2 with (t1, t2, n) right-handed, a function of n alone (Frisvad, "Building
// an Orthonormal Basis from a 3D Unit Vector Without Normalization", JGT 2012, with the sign
// fix of Duff et al., JCGT 2017): the same normal gives the same tangents every step.
void tangentsOf(const Vec3& n, Vec3& t1, Vec3& t2) noexcept {
    const double s = std::copysign(1.0, n.z);
    const double a = -1.0 / (s + n.z);
    const double b = n.x * n.y * a;
    t1 = Vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
    t2 = Vec3(b, s + n.y * n.y * a, -n.y);
}

double massAlong(const FrictionPatch& c, const Vec3& d, const BodySide& a,
                 const BodySide& b) noexcept {
    const Vec3 ra = glm::cross(c.rA, d), rb = glm::cross(c.rB, d);
    const double k =
        a.invMass + b.invMass + glm::dot(ra, a.invInertia * ra) + glm::dot(rb, b.invInertia * rb);
    return k > 0.0 ? 1.0 / k : 0.0;
}

void placePatch(FrictionPatch& f, std::span<const BodyState> bodies,
                const std::vector<ContactWork>& contacts) noexcept {
    Vec3 sum(0.0), normal(0.0);
    for (std::uint32_t k = f.first; k < f.first + f.count; ++k) {
        sum += contacts[k].point;
        normal += contacts[k].normal;
    }
    f.point = sum / static_cast<double>(f.count);
    f.normal = glm::length(normal) > 0.0 ? glm::normalize(normal) : contacts[f.first].normal;
    double radius = 0.0;
    for (std::uint32_t k = f.first; k < f.first + f.count; ++k) {
        radius += glm::length(contacts[k].point - f.point);
    }
    f.radiusM = radius / static_cast<double>(f.count);
    tangentsOf(f.normal, f.t1, f.t2);
    f.rA = f.point - bodies[f.a].position;
    f.rB = f.b == kStaticSide ? Vec3(0.0) : f.point - bodies[f.b].position;
}

void anchorHere(FrictionPatch& f, std::span<const BodyState> bodies) noexcept {
    const BodyState& a = bodies[f.a];
    f.anchorA = glm::conjugate(a.orientation) * (f.point - a.position);
    if (f.b == kStaticSide) {
        f.anchorB = f.point;
    } else {
        const BodyState& b = bodies[f.b];
        f.anchorB = glm::conjugate(b.orientation) * (f.point - b.position);
    }
}

const FrictionPatch* matchOf(const FrictionPatch& f,
                             const std::vector<FrictionPatch>& previous) noexcept {
    for (const FrictionPatch& p : previous) {
        if (p.a == f.a && p.b == f.b && p.item == f.item) {
            return &p;
        }
    }
    return nullptr;
}

double normalSum(const FrictionPatch& f, const std::vector<ContactWork>& contacts) noexcept {
    double sum = 0.0;
    for (std::uint32_t k = f.first; k < f.first + f.count; ++k) {
        sum += contacts[k].normalImpulse;
    }
    return sum;
}

double tangentialSpeed(const FrictionPatch& f, std::span<const BodyState> bodies,
                       const std::vector<BodyWork>& work) noexcept {
    const Vec3 v = relativeVelocity(f, bodies, work, false);
    return glm::length(v - glm::dot(v, f.normal) * f.normal);
}

// Clamps the pair (x, y) to the disc of radius cap.
void clampToDisc(double& x, double& y, double cap) noexcept {
    const double len2 = x * x + y * y;
    if (len2 > cap * cap) {
        const double s = len2 > 0.0 ? cap / std::sqrt(len2) : 0.0;
        x *= s;
        y *= s;
    }
}

} // namespace

void preparePatches(std::span<BodyState> bodies, Dynamics::Impl& impl,
                    const DynamicsOptions& options) noexcept {
    for (FrictionPatch& f : impl.patches) {
        placePatch(f, bodies, impl.contacts);
        const BodySide a = sideOf(bodies, impl.work, f.a), b = sideOf(bodies, impl.work, f.b);
        f.tangentMass1 = massAlong(f, f.t1, a, b);
        f.tangentMass2 = massAlong(f, f.t2, a, b);
        const double k = glm::dot(f.normal, (a.invInertia + b.invInertia) * f.normal);
        f.twistMass = k > 0.0 ? 1.0 / k : 0.0;
        const Vec3 other = f.b == kStaticSide ? staticMaterial(impl, f.item)
                                              : Vec3(impl.work[f.b].staticFriction,
                                                     impl.work[f.b].dynamicFriction, 0.0);
        f.staticMu = std::min(impl.work[f.a].staticFriction, other.x);
        f.dynamicMu = std::min(impl.work[f.a].dynamicFriction, other.y);
        const FrictionPatch* p = matchOf(f, impl.previousPatches);
        if (p != nullptr) {
            f.impulse1 = p->impulse1;
            f.impulse2 = p->impulse2;
            f.twistImpulse = p->twistImpulse;
            f.sticking = p->sticking;
            f.anchorA = p->anchorA;
            f.anchorB = p->anchorB;
        } else {
            f.sticking = tangentialSpeed(f, bodies, impl.work) < options.stickSpeedMPerS;
        }
        if (p == nullptr || !f.sticking) {
            anchorHere(f, bodies);
        }
        applyImpulse(f, f.impulse1 * f.t1 + f.impulse2 * f.t2, bodies, impl.work, false);
        applyAngular(f, f.twistImpulse * f.normal, bodies, impl.work);
    }
}

void solvePatchFriction(FrictionPatch& f, std::span<BodyState> bodies,
                        Dynamics::Impl& impl) noexcept {
    const double cap = (f.sticking ? f.staticMu : f.dynamicMu) * normalSum(f, impl.contacts);
    const Vec3 v = relativeVelocity(f, bodies, impl.work, false);
    const double old1 = f.impulse1, old2 = f.impulse2;
    f.impulse1 -= f.tangentMass1 * glm::dot(v, f.t1);
    f.impulse2 -= f.tangentMass2 * glm::dot(v, f.t2);
    clampToDisc(f.impulse1, f.impulse2, cap);
    applyImpulse(f, (f.impulse1 - old1) * f.t1 + (f.impulse2 - old2) * f.t2, bodies, impl.work,
                 false);
    const auto spin = [&](std::uint32_t i) {
        return i == kStaticSide || !moves(bodies[i]) ? Vec3(0.0) : bodies[i].angularVelocity;
    };
    const double twist = glm::dot(spin(f.a) - spin(f.b), f.normal);
    const double oldTwist = f.twistImpulse;
    const double twistCap = cap * f.radiusM;
    f.twistImpulse = std::clamp(oldTwist - f.twistMass * twist, -twistCap, twistCap);
    applyAngular(f, (f.twistImpulse - oldTwist) * f.normal, bodies, impl.work);
}

void solvePatchAnchor(FrictionPatch& f, std::span<BodyState> bodies, Dynamics::Impl& impl,
                      double rate) noexcept {
    const double n = normalSum(f, impl.contacts);
    if (!f.sticking || n <= 0.0) {
        return;
    }
    const BodyState& a = bodies[f.a];
    Vec3 drift = a.position + a.orientation * f.anchorA - f.anchorB;
    if (f.b != kStaticSide) {
        const BodyState& b = bodies[f.b];
        drift = a.position + a.orientation * f.anchorA - (b.position + b.orientation * f.anchorB);
    }
    const Vec3 v = relativeVelocity(f, bodies, impl.work, true);
    const double old1 = f.pseudo1, old2 = f.pseudo2;
    f.pseudo1 += f.tangentMass1 * (-rate * glm::dot(drift, f.t1) - glm::dot(v, f.t1));
    f.pseudo2 += f.tangentMass2 * (-rate * glm::dot(drift, f.t2) - glm::dot(v, f.t2));
    clampToDisc(f.pseudo1, f.pseudo2, f.staticMu * n);
    applyImpulse(f, (f.pseudo1 - old1) * f.t1 + (f.pseudo2 - old2) * f.t2, bodies, impl.work, true);
}

void finishPatches(std::span<const BodyState> bodies, Dynamics::Impl& impl,
                   const DynamicsOptions& options) noexcept {
    for (FrictionPatch& f : impl.patches) {
        const double n = normalSum(f, impl.contacts);
        const bool slow = tangentialSpeed(f, bodies, impl.work) < options.stickSpeedMPerS;
        if (n > 0.0) {
            const double cap = (f.sticking ? f.staticMu : f.dynamicMu) * n;
            const double t2 = f.impulse1 * f.impulse1 + f.impulse2 * f.impulse2;
            const bool inside = t2 < cap * cap * (1.0 - 1e-9);
            f.sticking = f.sticking ? inside : inside && slow;
        } else {
            f.sticking = slow;
        }
    }
}

} // namespace hapto::dyn
