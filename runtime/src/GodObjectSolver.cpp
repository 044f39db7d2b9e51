/// The god-object renderer's proxy solve: plane solve, swept test, edge and corner rules.
///
/// Design note
/// -----------
/// Idea. The proxy moves toward a goal as far as the surfaces allow, in passes. A pass solves
/// for the point nearest the goal inside the active constraint half-spaces (at most three
/// planes; core's closestPointInHalfSpaces, an 8-subset enumeration), then sweeps the straight
/// path from the proxy to that point against the near items (core's SweptShapes) and stops at
/// the first skin it would enter. The face (or sphere tangent plane, or triangle plane)
/// entered becomes a constraint; when the stop point lies on an edge or a corner, every face
/// there that the goal is behind is added too (Zilles & Salisbury's rule: a box's other faces
/// unless another object covers them, a mesh's neighbouring triangles there), so pressing into
/// an edge keeps the proxy on the edge. Planes whose item no longer touches the proxy (it slid
/// off a face, or along a sphere's tangent plane) are dropped and the sweep toward the goal
/// repeats, for at most maxIterations passes. A solve may go on from where another ended, with
/// the planes that one rests on there: the friction solve from the frictionless one, and a
/// tick's first solve from the last tick's end (restingPlanes), so neither spends a pass
/// meeting again at t = 0 the surfaces its start rests on.
///
/// Invariant. At the end of every pass the proxy lies outside the shrunk skin of every near
/// item that did not already contain it at the start of the sweep: a sweep never crosses a
/// surface, whatever the speed. Coplanar planes are kept once, so shared mesh edges do not
/// snag. Every pass's end is a visited point (visitedPath), so the tick can walk where the
/// proxy went.
///
/// Cost. Per pass: one <= 3-plane solve (at most 8 tiny linear solves) plus one swept test per
/// near item; an edge or corner hit adds one scan of the near list. No allocation.

#include "GodObjectParts.h"

#include "hapto/core/SweptShapes.h"

#include <cmath>

