/// God-object proxy renderer: point tool vs oriented boxes, spheres and mesh triangles, with
/// Coulomb friction. This file is the tick (the proxy's start, the contacts, the force, the
/// faults); its parts are GodObjectNearList.cpp (the candidate gathering), GodObjectSolver.cpp
/// (the proxy solve) and GodObjectFriction.cpp, each with its own note, over core's shape
/// geometry (ClosestPoint.h, SweptShapes.h).
///
/// Design note
/// -----------
/// Idea. The proxy (god-object) is a point that never enters an object; the device point
/// (the "goal") may. Each tick the proxy moves toward the goal as far as the surfaces allow:
/// we solve for the closest point to the goal inside the intersection of the active constraint
/// half-spaces (at most three planes, an 8-subset enumeration), then sweep the straight path
/// from the proxy to that point against the nearby objects and stop at the first surface it
/// would enter. The face (or sphere tangent plane) entered becomes a new constraint; when the
/// entry point lies on an edge or corner, every face there that the goal is behind is added
/// too (Zilles & Salisbury's rule), so pressing into an edge keeps the proxy on the edge.
/// Planes whose object no longer touches the proxy (it slid off a face, or along a sphere's
/// tangent plane) are dropped and the sweep toward the goal repeats, for a bounded number of
/// passes. Force = k (proxy - goal). Friction is a cone test on top: the previous proxy (or
/// the first touch point) is kept while it lies within atan(mu) of the frictionless contact
/// normal; otherwise the goal is shifted back along the surface by mu_d x penetration and the
/// same solver goes on from the frictionless proxy, so the friction path is swept like every
/// other move.
///
/// Invariant. At the end of every pass the proxy lies outside every candidate object that did
/// not already contain it at the start of the sweep: a sweep never crosses a surface, whatever
/// the speed, so thin objects cannot be tunnelled. Surfaces are inflated by a 10 nm skin
/// (kSkinM) and the swept test uses surfaces 1 nm inside that skin (kShrinkM), so a proxy
/// resting on, or sliding along, a surface is "outside" with a margin, and the cracks between
/// flush objects (a box on a box, boxes side by side) are closed by the overlapping skins.
/// An object that contains the proxy at the start of a tick (it was reset inside one, or a
/// moving object jumped onto it) is passed through until the proxy has left it, except that an
/// object the proxy was touching pushes the proxy back out to its surface first.
///
/// Triangles. A mesh is its triangles (index items; a moving mesh's object slot stands for its
/// triangles near the path, found in the mesh's own frame). A triangle is entered only from its
/// front: its skin slab is the plane kSkinM in front over the triangle grown by kSkinM across
/// its edges (a box face's skin, so a flat mesh feels like the box face it replaces), and a
/// path that really crosses the triangle is stopped too. At an edge or vertex the same mesh's
/// triangles there that the goal is behind are added (Zilles & Salisbury); coplanar ones give
/// the same plane, kept once, so shared edges do not snag. One-sidedness is also what frees a
/// proxy inside a closed mesh: from inside, every path leaves through back faces.
///
/// Dynamic bodies. A dynamic object's pose comes from the tick's DynamicBodySet (its pose
/// published by the dynamics step, extrapolated to the tick), never from the scene; its items
/// the static index lists are skipped (bodyAt, faceAt, cornersAt, skipItem). Its surface moves,
/// so the damping acts on the velocity relative to the body's surface at the proxy, and the
/// coupling adds c = k h (h the dynamics step) to it. Why k h: the loop is a spring k on the
/// body's position x_n as published, integrated by the step as v' = v + h F / m, x' = x + h v'
/// (symplectic Euler). With a = sum k h^2 / m and beta = sum c h / m, the energy
/// E = 1/2 m v^2 + 1/2 sum k x^2 changes per step by the quadratic form
/// [a^2 (a - 1)] x^2 - 2 a^2 (1 - beta) x (h v) + [(1 - beta)^2 (1 + a) - 1] (h v)^2 (in units
/// of m / 2 h^2), negative semidefinite iff a <= 1 and |1 - beta| <= sqrt(1 - a); beta = a
/// (c = k h per contact) satisfies it for every a <= 1, however many hands share the body, and
/// the loop is stable (Jury) for beta < (4 - a) / 2, i.e. a < 4/3. Without damping the true
/// energy oscillates by O(omega h) (it is the shadow energy that symplectic Euler keeps). A
/// 10 g body against 10^4 N/m at 1 kHz is a = 1: the energy never grows, the contact settles
/// in one step. Two such hands on it (a = 2) need the dynamics at 2 kHz or more.
///
/// Cost. One pass over the candidate spans per tick builds a deduplicated near list of the
/// objects whose bounding sphere meets the ball around the goal that the proxy can reach this
/// tick (every point the proxy visits is no farther from the goal than where it started),
/// with a generous margin for objects and 1 µm for triangles (a fine mesh stays a few items).
/// Each solver pass is one <= 3-plane solve (at most 8 tiny linear solves) plus one swept test
/// per near item (slab clipping in the box frame, a quadratic for a sphere, a plane crossing and
/// three edge tests for a triangle, after a plane test that rejects most; a box or sphere whose
/// skin's bounding box the pass's segment misses, up to the nearest entry found so far, ends at
/// six comparisons, and a triangle whose skin plane it reaches only beyond that entry ends at
/// its plane test; every pose, matrix, radius and triangle plane comes precomputed from the
/// scene's render copy). Worst case per tick: 2 solves x maxIterations x near items; typically
/// 2-3 passes over 1-5 objects or a handful of triangles. A tick solved again over more spans
/// (extendNextUpdate) reads only those spans into its near list. No allocation: the near list
/// and plane sets are fixed arrays.

