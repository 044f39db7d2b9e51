/// God-object proxy solver: point tool vs oriented boxes and spheres, with Coulomb friction.
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
/// same solver runs again, so the friction path is swept like every other move.
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
/// Cost. One pass over the candidate spans per tick builds a deduplicated near list of the
/// objects whose bounding sphere meets the ball around the goal that the proxy can reach this
/// tick (every point the proxy visits is no farther from the goal than where it started).
/// Each solver pass is one <= 3-plane solve (at most 8 tiny linear solves) plus one swept test
/// per near object (slab clipping in the box frame, or a quadratic for a sphere). Worst case
/// per tick: 2 solves x maxIterations x near objects; typically 2-3 passes over 1-5 objects.
/// No allocation: the near list and plane sets are fixed arrays.

#include "hapto/runtime/GodObjectRenderer.h"

#include "hapto/core/Finite.h"
#include "hapto/core/ShapeGeometry.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace hapto {

static_assert(sizeof(GodObjectRenderer) == 1408, "update the size in GodObjectRenderer.h");
static_assert(alignof(GodObjectRenderer) == 64);

namespace {

constexpr double kSkinM = GodObjectRenderer::kSkinM;
constexpr double kShrinkM = 1e-9;      ///< Swept tests use surfaces this far inside the skin (m).
constexpr double kOnM = 2e-9;          ///< "On a plane / touching an object" tolerance (m).
constexpr double kProbeM = 4e-9;       ///< Covered-face probe step (m), > kShrinkM.
constexpr double kFeasibleM = 1e-12;   ///< Half-space feasibility slack (m).
constexpr double kNearMarginM = 1e-3;  ///< Extra radius of the near ball (m).
constexpr double kFrictionCover = 1.0; ///< Near ball also covers a friction lag up to mu_d = 1.
constexpr double kInf = std::numeric_limits<double>::infinity();

double length2(const Vec3& v) {
    return glm::dot(v, v);
}

/// The swept test of one object: where the path enters its shrunk skin, and where it reaches
/// the skin itself (the stop point), as fractions of the path.
struct Entry {
    bool found = false;
    double t = kInf;  ///< Entry into the shrunk skin, in [0, 1).
    double tStop = 0; ///< Arrival at the skin, in [0, t].
    int axis = -1;    ///< Box: the entered face's axis; -1 for a sphere.
    double sign = 0;  ///< Box: the entered face's side (+1 or -1 along the axis).
};

Entry sweepBox(const Obb& obb, const Vec3& from, const Vec3& to) {
    const Vec3 a = obb.toLocal(from);
    const Vec3 d = obb.toLocal(to) - a;
    double tIn = -kInf;
    double tOut = kInf;
    double sIn = -kInf;
    Entry e;
    for (int i = 0; i < 3; ++i) {
        const double h = obb.halfExtents[i] + kSkinM - kShrinkM;
        const double hs = obb.halfExtents[i] + kSkinM;
        if (std::abs(d[i]) < 1e-18) {
            if (std::abs(a[i]) >= h) {
                return {};
            }
            continue;
        }
        const double inv = 1.0 / d[i];
        double t1 = (-h - a[i]) * inv;
        double t2 = (h - a[i]) * inv;
        double s1 = (-hs - a[i]) * inv;
        if (t1 > t2) {
            std::swap(t1, t2);
            s1 = (hs - a[i]) * inv;
        }
        if (t1 > tIn) {
            tIn = t1;
            e.axis = i;
            e.sign = d[i] > 0 ? -1.0 : 1.0;
        }
        tOut = std::min(tOut, t2);
        sIn = std::max(sIn, s1);
    }
    // tIn < 0: the start is already inside (passed through); tIn >= tOut: no interior chord.
    if (e.axis < 0 || tIn < 0.0 || tIn >= 1.0 || tIn >= tOut) {
        return {};
    }
    e.found = true;
    e.t = tIn;
    e.tStop = std::clamp(sIn, 0.0, tIn);
    return e;
}

Entry sweepSphere(const Vec3& center, double radius, const Vec3& from, const Vec3& to) {
    const Vec3 f = from - center;
    const Vec3 d = to - from;
    const double a = glm::dot(d, d);
    if (a < 1e-36) {
        return {};
    }
    const double b = glm::dot(f, d); // half the linear coefficient
    const double r = radius + kSkinM - kShrinkM;
    const double c = glm::dot(f, f) - r * r;
    if (c <= 0.0 || b >= 0.0) { // inside already, or moving away
        return {};
    }
    const double disc = b * b - a * c;
    if (disc <= 0.0) {
        return {};
    }
    const double t = c / (-b + std::sqrt(disc)); // the smaller root, in a stable form
    if (t < 0.0 || t >= 1.0) {
        return {};
    }
    Entry e;
    e.found = true;
    e.t = t;
    const double rs = radius + kSkinM;
    const double cs = glm::dot(f, f) - rs * rs;
    if (cs > 0.0) {
        const double discS = b * b - a * cs;
        e.tStop = discS > 0.0 ? std::clamp(cs / (-b + std::sqrt(discS)), 0.0, t) : t;
    }
    return e;
}

/// True when p is inside the object's shrunk skin (strictly).
bool insideSkin(const SceneObject& o, const Vec3& p) {
    return o.shape == Shape::Sphere
               ? sphereStrictlyContains(o.center, o.halfExtents.x + kSkinM - kShrinkM, p)
               : boxStrictlyContains(o.obb(), p, kSkinM - kShrinkM);
}

/// Distance (m) from p to the object's skin, 0 inside.
double distanceToSkin(const SceneObject& o, const Vec3& p) {
    return o.shape == Shape::Sphere
               ? std::max(0.0, sphereSignedDistance(o.center, o.halfExtents.x + kSkinM, p))
               : boxDistanceOutside(o.obb(), p, kSkinM);
}

/// The nearest point on the object's skin to an inside point p.
Vec3 pushOut(const SceneObject& o, const Vec3& p) {
    if (o.shape == Shape::Sphere) {
        const Vec3 d = p - o.center;
        const double len = glm::length(d);
        const Vec3 n = len > 0.0 ? d / len : Vec3(0, 0, 1);
        return o.center + (o.halfExtents.x + kSkinM) * n;
    }
    const Obb obb = o.obb();
    Vec3 l = obb.toLocal(p);
    const int best = dominantFaceAxis(l, obb.halfExtents + Vec3(kSkinM)); // the nearest face
    l[best] = (l[best] < 0.0 ? -1.0 : 1.0) * (obb.halfExtents[best] + kSkinM);
    return obb.center + obb.axes * l;
}

} // namespace

