/// The god-object renderer's Coulomb friction: the cone test and the second solve.
///
/// Design note
/// -----------
/// Idea. Friction is a cone test on top of the frictionless solve. The anchor is where the
/// proxy held last tick (its start), or the first touch point of a tick that came into
/// contact. While the anchor lies within atan(mu_s) (atan(mu_d) once slipping) of the
/// frictionless contact normal, seen from the goal, and still rests on a surface, the proxy
/// stays there (stuck). Otherwise it slips: the goal is shifted back along the surface toward
/// the anchor by mu_d x penetration (never past the anchor) and the same solver runs again from
/// the same start, so the friction path is swept like every other move and the proxy trails
/// the frictionless proxy by exactly that much.
///
/// Invariant. With several contacts the smallest friction coefficients among the touched
/// materials apply (conservative); a goal with no contact behind it has no friction. The
/// second solve starts where the first did, so it never crosses a surface either.
///
/// Cost. One scan of the near list for the anchor's contact, and at most one more solve (the
/// near list is rebuilt only when its ball does not cover the shifted goal). No allocation.

#include "GodObjectParts.h"

#include <algorithm>

namespace hapto {

using namespace godobject;

GodObjectRenderer::Friction
GodObjectRenderer::friction(const Scene& scene, const CandidateSet& candidates, const Vec3& start,
                            const Vec3& goal, const Solve& free, std::uint32_t& tested) noexcept {
    Friction f{free, free.iterations, false};
    // The contact materials of the frictionless solution.
    double muStatic = kInf;
    double muDynamic = kInf;
    std::uint32_t freeContacts = 0;
    for (std::uint32_t i = 0; i < free.planeCount; ++i) {
        if (glm::dot(free.planes[i].normal, goal) < free.planes[i].offset) {
            const Material& m = scene.object(scene.objectSlotOf(free.planes[i].item)).material;
            muStatic = std::min(muStatic, m.staticFriction);
            muDynamic = std::min(muDynamic, m.dynamicFriction);
            ++freeContacts;
        }
    }
    const Vec3 toFree = free.proxy - goal;
    const double penetration = glm::length(toFree);
    if (freeContacts == 0 || !(penetration > 0.0) || !(muStatic > 0.0 || muDynamic > 0.0)) {
        return f;
    }
    const Vec3 n = toFree / penetration;
    const Vec3 anchor = mState.contactCount > 0 ? start : (free.touched ? free.firstTouch : start);
    const double mu = mState.slipping ? muDynamic : muStatic;
    const Vec3 rel = anchor - goal;
    const double normal = glm::dot(n, rel);
    const double tangential = glm::length(rel - normal * n);
    // The anchor must still rest on something (an object may have moved away under it).
    bool anchorTouches = false;
    forEachNear(scene, candidates, [&](std::uint32_t item, std::uint32_t near) {
        anchorTouches = anchorTouches || distanceToSkinOf(scene, item, near, anchor) <= kOnM;
    });
    if (anchorTouches && normal > 0.0 && tangential <= mu * normal + 1e-12) {
        f.stuck = true;
        mState.slipping = false;
        f.solve.proxy = anchor;
        return f;
    }
    mState.slipping = true;
    const Vec3 lag = anchor - free.proxy;
    const Vec3 lagT = lag - glm::dot(n, lag) * n;
    const double lagLen = glm::length(lagT);
    if (lagLen > 1e-15 && muDynamic > 0.0) {
        // Shift the goal back along the surface by mu_d x penetration (never past the anchor)
        // and solve again: the proxy trails by exactly that much.
        const Vec3 g2 = goal + lagT * (std::min(muDynamic * penetration, lagLen) / lagLen);
        ensureNear(scene, candidates, g2, glm::length(start - g2), tested);
        f.solve = solve(scene, candidates, start, g2);
        f.iterations += f.solve.iterations;
    }
    return f;
}

} // namespace hapto