#include "GodObjectParts.h"

#include "hapto/core/Finite.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hapto {

using namespace godobject;

static_assert(sizeof(GodObjectRenderer) == 12416, "update the size in GodObjectRenderer.h");
static_assert(alignof(GodObjectRenderer) == 64);

namespace {

/// The nearest point on the object's skin to an inside point p.
Vec3 pushOut(const RenderBody& o, const Vec3& p) {
    if (o.shape == Shape::Sphere) {
        return sphereSurfacePointNearest(o.center, o.halfExtents.x + kSkinM, p);
    }
    return o.toWorld(boxSurfacePointNearestLocal(o.toLocal(p), o.halfExtents + Vec3(kSkinM)));
}

} // namespace

GodObjectRenderer::GodObjectRenderer(const RendererConfig& config) : mConfig(config) {
    if (!(config.damping >= 0.0) || !std::isfinite(config.damping)) {
        throw std::invalid_argument("GodObjectRenderer: damping must be a finite value >= 0 N*s/m"
                                    " (got " +
                                    std::to_string(config.damping) + ")");
    }
    if (config.maxIterations < 1 || config.maxIterations > kMaxIterations) {
        throw std::invalid_argument("GodObjectRenderer: maxIterations must be in 1.." +
                                    std::to_string(kMaxIterations) + " (got " +
                                    std::to_string(config.maxIterations) + ")");
    }
}

void GodObjectRenderer::reset(const Vec3& devicePosition) noexcept {
    mState.proxy = devicePosition;
    mState.lastDevice = devicePosition;
    mState.hasLastDevice = finite(devicePosition);
    mState.slipping = false;
    mState.contactCount = 0;
    mState.restCount = 0;
    mNearRadius = -1.0;
    mNearCount = 0;
    mTriangleCount = 0;
    mNearOverflow = false;
    mNearTriangles = false;
}

RenderOutput GodObjectRenderer::update(const Scene& scene, const CandidateSet& candidates,
                                       const Vec3& devicePosition, const Vec3& deviceVelocity,
                                       double dtSeconds) noexcept {
    return update(scene, candidates, devicePosition, devicePosition, deviceVelocity, dtSeconds);
}

