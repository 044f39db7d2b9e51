#pragma once
// The solver's working state and the steps it runs, shared by Dynamics*.cpp (internal header).
//
// Design note. One Dynamics::Impl holds everything a step touches, sized by the constructor:
// per-body constants (inverse mass and inertia, the shape as the narrow phase sees it, the
// material), per-body working values (world inverse inertia, pseudo velocities of the split
// impulse, sleep timers, energy book-keeping), the candidate list of the broad phase and two
// contact arrays (this step's and the previous step's, for warm starting and static anchors).
// Invariants: no vector here grows after the constructor (capacities are fixed; a step that
// would exceed one drops the excess and counts it in `droppedContacts`); every loop runs in
// body-slot, then item, then manifold order, so a step is deterministic bit for bit.

#include "hapto/dynamics/Contact.h"
#include "hapto/dynamics/Dynamics.h"

#include <array>
#include <cstdint>
#include <vector>

namespace hapto::dyn {

/// Marks a contact's other side as the static scene (an index item) rather than a body.
inline constexpr std::uint32_t kStaticSide = 0xFFFFFFFFu;

/// One body's constants and working values.
struct BodyWork {
    double invMass = 0.0;
    Mat3 invInertiaLocal{0.0}; // about the centre of mass, own axes (1/(kg m^2))
    Mat3 invInertiaWorld{0.0};
    ConvexShape shapeTemplate{}; // kind, size, hull; placed each step by placeShape()
    Vec3 comLocal{0.0};          // centre of mass in the object frame (m)
    double staticFriction = 0.0, dynamicFriction = 0.0, restitution = 0.0;
    Vec3 pseudoV{0.0}, pseudoW{0.0}; // split-impulse velocities, discarded after the step
    Vec3 pendingLinear{0.0}, pendingAngular{0.0};
    double stillS = 0.0;        // time spent below the sleep thresholds (s)
    double handWorkJ = 0.0;     // work of applyImpulse's impulses so far (J)
    double minNetEnergyJ = 0.0; // lowest energy minus hand work seen so far (J)
    bool energySeen = false;
    Aabb sweptBox{}; // this step's broad-phase box (m)
    /// The broad phase's cached query (DynamicsBroadPhase.cpp): the static items of every leaf
    /// meeting `box` (plus outsideObjects() when `box` leaves the index's bounds), static
    /// only, each once, ascending. Valid while `count` <= the capacity and the swept box stays
    /// inside `box`: a resting or slow body walks the index once, not every step.
    struct QueryCache {
        static constexpr std::size_t kItems = 128;
        Aabb box = Aabb::empty();
        std::uint32_t count = 0;
        bool valid = false;    // the items are box's
        bool overflow = false; // box's items did not fit: the direct query inside box

        std::array<std::uint32_t, kItems> items{};
    } cache;
};

/// One contact point's normal constraint between body `a` and either body `b` or a static
/// item. Its friction is its patch's (FrictionPatch).
struct ContactWork {
    std::uint32_t a = 0, b = kStaticSide; // bodies; b == kStaticSide: static item
    std::uint32_t item = 0;               // the static item when b == kStaticSide
    std::uint32_t feature = 0;
    Vec3 point{0.0}, normal{0.0};
    Vec3 rA{0.0}, rB{0.0};        // from the centres of mass to the point (m)
    double separation = 0.0;      // signed gap (m); after solvePositions: the step's end
    double startSeparation = 0.0; // the gap the narrow phase found (m)
    double normalMass = 0.0;
    double normalImpulse = 0.0, pseudoImpulse = 0.0; // accumulated (N s)
    double preNormalVelocity = 0.0;                  // vn before the solve (m/s)
    double restitutionVelocity = 0.0; // the approach speed restitution reflects (m/s, < 0)
    double bounceVelocity = 0.0;      // an approach a speculative stop hands to the next step
    double speculativeTarget = 0.0;   // lowest vn allowed: -separation/dt when apart
    double restitution = 0.0;
};

/// The friction of one manifold (the points one collide() call gave): Coulomb's cone at the
/// points' centroid, bounded by mu times the sum of their normal impulses, and a torsional
/// friction about the normal bounded by that times the points' mean distance from the
/// centroid (patch friction, as PhysX's; one cone per point instead lets a statically
/// indeterminate split of the normal impulses spin a sliding face).
struct FrictionPatch {
    std::uint32_t a = 0, b = kStaticSide, item = 0;
    std::uint32_t first = 0, count = 0; // its points in the contact array
    Vec3 point{0.0}, normal{0.0}, t1{0.0}, t2{0.0};
    Vec3 rA{0.0}, rB{0.0};
    double radiusM = 0.0; // mean distance of the points from the centroid (m)
    double tangentMass1 = 0.0, tangentMass2 = 0.0, twistMass = 0.0;
    double impulse1 = 0.0, impulse2 = 0.0, twistImpulse = 0.0; // accumulated
    double pseudo1 = 0.0, pseudo2 = 0.0;                       // anchor correction
    double staticMu = 0.0, dynamicMu = 0.0;
    bool sticking = true;
    Vec3 anchorA{0.0}, anchorB{0.0}; // where it stuck, in a's and b's frames (b: world if static)
};

/// A static candidate of one body: an index item and the body.
struct Candidate {
    std::uint32_t body = 0, item = 0;
};

} // namespace hapto::dyn

