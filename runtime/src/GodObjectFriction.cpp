/// The god-object renderer's Coulomb friction: the cone test and the second solve.
///
/// Design note
/// -----------
/// Idea. Friction is a cone test on top of the frictionless solve. The anchor is where the
/// proxy held last tick (its start), or the first touch point of a tick that came into
/// contact. While the anchor lies within atan(mu_s) (atan(mu_d) once slipping) of the
/// frictionless contact normal, seen from the goal, and still rests on a surface, the proxy
/// stays there (stuck). Otherwise it slips: the goal is shifted back along the surface toward
/// the anchor by mu_d x penetration (never past the anchor) and the same solver goes on from
/// the frictionless proxy, with the planes it rests on there, so the friction path is swept
/// like every other move and the proxy trails the frictionless proxy by exactly that much.
/// Going on from there, not from the tick's start, the second solve steps back a fraction of a
/// millimetre instead of retracing the whole way (and does not find again, in a pass of its
/// own, the planes it starts on); its ball (the shifted goal's, as far as the frictionless
/// proxy) mostly lies inside the first solve's, so the near list built for that one serves it
/// too.
///
/// Invariant. With several contacts the smallest friction coefficients among the touched
/// materials apply (conservative); a goal with no contact behind it has no friction. The
/// second solve starts where the first ended, outside every skin that did not hold the tick's
/// start, so it never crosses a surface either (an item that held the start and not the
/// frictionless proxy now stops it: stricter, never looser); the planes it starts with only
/// hold it back, and it drops each as it slides off, as any solve does.
///
/// Cost. One scan of the near list for the anchor's contact, and at most one more solve (the
/// near list is rebuilt only when its ball does not cover the shifted goal's). No allocation.

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
        // and go on from the frictionless proxy: the proxy trails by exactly that much.
        const Vec3 g2 = goal + lagT * (std::min(muDynamic * penetration, lagLen) / lagLen);
        ensureNear(scene, candidates, g2, glm::length(free.proxy - g2), tested);
        f.solve = solve(scene, candidates, free.proxy, g2, &free);
        f.iterations += f.solve.iterations;
    }
    return f;
}

} // namespace hapto