RenderOutput GodObjectRenderer::update(const Scene& scene, const CandidateSet& candidates,
                                       const Vec3& devicePosition, const Vec3& goal,
                                       const Vec3& deviceVelocity, double dtSeconds) noexcept {
    RenderOutput out;
    ++mState.counters.ticks;
    // The same tick solved again over more spans keeps its near list (extendNextUpdate).
    const bool extend = mExtendNear && extendsNearSpans(candidates);
    mExtendNear = false;
    if (!extend) {
        mNearRadius = -1.0;
        mNearCount = 0;
        mTriangleCount = 0;
        mNearOverflow = false;
        mNearTriangles = false;
    }
    mVisitedCount = 0;
    mVisitedSecond = 0;
    if (!finite(devicePosition) || !finite(goal)) {
        out.status = RenderStatus::NonFiniteInput;
        out.proxy = mState.proxy;
        ++mState.counters.nonFiniteInput;
        return out;
    }
    if (!finite(mState.proxy)) {
        reset(devicePosition);
    }
    const Vec3 velocity = velocityAt(devicePosition, deviceVelocity, dtSeconds);
    mState.lastDevice = devicePosition;
    mState.hasLastDevice = true;
    visit(mState.proxy);

    std::uint32_t tested = 0;
    if (extend) {
        addNearSpans(scene, candidates, tested);
    }
    ensureNear(scene, candidates, goal, glm::length(mState.proxy - goal), tested);
    const Vec3 start = startOfTick(scene, candidates, goal, tested);
    const Solve resting = restingPlanes(scene, start);
    const Solve free = solve(scene, candidates, start, goal, &resting);
    mVisitedSecond = mVisitedCount;
    const Friction f = friction(scene, candidates, start, goal, free, tested);
    mState.restCount = static_cast<std::uint8_t>(f.solve.planeCount);
    for (std::uint32_t i = 0; i < f.solve.planeCount; ++i) {
        mState.restItems[i] = f.solve.planes[i].item;
        mState.restNormals[i] = f.solve.planes[i].normal;
    }

    const double stiffness = takeContacts(scene, f.solve, f.stuck, devicePosition, out);
    out.proxy = f.solve.proxy;
    out.force = contactForce(scene, out, stiffness, devicePosition, velocity);
    out.sliding = out.contactCount > 0 && !f.stuck && glm::length(f.solve.proxy - start) > kOnM;
    out.iterations = static_cast<std::uint8_t>(std::min<std::uint32_t>(f.iterations, 255));
    out.objectsTested = tested;
    finishTick(scene, candidates, start, goal, out);
    return out;
}

Vec3 GodObjectRenderer::velocityAt(const Vec3& devicePosition, const Vec3& deviceVelocity,
                                   double dtSeconds) const noexcept {
    if (finite(deviceVelocity)) {
        return deviceVelocity;
    }
    if (mState.hasLastDevice && dtSeconds > 0.0 && std::isfinite(dtSeconds)) {
        const Vec3 velocity = (devicePosition - mState.lastDevice) / dtSeconds;
        if (finite(velocity)) {
            return velocity;
        }
    }
    return Vec3(0.0);
}

Vec3 GodObjectRenderer::startOfTick(const Scene& scene, const CandidateSet& candidates,
                                    const Vec3& goal, std::uint32_t& tested) noexcept {
    Vec3 start = mState.proxy;
    // A touched object that moved carries the proxy with it: friction holds in the object's
    // frame, so an object that is pushed, carried or grasped takes its contact point along.
    // A touched triangle carries the proxy with its mesh's pose.
    for (std::uint32_t i = 0; i < mState.contactCount; ++i) {
        const std::uint32_t item = mState.contactSlots[i];
        const State::ContactPose& was = mState.contactPoses[i];
        if (!validItem(scene, item) || scene.object(scene.objectSlotOf(item)).id != was.id ||
            (!isTriangleItem(item) && skipItem(scene, item))) {
            continue; // the world was re-indexed and the item now names another object
        }
        Vec3 center;
        Quat rotation;
        poseAt(scene, scene.objectSlotOf(item), center, rotation);
        if (center != was.center || rotation != was.rotation) {
            start = center + rotation * (glm::conjugate(was.rotation) * (start - was.center));
            ensureNear(scene, candidates, goal, glm::length(start - goal), tested);
            break;
        }
    }
    // A touched object that moved into the proxy pushes it back out to its surface (a touched
    // mesh has carried the proxy in its own frame above, so it stays on its skin).
    if (mState.contactCount > 0) {
        const auto touched = mState.contactSlots.begin();
        const auto touchedEnd = touched + mState.contactCount;
        forEachNear(scene, candidates, [&](std::uint32_t slot, std::uint32_t) {
            if (isTriangleItem(slot)) {
                return;
            }
            const RenderBody& o = bodyAt(scene, slot);
            if (std::find(touched, touchedEnd, slot) != touchedEnd && insideSkin(o, start)) {
                start = pushOut(o, start);
            }
        });
        ensureNear(scene, candidates, goal, glm::length(start - goal), tested);
    }
    // A dynamic body that ran into the proxy since the last tick (it is inside the body now,
    // was outside it a period ago) pushes it out to its surface: a body is not passed through
    // because it, not the tool, moved. (A dynamic mesh is not: its triangles are one-sided.)
    for (std::uint32_t i = 0; mDynamic != nullptr && i < mDynamic->count; ++i) {
        const DynamicBodySet::Entry& e = mDynamic->entries[i];
        if (e.render.shape != Shape::Mesh && insideSkin(e.render, start) &&
            !insideSkin(e.previous, start)) {
            start = pushOut(e.render, start);
            ensureNear(scene, candidates, goal, glm::length(start - goal), tested);
        }
    }
    return start;
}