namespace hapto {

struct Dynamics::Impl {
    const Scene* scene = nullptr;           // the dynamics' scene (static materials)
    const SpatialIndex* index = nullptr;    // the static items' index (broad phase)
    std::vector<std::uint64_t> seenStamp;   // by dense item position: last gathering that saw it
    std::uint64_t stamp = 0;                // this gathering's stamp
    std::vector<dyn::BodyWork> work;        // by body
    std::vector<dyn::Candidate> candidates; // capacity fixed
    std::vector<dyn::ContactWork> contacts, previous;         // capacity fixed
    std::vector<dyn::FrictionPatch> patches, previousPatches; // capacity fixed
    std::uint64_t droppedContacts = 0;
    std::uint64_t droppedCandidates = 0;
};

} // namespace hapto

namespace hapto::dyn {

/// A contact at most this far apart (m) touches: an arrival at the surface, to rounding.
inline constexpr double kTouchM = 1e-6;

/// Per-body candidate capacity and per-step contact capacity per body.
inline constexpr std::size_t kCandidatesPerBody = 256, kContactsPerBody = 64;

/// The body's shape placed at its current pose. [dynamics]
ConvexShape placeShape(const BodyWork& w, const BodyState& b) noexcept;
/// A static item's shape (box, sphere or triangle) at its scene pose. [dynamics]
ConvexShape staticShape(const Scene& scene, std::uint32_t item) noexcept;
/// The world inverse inertia R I^-1 R^T of every body (zero for a sleeping one). [dynamics]
void updateWorldInertia(std::span<const BodyState> bodies, std::vector<BodyWork>& work) noexcept;
/// Applies the pending hand impulses, adds their work, wakes the bodies they push. [dynamics]
void applyPendingImpulses(std::span<BodyState> bodies, std::vector<BodyWork>& work) noexcept;
/// Gravity on every awake body. [dynamics]
void integrateVelocities(std::span<BodyState> bodies, const Vec3& gravity, double dtS) noexcept;
/// Moves every awake body by (v + pseudo v) dt, renormalising its orientation. [dynamics]
void integratePositions(std::span<BodyState> bodies, std::vector<BodyWork>& work,
                        double dtS) noexcept;
/// Each awake body's swept box and its static candidates. [dynamics]
void gatherCandidates(const Scene& scene, std::span<const BodyState> bodies, Dynamics::Impl& impl,
                      const DynamicsOptions& options, double dtS) noexcept;
/// True when both bodies' swept boxes (set by gatherCandidates) overlap. [dynamics]
bool sweptBoxesOverlap(const BodyWork& a, const BodyWork& b) noexcept;
/// The narrow phase over the candidates and the body pairs, into impl.contacts. [dynamics]
void findContacts(const Scene& scene, std::span<const BodyState> bodies, Dynamics::Impl& impl,
                  const DynamicsOptions& options, double dtS) noexcept;
/// Effective masses, tangents, speculative targets, warm start and anchors. [dynamics]
void prepareContacts(std::span<BodyState> bodies, Dynamics::Impl& impl,
                     const DynamicsOptions& options, double dtS) noexcept;
/// Each patch's centroid, tangents, masses and pair friction, warm started. [dynamics]
void preparePatches(std::span<BodyState> bodies, Dynamics::Impl& impl,
                    const DynamicsOptions& options) noexcept;
/// One friction pass on a patch (tangential and twist). [dynamics]
void solvePatchFriction(FrictionPatch& f, std::span<BodyState> bodies,
                        Dynamics::Impl& impl) noexcept;
/// One anchor-correction pass on a sticking patch (pseudo velocities; `rate` 1/s). [dynamics]
void solvePatchAnchor(FrictionPatch& f, std::span<BodyState> bodies, Dynamics::Impl& impl,
                      double rate) noexcept;
/// Sticking or sliding for the next step. [dynamics]
void finishPatches(std::span<const BodyState> bodies, Dynamics::Impl& impl,
                   const DynamicsOptions& options) noexcept;
/// The sequential-impulse passes, then restitution. [dynamics]
void solveVelocities(std::span<BodyState> bodies, Dynamics::Impl& impl,
                     const DynamicsOptions& options) noexcept;
/// The split-impulse passes: overlap beyond the slop and anchor drift. [dynamics]
void solvePositions(std::span<BodyState> bodies, Dynamics::Impl& impl,
                    const DynamicsOptions& options, double dtS) noexcept;
/// Sticking or sliding for the next step; keeps this step's contacts for warm starting.
/// [dynamics]
void finishContacts(std::span<const BodyState> bodies, Dynamics::Impl& impl,
                    const DynamicsOptions& options, double dtS) noexcept;
/// Sleep timers, sleeping and waking by touch. [dynamics]
void updateSleep(std::span<BodyState> bodies, Dynamics::Impl& impl, const DynamicsOptions& options,
                 double dtS) noexcept;
/// True when the body takes part in the solve (awake). [dynamics]
inline bool moves(const BodyState& b) noexcept {
    return !b.sleeping;
}

/// One side of a contact as the solver sees it: a sleeping body or the static scene has
/// infinite mass.
struct BodySide {
    double invMass = 0.0;
    Mat3 invInertia{0.0};
};

/// Side `i` of a contact (kStaticSide: the scene). [dynamics]
inline BodySide sideOf(std::span<const BodyState> bodies, const std::vector<BodyWork>& work,
                       std::uint32_t i) noexcept {
    if (i == kStaticSide || !moves(bodies[i])) {
        return {};
    }
    return {work[i].invMass, work[i].invInertiaWorld};
}

/// The static side's (static friction, dynamic friction, restitution). [dynamics]
inline Vec3 staticMaterial(const Dynamics::Impl& impl, std::uint32_t item) noexcept {
    const SceneObject& o = impl.scene->object(impl.scene->objectSlotOf(item));
    return {o.material.staticFriction, o.material.dynamicFriction, o.body.restitution};
}

/// Applies angular impulse L (N m s) to a and -L to b. [dynamics]
inline void applyAngular(const FrictionPatch& c, const Vec3& l, std::span<BodyState> bodies,
                         std::vector<BodyWork>& work) noexcept {
    if (moves(bodies[c.a])) {
        bodies[c.a].angularVelocity += work[c.a].invInertiaWorld * l;
    }
    if (c.b != kStaticSide && moves(bodies[c.b])) {
        bodies[c.b].angularVelocity -= work[c.b].invInertiaWorld * l;
    }
}

/// Velocity of a's contact point relative to b's (m/s); `pseudo`: of the split impulse's
/// pseudo velocities instead. [dynamics]
template <class C>
inline Vec3 relativeVelocity(const C& c, std::span<const BodyState> bodies,
                             const std::vector<BodyWork>& work, bool pseudo) noexcept {
    auto pointVelocity = [&](std::uint32_t i, const Vec3& r) {
        if (i == kStaticSide || !moves(bodies[i])) {
            return Vec3(0.0);
        }
        const Vec3 v = pseudo ? work[i].pseudoV : bodies[i].velocity;
        const Vec3 w = pseudo ? work[i].pseudoW : bodies[i].angularVelocity;
        return v + glm::cross(w, r);
    };
    return pointVelocity(c.a, c.rA) - pointVelocity(c.b, c.rB);
}

/// Applies impulse p (N s) to a at its contact point and -p to b; `pseudo`: to the pseudo
/// velocities. A sleeping or static side is not moved. [dynamics]
template <class C>
inline void applyImpulse(const C& c, const Vec3& p, std::span<BodyState> bodies,
                         std::vector<BodyWork>& work, bool pseudo) noexcept {
    auto push = [&](std::uint32_t i, const Vec3& r, const Vec3& q) {
        if (i == kStaticSide || !moves(bodies[i])) {
            return;
        }
        Vec3& v = pseudo ? work[i].pseudoV : bodies[i].velocity;
        Vec3& w = pseudo ? work[i].pseudoW : bodies[i].angularVelocity;
        v += q * work[i].invMass;
        w += work[i].invInertiaWorld * glm::cross(r, q);
    };
    push(c.a, c.rA, p);
    push(c.b, c.rB, -p);
}

} // namespace hapto::dyn