namespace hapto {

using namespace godobject;

/// The first surface a swept path enters.
struct GodObjectRenderer::Hit {
    bool found = false;
    double t = kInf;
    double tStop = 0.0;
    std::uint32_t item = 0; ///< A box or sphere slot, or a triangle item.
    int axis = -1;
    double sign = 0.0;
    std::uint32_t near = kNotCached; ///< A triangle's place in mTriangleData, if there.
};

void GodObjectRenderer::Solve::keepPlanesOn(const Vec3& at) noexcept {
    std::uint32_t kept = 0;
    for (std::uint32_t i = 0; i < planeCount; ++i) {
        if (glm::dot(planes[i].normal, at) - planes[i].offset <= kOnM) {
            planes[kept++] = planes[i];
        }
    }
    planeCount = kept;
}

bool GodObjectRenderer::Solve::addPlane(const Plane& plane) noexcept {
    for (std::uint32_t i = 0; i < planeCount; ++i) {
        const Plane& q = planes[i];
        if (glm::dot(q.normal, plane.normal) > 1.0 - 1e-12 &&
            std::abs(q.offset - plane.offset) <= kOnM) {
            return true;
        }
    }
    if (planeCount == kMaxContacts) {
        return false;
    }
    planes[planeCount++] = plane;
    return true;
}

GodObjectRenderer::Hit GodObjectRenderer::sweep(const Scene& scene, const CandidateSet& candidates,
                                                const Vec3& from, const Vec3& to) const noexcept {
    Hit best;
    // The bounding box of the segment up to the nearest entry found so far: a box or sphere
    // whose skin's bounding box it misses cannot be entered before that (the entry test's
    // surface lies kShrinkM inside that skin, far more than rounding), so most of a long near
    // list ends at six comparisons, and once a hit is found, so do the items beyond it. A
    // triangle's test likewise skips its edge tests when its skin plane lies beyond that hit
    // (an entry is kept only when strictly nearer).
    Vec3 mid = 0.5 * (from + to);
    Vec3 half = 0.5 * glm::abs(to - from);
    // Inlined into forEachNear's loops: a call per item cost about 5 % of a swept tick.
    const auto test = [&](std::uint32_t item, std::uint32_t near) __attribute__((always_inline)) {
        SweptEntry e;
        if (near != kNotCached) {
            const NearTriangle& t = mTriangleData[near];
            e = sweepTriangleFront(
                t.face.normal, t.face.offset, [&]() -> const NearTriangle& { return t; }, from, to,
                kSkinM, kShrinkM, kOnM, best.t);
        } else if (isTriangleItem(item)) {
            const WorldFace tp = faceAt(scene, item);
            e = sweepTriangleFront(
                tp.normal, tp.offset,
                [&] { return fetchTriangle(cornersAt(scene, item), tp.normal); }, from, to, kSkinM,
                kShrinkM, kOnM, best.t);
        } else {
            const RenderBody& o = bodyAt(scene, item);
            const Vec3 reach = half + (o.axisAligned ? o.halfExtents : Vec3(o.radius)) + kSkinM;
            const Vec3 apart = glm::abs(o.center - mid);
            if (apart.x > reach.x || apart.y > reach.y || apart.z > reach.z) {
                return;
            }
            if (o.shape == Shape::Sphere) {
                e = sweepSphere(o.center, o.halfExtents.x, from, to, kSkinM, kShrinkM);
            } else {
                const Vec3 a = o.toLocal(from);
                e = sweepBoxLocal(o.halfExtents, a, o.toLocal(to) - a, kSkinM, kShrinkM);
            }
        }
        if (e.found && e.t < best.t) {
            best = {true, e.t, e.tStop, item, e.axis, e.sign, near};
            const Vec3 end = from + e.t * (to - from);
            mid = 0.5 * (from + end);
            half = 0.5 * glm::abs(end - from);
        }
    };
    forEachNear(scene, candidates, test);
    return best;
}

bool GodObjectRenderer::covered(const Scene& scene, const CandidateSet& candidates,
                                const Vec3& probe, std::uint32_t self) const noexcept {
    bool inside = false;
    // Boxes and spheres only: flush meshes are not looked for (see DESIGN, "Triangles").
    forEachNear(scene, candidates, [&](std::uint32_t item, std::uint32_t) {
        if (!inside && item != self && !isTriangleItem(item)) {
            inside = insideSkin(bodyAt(scene, item), probe);
        }
    });
    return inside;
}

GodObjectRenderer::Solve GodObjectRenderer::solve(const Scene& scene,
                                                  const CandidateSet& candidates, const Vec3& start,
                                                  const Vec3& goal, const Solve* from) noexcept {
    Solve s;
    if (from != nullptr) {
        s.planes = from->planes;
        s.planeCount = from->planeCount;
    }
    Vec3 p = start;
    visit(p);
    for (std::uint32_t it = 0; it < mConfig.maxIterations; ++it) {
        s.iterations = it + 1;
        const Vec3 target =
            closestPointInHalfSpaces(s.planes.data(), s.planeCount, goal, p, kFeasibleM);
        const Hit hit = sweep(scene, candidates, p, target);
        if (hit.found) {
            p += hit.tStop * (target - p);
            visit(p);
            if (!s.touched) {
                s.touched = true;
                s.firstTouch = p;
            }
            s.keepPlanesOn(p);
            if (!addHitPlanes(scene, candidates, s, hit, p, target, goal)) {
                break;
            }
            continue;
        }
        p = target;
        visit(p);
        s.keepPlanesOn(p);
        // Drop planes whose item the proxy has slid off; then sweep on toward the goal.
        if (it + 1 >= mConfig.maxIterations || !dropSlidOff(scene, s, p)) {
            break;
        }
    }
    s.proxy = p;
    return s;
}

bool GodObjectRenderer::addHitPlanes(const Scene& scene, const CandidateSet& candidates, Solve& s,
                                     const Hit& hit, const Vec3& p, const Vec3& target,
                                     const Vec3& goal) noexcept {
    if (isTriangleItem(hit.item)) {
        const WorldFace tp =
            hit.near != kNotCached ? mTriangleData[hit.near].face : faceAt(scene, hit.item);
        if (!s.addPlane({tp.normal, tp.offset + kSkinM, hit.item, hit.near})) {
            return false;
        }
        addTriangleNeighbourPlanes(scene, candidates, s, hit, p, goal);
        return true;
    }
    const RenderBody& o = bodyAt(scene, hit.item);
    if (o.shape == Shape::Sphere) {
        Vec3 n = p - o.center;
        const double len = glm::length(n);
        n = len > 0.0 ? n / len : glm::normalize(p - target);
        return s.addPlane({n, glm::dot(n, o.center) + o.halfExtents.x + kSkinM, hit.item});
    }
    const Vec3 entered = hit.sign * o.axes[hit.axis];
    if (!s.addPlane(
            {entered, glm::dot(entered, o.center) + o.halfExtents[hit.axis] + kSkinM, hit.item})) {
        return false;
    }
    addBoxEdgePlanes(scene, candidates, s, hit, p, goal);
    return true;
}

void GodObjectRenderer::addTriangleNeighbourPlanes(const Scene& scene,
                                                   const CandidateSet& candidates, Solve& s,
                                                   const Hit& hit, const Vec3& p,
                                                   const Vec3& goal) noexcept {
    // On an edge or a vertex: every other triangle of the same mesh there (the proxy is on its
    // skin plane, over it grown by the skin, as on a box's edge) that the goal is behind.
    // Coplanar neighbours give the same plane, which addPlane keeps once.
    const std::uint32_t mesh =
        hit.near != kNotCached ? mTriangleData[hit.near].mesh : scene.objectSlotOf(hit.item);
    forEachNear(scene, candidates, [&](std::uint32_t other, std::uint32_t near) {
        if (other == hit.item || !isTriangleItem(other)) {
            return;
        }
        const NearTriangle* t = near != kNotCached ? &mTriangleData[near] : nullptr;
        if ((t ? t->mesh : scene.objectSlotOf(other)) != mesh) {
            return;
        }
        const WorldFace op = t ? t->face : faceAt(scene, other);
        const double offset = op.offset + kSkinM;
        if (op.normal == Vec3(0.0) || glm::dot(op.normal, goal) >= offset - kFeasibleM ||
            glm::dot(op.normal, p) < offset - kOnM ||
            !(t ? overGrownTriangle(p, t->corners, op.normal, t->edges, kSkinM + kOnM)
                : overGrownTriangle(p, cornersAt(scene, other), op.normal, kSkinM + kOnM))) {
            return;
        }
        s.addPlane({op.normal, offset, other, near});
    });
}

void GodObjectRenderer::addBoxEdgePlanes(const Scene& scene, const CandidateSet& candidates,
                                         Solve& s, const Hit& hit, const Vec3& p,
                                         const Vec3& goal) noexcept {
    // On an edge or a corner: every other face there that the goal is behind, unless another
    // object covers it (flush neighbours make internal faces).
    const RenderBody& o = bodyAt(scene, hit.item);
    const Vec3 entered = hit.sign * o.axes[hit.axis];
    const Vec3 l = o.toLocal(p);
    for (int j = 0; j < 3; ++j) {
        if (j == hit.axis) {
            continue;
        }
        for (const double side : {-1.0, 1.0}) {
            if (side * l[j] < o.halfExtents[j] + kSkinM - kOnM) {
                continue;
            }
            const Vec3 n = side * o.axes[j];
            const double offset = glm::dot(n, o.center) + o.halfExtents[j] + kSkinM;
            if (glm::dot(n, goal) >= offset - kFeasibleM) {
                continue;
            }
            if (covered(scene, candidates, p + kProbeM * n - kProbeM * entered, hit.item)) {
                continue;
            }
            s.addPlane({n, offset, hit.item});
        }
    }
}

std::uint32_t GodObjectRenderer::cachedTriangle(std::uint32_t item) const noexcept {
    for (std::uint32_t k = 0; k < mTriangleCount; ++k) {
        if (mTriangleData[k].item == item) {
            return k;
        }
    }
    return kNotCached;
}

GodObjectRenderer::Solve GodObjectRenderer::restingPlanes(const Scene& scene,
                                                          const Vec3& start) const noexcept {
    // The planes the last tick ended on, taken again from the scene as it is now: a triangle's
    // face, the box face with the same normal, a sphere's tangent plane at the start; each
    // only while the start touches its item (dropSlidOff's test). So a surface that moved,
    // changed or went away gives no plane, and every plane given is one the first pass would
    // meet at t = 0 (it only holds the proxy back; the sweeps decide what it enters).
    Solve s;
    if (start != mState.proxy) {
        return s; // carried or pushed out: its planes are found by the solve
    }
    for (std::uint32_t i = 0; i < mState.restCount; ++i) {
        const std::uint32_t item = mState.restItems[i];
        if (!validItem(scene, item) || skipItem(scene, item)) {
            continue;
        }
        Plane plane{Vec3(0.0), 0.0, item, kNotCached};
        if (isTriangleItem(item)) {
            plane.near = cachedTriangle(item);
            const WorldFace f =
                plane.near != kNotCached ? mTriangleData[plane.near].face : faceAt(scene, item);
            plane.normal = f.normal;
            plane.offset = f.offset + kSkinM;
        } else {
            const RenderBody& o = bodyAt(scene, item);
            if (o.shape == Shape::Sphere) {
                const Vec3 out = start - o.center;
                const double len = glm::length(out);
                if (!(len > 0.0)) {
                    continue;
                }
                plane.normal = out / len;
                plane.offset = glm::dot(plane.normal, o.center) + o.halfExtents.x + kSkinM;
            } else if (o.shape == Shape::Box) {
                for (int j = 0; j < 3; ++j) {
                    for (const double side : {-1.0, 1.0}) {
                        const Vec3 n = side * o.axes[j];
                        if (glm::dot(n, mState.restNormals[i]) > 1.0 - 1e-12) {
                            plane.normal = n;
                            plane.offset = glm::dot(n, o.center) + o.halfExtents[j] + kSkinM;
                        }
                    }
                }
            }
        }
        if (plane.normal == Vec3(0.0) || glm::dot(plane.normal, start) - plane.offset > kOnM ||
            distanceToSkinOf(scene, item, plane.near, start) > kOnM) {
            continue;
        }
        s.addPlane(plane);
    }
    return s;
}

bool GodObjectRenderer::dropSlidOff(const Scene& scene, Solve& s, const Vec3& p) const noexcept {
    std::uint32_t kept = 0;
    for (std::uint32_t i = 0; i < s.planeCount; ++i) {
        const Plane& plane = s.planes[i];
        const double away = distanceToSkinOf(scene, plane.item, plane.near, p);
        if (away <= kOnM) {
            s.planes[kept++] = s.planes[i];
        }
    }
    const bool dropped = kept != s.planeCount;
    s.planeCount = kept;
    return dropped;
}

} // namespace hapto