double GodObjectRenderer::takeContacts(const Scene& scene, const Solve& fin, bool stuck,
                                       const Vec3& devicePosition,
                                       RenderOutput& out) const noexcept {
    // Contacts: planes the final proxy is on and the device point is behind (a goal short of
    // the device point is behind every plane it is behind: it lies on the way to it).
    double stiffness = kInf;
    for (std::uint32_t i = 0; i < fin.planeCount && out.contactCount < kMaxContacts; ++i) {
        const Plane& pl = fin.planes[i];
        const double depth = pl.offset - glm::dot(pl.normal, devicePosition);
        const bool onPlane = stuck || glm::dot(pl.normal, fin.proxy) - pl.offset <= kOnM;
        if (depth <= 0.0 || !onPlane) {
            continue;
        }
        const SceneObject& o = scene.object(scene.objectSlotOf(pl.item));
        out.contacts[out.contactCount++] = {pl.item, o.id, pl.normal, depth};
        stiffness = std::min(stiffness, o.material.stiffness);
    }
    return stiffness;
}

Vec3 GodObjectRenderer::contactForce(const Scene& scene, const RenderOutput& out, double stiffness,
                                     const Vec3& devicePosition, const Vec3& velocity) noexcept {
    if (out.contactCount == 0) {
        mState.slipping = false;
        return Vec3(0.0);
    }
    Vec3 force = stiffness * (out.proxy - devicePosition);
    const double magnitude = glm::length(force);
    Vec3 surfaceVelocity(0.0);
    const double coupling = couplingDampingOf(scene, out, stiffness, surfaceVelocity);
    const double damping = mConfig.damping + coupling;
    if (damping > 0.0 && magnitude > 0.0) {
        const Vec3 n = force / magnitude;
        force -= damping * glm::dot(n, velocity - surfaceVelocity) * n;
        const double along = glm::dot(n, force);
        if (along < 0.0) { // damping may soften a push, never pull into the surface
            force -= along * n;
        }
    }
    return force;
}

double GodObjectRenderer::couplingDampingOf(const Scene& scene, const RenderOutput& out,
                                            double stiffness,
                                            Vec3& surfaceVelocity) const noexcept {
    if (mDynamic == nullptr || mDynamic->count == 0) {
        return 0.0;
    }
    const double h = 1.0 / scene.physics().rateHz;
    double c = 0.0;
    for (std::uint32_t i = 0; i < out.contactCount; ++i) {
        const DynamicBodySet::Entry* e = mDynamic->find(scene.objectSlotOf(out.contacts[i].slot));
        if (e == nullptr) {
            continue;
        }
        const double ci = dynamicCouplingDamping(stiffness, h);
        if (ci >= c) {
            c = ci;
            surfaceVelocity = e->pointVelocity(out.proxy);
        }
    }
    return c;
}

double GodObjectRenderer::dynamicCouplingDamping(double stiffnessNPerM, double stepS) noexcept {
    if (!(stepS > 0.0) || !(stiffnessNPerM > 0.0) || !std::isfinite(stiffnessNPerM)) {
        return 0.0;
    }
    return stiffnessNPerM * stepS; // beta = a: see the header and DESIGN's coupling section
}

void GodObjectRenderer::finishTick(const Scene& scene, const CandidateSet& candidates,
                                   const Vec3& start, const Vec3& goal,
                                   RenderOutput& out) noexcept {
    if (mNearOverflow) {
        out.status = RenderStatus::NearListFull;
        ++mState.counters.nearListFull;
    } else if (candidates.overflowed) {
        out.status = RenderStatus::CandidatesDropped;
    }
    if (candidates.overflowed) {
        ++mState.counters.candidatesDropped;
    }
    if (!finite(out.force) || !finite(out.proxy)) {
        out.status = RenderStatus::NonFiniteOutput;
        ++mState.counters.nonFiniteOutput;
        out.force = Vec3(0.0);
        out.proxy = finite(start) ? start : goal;
        out.contactCount = 0;
        out.sliding = false;
        mState.restCount = 0;
    }
    mState.proxy = out.proxy;
    mState.contactCount = out.contactCount;
    for (std::uint32_t i = 0; i < out.contactCount; ++i) {
        const std::uint32_t slot = scene.objectSlotOf(out.contacts[i].slot);
        Vec3 center;
        Quat rotation;
        poseAt(scene, slot, center, rotation);
        mState.contactSlots[i] = out.contacts[i].slot;
        mState.contactPoses[i] = {scene.object(slot).id, center, rotation};
    }
}

} // namespace hapto