/// The first surface a swept path enters.
struct GodObjectRenderer::Hit {
    bool found = false;
    double t = kInf;
    double tStop = 0.0;
    std::uint32_t slot = 0;
    int axis = -1;
    double sign = 0.0;
};

namespace {

/// Closest point to goal in {x : n_i . x >= offset_i, i < count} (count <= 3): the best
/// feasible equality-constrained projection over all subsets of the planes. Returns fallback
/// (a point known to be feasible) if no subset gives a feasible point (degenerate input).
template <class PlaneT>
Vec3 closestInHalfSpaces(const PlaneT* planes, std::uint32_t count, const Vec3& goal,
                         const Vec3& fallback) {
    Vec3 best = fallback;
    double bestD = kInf;
    for (std::uint32_t mask = 0; mask < (1u << count); ++mask) {
        std::uint32_t idx[3];
        std::uint32_t k = 0;
        for (std::uint32_t i = 0; i < count; ++i) {
            if (mask & (1u << i)) {
                idx[k++] = i;
            }
        }
        Vec3 c = goal;
        if (k == 1) {
            const PlaneT& p = planes[idx[0]];
            c = goal - (glm::dot(p.normal, goal) - p.offset) * p.normal;
        } else if (k == 2) {
            const PlaneT& p1 = planes[idx[0]];
            const PlaneT& p2 = planes[idx[1]];
            const double a = glm::dot(p1.normal, p2.normal);
            const double det = 1.0 - a * a;
            if (det < 1e-10) {
                continue; // (anti)parallel: a single-plane subset covers it
            }
            const double r1 = glm::dot(p1.normal, goal) - p1.offset;
            const double r2 = glm::dot(p2.normal, goal) - p2.offset;
            const double l1 = (r1 - a * r2) / det;
            const double l2 = (r2 - a * r1) / det;
            c = goal - l1 * p1.normal - l2 * p2.normal;
        } else if (k == 3) {
            const PlaneT& p1 = planes[idx[0]];
            const PlaneT& p2 = planes[idx[1]];
            const PlaneT& p3 = planes[idx[2]];
            const Vec3 c23 = glm::cross(p2.normal, p3.normal);
            const double det = glm::dot(p1.normal, c23);
            if (std::abs(det) < 1e-8) {
                continue;
            }
            c = (p1.offset * c23 + p2.offset * glm::cross(p3.normal, p1.normal) +
                 p3.offset * glm::cross(p1.normal, p2.normal)) /
                det;
        }
        bool feasible = true;
        for (std::uint32_t i = 0; i < count && feasible; ++i) {
            feasible = glm::dot(planes[i].normal, c) >= planes[i].offset - kFeasibleM;
        }
        const double d = length2(c - goal);
        if (feasible && d < bestD) {
            bestD = d;
            best = c;
        }
    }
    return best;
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
    mProxy = devicePosition;
    mLastDevice = devicePosition;
    mHasLastDevice = finite(devicePosition);
    mSlipping = false;
    mContactCount = 0;
    mNearRadius = -1.0;
    mNearCount = 0;
    mNearOverflow = false;
}

template <class Fn>
void GodObjectRenderer::forEachNear(const Scene& scene, const CandidateSet& candidates,
                                    Fn&& fn) const noexcept {
    if (!mNearOverflow) {
        for (std::uint32_t i = 0; i < mNearCount; ++i) {
            fn(mNear[i]);
        }
        return;
    }
    // Too many nearby objects for the scratch list: walk the spans (duplicates are harmless,
    // they give the same answer twice).
    const std::uint32_t n = scene.size();
    for (std::size_t s = 0; s < candidates.count && s < CandidateSet::kMaxSpans; ++s) {
        for (const std::uint32_t slot : candidates.spans[s]) {
            if (slot < n) {
                fn(slot);
            }
        }
    }
}

void GodObjectRenderer::buildNear(const Scene& scene, const CandidateSet& candidates,
                                  const Vec3& center, double radius,
                                  std::uint32_t& tested) noexcept {
    mNearCenter = center;
    mNearRadius = radius;
    mNearCount = 0;
    mNearOverflow = false;
    const std::uint32_t n = scene.size();
    for (std::size_t s = 0; s < candidates.count && s < CandidateSet::kMaxSpans; ++s) {
        tested += static_cast<std::uint32_t>(candidates.spans[s].size());
        for (const std::uint32_t slot : candidates.spans[s]) {
            if (slot >= n || mNearOverflow) {
                continue;
            }
            const SceneObject& o = scene.object(slot);
            const double reach = radius + o.radius() + kSkinM;
            if (length2(o.center - center) > reach * reach) {
                continue;
            }
            bool seen = false;
            for (std::uint32_t k = 0; k < mNearCount && !seen; ++k) {
                seen = mNear[k] == slot;
            }
            if (seen) {
                continue;
            }
            if (mNearCount == kMaxNearObjects) {
                mNearOverflow = true;
                continue;
            }
            mNear[mNearCount++] = slot;
        }
    }
}

GodObjectRenderer::Hit GodObjectRenderer::sweep(const Scene& scene, const CandidateSet& candidates,
                                                const Vec3& from, const Vec3& to) const noexcept {
    Hit best;
    forEachNear(scene, candidates, [&](std::uint32_t slot) {
        const SceneObject& o = scene.object(slot);
        const Entry e = o.shape == Shape::Sphere ? sweepSphere(o.center, o.halfExtents.x, from, to)
                                                 : sweepBox(o.obb(), from, to);
        if (e.found && e.t < best.t) {
            best = {true, e.t, e.tStop, slot, e.axis, e.sign};
        }
    });
    return best;
}

bool GodObjectRenderer::covered(const Scene& scene, const CandidateSet& candidates,
                                const Vec3& probe, std::uint32_t self) const noexcept {
    bool inside = false;
    forEachNear(scene, candidates, [&](std::uint32_t slot) {
        if (!inside && slot != self) {
            inside = insideSkin(scene.object(slot), probe);
        }
    });
    return inside;
}

GodObjectRenderer::Solve GodObjectRenderer::solve(const Scene& scene,
                                                  const CandidateSet& candidates, const Vec3& start,
                                                  const Vec3& goal) const noexcept {
    Solve s;
    Vec3 p = start;

    // Drops planes the proxy is not on (within kOnM).
    auto pruneNonBinding = [&](const Vec3& at) {
        std::uint32_t kept = 0;
        for (std::uint32_t i = 0; i < s.planeCount; ++i) {
            if (glm::dot(s.planes[i].normal, at) - s.planes[i].offset <= kOnM) {
                s.planes[kept++] = s.planes[i];
            }
        }
        s.planeCount = kept;
    };
    // Adds a plane unless it is already there; false when there is no room.
    auto addPlane = [&](const Plane& plane) {
        for (std::uint32_t i = 0; i < s.planeCount; ++i) {
            const Plane& q = s.planes[i];
            if (glm::dot(q.normal, plane.normal) > 1.0 - 1e-12 &&
                std::abs(q.offset - plane.offset) <= kOnM) {
                return true;
            }
        }
        if (s.planeCount == kMaxContacts) {
            return false;
        }
        s.planes[s.planeCount++] = plane;
        return true;
    };

    for (std::uint32_t it = 0; it < mConfig.maxIterations; ++it) {
        s.iterations = it + 1;
        const Vec3 target = closestInHalfSpaces(s.planes.data(), s.planeCount, goal, p);
        const Hit hit = sweep(scene, candidates, p, target);
        if (hit.found) {
            p += hit.tStop * (target - p);
            if (!s.touched) {
                s.touched = true;
                s.firstTouch = p;
            }
            pruneNonBinding(p);
            const SceneObject& o = scene.object(hit.slot);
            if (o.shape == Shape::Sphere) {
                Vec3 n = p - o.center;
                const double len = glm::length(n);
                n = len > 0.0 ? n / len : glm::normalize(p - target);
                if (!addPlane({n, glm::dot(n, o.center) + o.halfExtents.x + kSkinM, hit.slot})) {
                    break;
                }
                continue;
            }
            const Obb obb = o.obb();
            const Vec3 entered = hit.sign * obb.axes[hit.axis];
            if (!addPlane({entered,
                           glm::dot(entered, obb.center) + obb.halfExtents[hit.axis] + kSkinM,
                           hit.slot})) {
                break;
            }
            // On an edge or a corner: every other face there that the goal is behind, unless
            // another object covers it (flush neighbours make internal faces).
            const Vec3 l = obb.toLocal(p);
            for (int j = 0; j < 3; ++j) {
                if (j == hit.axis) {
                    continue;
                }
                for (const double side : {-1.0, 1.0}) {
                    if (side * l[j] < obb.halfExtents[j] + kSkinM - kOnM) {
                        continue;
                    }
                    const Vec3 n = side * obb.axes[j];
                    const double offset = glm::dot(n, obb.center) + obb.halfExtents[j] + kSkinM;
                    if (glm::dot(n, goal) >= offset - kFeasibleM) {
                        continue;
                    }
                    if (covered(scene, candidates, p + kProbeM * n - kProbeM * entered, hit.slot)) {
                        continue;
                    }
                    addPlane({n, offset, hit.slot});
                }
            }
            continue;
        }
        p = target;
        pruneNonBinding(p);
        if (it + 1 >= mConfig.maxIterations) {
            break;
        }
        // Drop planes whose object the proxy has slid off; then sweep on toward the goal.
        std::uint32_t kept = 0;
        for (std::uint32_t i = 0; i < s.planeCount; ++i) {
            if (distanceToSkin(scene.object(s.planes[i].slot), p) <= kOnM) {
                s.planes[kept++] = s.planes[i];
            }
        }
        const bool dropped = kept != s.planeCount;
        s.planeCount = kept;
        if (!dropped) {
            break;
        }
    }
    s.proxy = p;
    return s;
}

RenderOutput GodObjectRenderer::update(const Scene& scene, const CandidateSet& candidates,
                                       const Vec3& devicePosition, const Vec3& deviceVelocity,
                                       double dtSeconds) noexcept {
    RenderOutput out;
    ++mCounters.ticks;
    mNearRadius = -1.0;
    mNearCount = 0;
    mNearOverflow = false;
    if (!finite(devicePosition)) {
        out.status = RenderStatus::NonFiniteInput;
        out.proxy = mProxy;
        ++mCounters.nonFiniteInput;
        return out;
    }
    if (!finite(mProxy)) {
        reset(devicePosition);
    }
    Vec3 velocity = deviceVelocity;
    if (!finite(velocity)) {
        velocity = Vec3(0.0);
        if (mHasLastDevice && dtSeconds > 0.0 && std::isfinite(dtSeconds)) {
            velocity = (devicePosition - mLastDevice) / dtSeconds;
            if (!finite(velocity)) {
                velocity = Vec3(0.0);
            }
        }
    }
    mLastDevice = devicePosition;
    mHasLastDevice = true;

    const Vec3 goal = devicePosition;
    Vec3 start = mProxy;
    std::uint32_t tested = 0;
    // Every point the proxy visits while solving toward g lies within |start - g| of g.
    auto ensureNear = [&](const Vec3& g, double need) {
        if (mNearRadius < 0.0 || glm::length(g - mNearCenter) + need > mNearRadius) {
            buildNear(scene, candidates, g, need + kNearMarginM, tested);
        }
    };
    ensureNear(goal, (1.0 + kFrictionCover) * glm::length(start - goal));

    // A touched object that moved carries the proxy with it: friction holds in the object's
    // frame, so an object that is pushed, carried or grasped takes its contact point along.
    for (std::uint32_t i = 0; i < mContactCount; ++i) {
        const std::uint32_t slot = mContactSlots[i];
        const ContactPose& was = mContactPoses[i];
        if (slot >= scene.size() || scene.object(slot).id != was.id) {
            continue; // the world was re-indexed and the slot now names another object
        }
        const SceneObject& o = scene.object(slot);
        if (o.center != was.center || o.rotation != was.rotation) {
            start = o.center + o.rotation * (glm::conjugate(was.rotation) * (start - was.center));
            ensureNear(goal, (1.0 + kFrictionCover) * glm::length(start - goal));
            break;
        }
    }

    // A touched object that moved into the proxy pushes it back out to its surface.
    if (mContactCount > 0) {
        forEachNear(scene, candidates, [&](std::uint32_t slot) {
            const SceneObject& o = scene.object(slot);
            if (std::find(mContactSlots.begin(), mContactSlots.begin() + mContactCount, slot) !=
                    mContactSlots.begin() + mContactCount &&
                insideSkin(o, start)) {
                start = pushOut(o, start);
            }
        });
        ensureNear(goal, (1.0 + kFrictionCover) * glm::length(start - goal));
    }

    const Solve free = solve(scene, candidates, start, goal);
    Solve fin = free;
    std::uint32_t iterations = free.iterations;

    // Friction: the contact materials of the frictionless solution.
    double muStatic = kInf;
    double muDynamic = kInf;
    std::uint32_t freeContacts = 0;
    for (std::uint32_t i = 0; i < free.planeCount; ++i) {
        if (glm::dot(free.planes[i].normal, goal) < free.planes[i].offset) {
            const Material& m = scene.object(free.planes[i].slot).material;
            muStatic = std::min(muStatic, m.staticFriction);
            muDynamic = std::min(muDynamic, m.dynamicFriction);
            ++freeContacts;
        }
    }
    bool stuck = false;
    const Vec3 toFree = free.proxy - goal;
    const double penetration = glm::length(toFree);
    if (freeContacts > 0 && penetration > 0.0 && (muStatic > 0.0 || muDynamic > 0.0)) {
        const Vec3 n = toFree / penetration;
        const Vec3 anchor = mContactCount > 0 ? start : (free.touched ? free.firstTouch : start);
        const double mu = mSlipping ? muDynamic : muStatic;
        const Vec3 rel = anchor - goal;
        const double normal = glm::dot(n, rel);
        const double tangential = glm::length(rel - normal * n);
        // The anchor must still rest on something (an object may have moved away under it).
        bool anchorTouches = false;
        forEachNear(scene, candidates, [&](std::uint32_t slot) {
            anchorTouches = anchorTouches || distanceToSkin(scene.object(slot), anchor) <= kOnM;
        });
        if (anchorTouches && normal > 0.0 && tangential <= mu * normal + 1e-12) {
            stuck = true;
            mSlipping = false;
            fin.proxy = anchor;
        } else {
            mSlipping = true;
            const Vec3 lag = anchor - free.proxy;
            const Vec3 lagT = lag - glm::dot(n, lag) * n;
            const double lagLen = glm::length(lagT);
            if (lagLen > 1e-15 && muDynamic > 0.0) {
                // Shift the goal back along the surface by mu_d x penetration (never past the
                // anchor) and solve again: the proxy trails by exactly that much.
                const Vec3 g2 = goal + lagT * (std::min(muDynamic * penetration, lagLen) / lagLen);
                ensureNear(g2, glm::length(start - g2));
                fin = solve(scene, candidates, start, g2);
                iterations += fin.iterations;
            }
        }
    }

    // Contacts: planes the final proxy is on and the device point is behind.
    double stiffness = kInf;
    for (std::uint32_t i = 0; i < fin.planeCount && out.contactCount < kMaxContacts; ++i) {
        const Plane& pl = fin.planes[i];
        const double depth = pl.offset - glm::dot(pl.normal, goal);
        const bool onPlane = stuck || glm::dot(pl.normal, fin.proxy) - pl.offset <= kOnM;
        if (depth <= 0.0 || !onPlane) {
            continue;
        }
        const SceneObject& o = scene.object(pl.slot);
        out.contacts[out.contactCount++] = {pl.slot, o.id, pl.normal, depth};
        stiffness = std::min(stiffness, o.material.stiffness);
    }

    Vec3 force(0.0);
    if (out.contactCount > 0) {
        force = stiffness * (fin.proxy - goal);
        const double magnitude = glm::length(force);
        if (mConfig.damping > 0.0 && magnitude > 0.0) {
            const Vec3 n = force / magnitude;
            force -= mConfig.damping * glm::dot(n, velocity) * n;
            const double along = glm::dot(n, force);
            if (along < 0.0) { // damping may soften a push, never pull into the surface
                force -= along * n;
            }
        }
    } else {
        mSlipping = false;
    }

    out.proxy = fin.proxy;
    out.force = force;
    out.sliding = out.contactCount > 0 && !stuck && glm::length(fin.proxy - start) > kOnM;
    out.iterations = static_cast<std::uint8_t>(std::min<std::uint32_t>(iterations, 255));
    out.objectsTested = tested;
    if (mNearOverflow) {
        out.status = RenderStatus::NearListFull;
        ++mCounters.nearListFull;
    } else if (candidates.overflowed) {
        out.status = RenderStatus::CandidatesDropped;
    }
    if (candidates.overflowed) {
        ++mCounters.candidatesDropped;
    }
    if (!finite(out.force) || !finite(out.proxy)) {
        out.status = RenderStatus::NonFiniteOutput;
        ++mCounters.nonFiniteOutput;
        out.force = Vec3(0.0);
        out.proxy = finite(start) ? start : goal;
        out.contactCount = 0;
        out.sliding = false;
    }

    mProxy = out.proxy;
    mContactCount = out.contactCount;
    for (std::uint32_t i = 0; i < out.contactCount; ++i) {
        const SceneObject& o = scene.object(out.contacts[i].slot);
        mContactSlots[i] = out.contacts[i].slot;
        mContactPoses[i] = {o.id, o.center, o.rotation};
    }
    return out;
}

} // namespace hapto
