/// God-object proxy solver: point tool vs oriented boxes, spheres and mesh triangles, with
/// Coulomb friction.
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
/// Triangles. A mesh is its triangles (index items; a moving mesh's object slot stands for its
/// triangles near the path, found in the mesh's own frame). A triangle is entered only from its
/// front: its skin slab is the plane kSkinM in front over the triangle grown by kSkinM across
/// its edges (a box face's skin, so a flat mesh feels like the box face it replaces), and a
/// path that really crosses the triangle is stopped too. At an edge or vertex the same mesh's
/// triangles there that the goal is behind are added (Zilles & Salisbury); coplanar ones give
/// the same plane, kept once, so shared edges do not snag. One-sidedness is also what frees a
/// proxy inside a closed mesh: from inside, every path leaves through back faces.
///
/// Cost. One pass over the candidate spans per tick builds a deduplicated near list of the
/// objects whose bounding sphere meets the ball around the goal that the proxy can reach this
/// tick (every point the proxy visits is no farther from the goal than where it started),
/// with a generous margin for objects and 1 µm for triangles (a fine mesh stays a few items).
/// Each solver pass is one <= 3-plane solve (at most 8 tiny linear solves) plus one swept test
/// per near item (slab clipping in the box frame, a quadratic for a sphere, a plane crossing and
/// three edge tests for a triangle, after a plane test that rejects most; every pose, matrix,
/// radius and triangle plane comes precomputed from the scene's render copy). Worst case per tick:
/// 2 solves x maxIterations x near items; typically 2-3 passes over 1-5 objects or a handful of
/// triangles. No allocation: the near list and plane sets are fixed arrays.

#include "hapto/runtime/GodObjectRenderer.h"

#include "hapto/core/Finite.h"
#include "hapto/core/ShapeGeometry.h"
#include "hapto/core/SweptShapes.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace hapto {

static_assert(sizeof(GodObjectRenderer) == 10176, "update the size in GodObjectRenderer.h");
static_assert(alignof(GodObjectRenderer) == 64);

namespace {

constexpr double kSkinM = GodObjectRenderer::kSkinM;
constexpr double kShrinkM = 1e-9;     ///< Swept tests use surfaces this far inside the skin (m).
constexpr double kOnM = 2e-9;         ///< "On a plane / touching an object" tolerance (m).
constexpr double kProbeM = 4e-9;      ///< Covered-face probe step (m), > kShrinkM.
constexpr double kFeasibleM = 1e-12;  ///< Half-space feasibility slack (m).
constexpr double kNearMarginM = 1e-3; ///< Extra radius of the near ball for objects (m).
constexpr double kTriangleNearMarginM = 1e-6; ///< Extra radius of the near ball for triangles (m).
constexpr double kFrictionCover = 1.0; ///< Near ball also covers a friction lag up to mu_d = 1.
constexpr double kInf = std::numeric_limits<double>::infinity();

double length2(const Vec3& v) {
    return glm::dot(v, v);
}

/// True when p is inside the object's shrunk skin (strictly).
bool insideSkin(const RenderBody& o, const Vec3& p) {
    return o.shape == Shape::Sphere
               ? sphereStrictlyContains(o.center, o.halfExtents.x + kSkinM - kShrinkM, p)
               : boxStrictlyContains(o.obb(), p, kSkinM - kShrinkM);
}

/// Distance (m) from p to the object's skin, 0 inside.
double distanceToSkin(const RenderBody& o, const Vec3& p) {
    return o.shape == Shape::Sphere
               ? std::max(0.0, sphereSignedDistance(o.center, o.halfExtents.x + kSkinM, p))
               : boxDistanceOutside(o.obb(), p, kSkinM);
}

/// The nearest point on the object's skin to an inside point p.
Vec3 pushOut(const RenderBody& o, const Vec3& p) {
    if (o.shape == Shape::Sphere) {
        return sphereSurfacePointNearest(o.center, o.halfExtents.x + kSkinM, p);
    }
    return o.toWorld(boxSurfacePointNearestLocal(o.toLocal(p), o.halfExtents + Vec3(kSkinM)));
}

/// A triangle's corners and edges read from the scene (m, world), for one not in the near
/// list's copy.
TriangleGeometry fetchTriangle(const Scene& scene, std::uint32_t item, const Vec3& normal) {
    const std::array<Vec3, 3> v = scene.triangleCorners(item);
    return {v, triangleEdges(v, normal)};
}

/// A valid item of this scene: a box or sphere slot, or a triangle item.
bool validItem(const Scene& scene, std::uint32_t item) {
    if (isTriangleItem(item)) {
        return (item & ~kTriangleItemBit) < scene.triangleCount();
    }
    return item < scene.size() && scene.object(item).shape != Shape::Mesh;
}

/// The item of a mesh object's first triangle: the scene numbers triangles mesh by mesh in
/// slot order, so a binary search over the numbers finds it. O(log triangles x log meshes).
std::uint32_t firstTriangleItem(const Scene& scene, std::uint32_t slot) {
    std::uint32_t lo = 0;
    std::uint32_t hi = scene.triangleCount();
    while (lo < hi) {
        const std::uint32_t mid = lo + (hi - lo) / 2;
        if (scene.triangle(kTriangleItemBit | mid).objectSlot < slot) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    return kTriangleItemBit | lo;
}

/// Visits (calls fn(t) for) every triangle of `mesh` whose local bounds meet `localBox` (m,
/// mesh frame), without allocating: the mesh's own local-frame BVH, built once with the mesh.
template <class Fn>
void visitMeshTrianglesNear(const TriangleMesh& mesh, const Aabb& localBox, Fn&& fn) {
    mesh.forEachTriangleNear(localBox, std::forward<Fn>(fn));
}

double itemDistanceToSkin(const Scene& scene, std::uint32_t item, const Vec3& p) {
    if (isTriangleItem(item)) {
        const WorldFace tp = scene.triangleFace(item);
        return triangleSkinDistance(
            tp.normal, tp.offset, [&] { return fetchTriangle(scene, item, tp.normal); }, p, kSkinM);
    }
    return distanceToSkin(scene.body(item), p);
}

} // namespace

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
    mNearRadius = -1.0;
    mNearCount = 0;
    mTriangleCount = 0;
    mNearOverflow = false;
    mNearTriangles = false;
}

template <class Fn>
void GodObjectRenderer::forEachMeshTriangleNear(const Scene& scene, std::uint32_t slot,
                                                const Vec3& center, double radius,
                                                Fn&& fn) const noexcept {
    const SceneObject& o = scene.object(slot);
    if (!o.mesh) {
        return;
    }
    // In the mesh's own frame: distances are the same there, and nothing is transformed but
    // the one point.
    const Vec3 local = scene.body(slot).toLocal(center);
    const double reach = radius + kSkinM;
    const std::uint32_t first = firstTriangleItem(scene, slot);
    const TriangleMesh& mesh = *o.mesh;
    visitMeshTrianglesNear(mesh, Aabb{local - Vec3(reach), local + Vec3(reach)},
                           [&](std::uint32_t t) {
                               if (triangleDistance2(local, mesh.corners(t)) <= reach * reach) {
                                   fn(first + t);
                               }
                           });
}

template <class Fn>
void GodObjectRenderer::forEachNear(const Scene& scene, const CandidateSet& candidates,
                                    Fn&& fn) const noexcept {
    if (!mNearOverflow) {
        for (std::uint32_t i = 0; i < mNearCount; ++i) {
            const std::uint32_t cached = mNearCached[i];
            fn(mNear[i], cached < kCachedTriangles ? cached : kNotCached);
        }
        return;
    }
    // Too many nearby items for the scratch list: walk the spans (duplicates are harmless,
    // they give the same answer twice). A mesh object's slot stands for its triangles within
    // the near ball.
    const std::uint32_t n = scene.size();
    for (std::size_t s = 0; s < candidates.count && s < CandidateSet::kMaxSpans; ++s) {
        for (const std::uint32_t item : candidates.spans[s]) {
            if (isTriangleItem(item)) {
                if (validItem(scene, item)) {
                    fn(item, kNotCached);
                }
            } else if (item < n && scene.object(item).shape == Shape::Mesh) {
                forEachMeshTriangleNear(scene, item, mNearCenter, mNearRadius,
                                        [&](std::uint32_t t) { fn(t, kNotCached); });
            } else if (item < n) {
                fn(item, kNotCached);
            }
        }
    }
}

double GodObjectRenderer::distanceToSkinOf(const Scene& scene, std::uint32_t item,
                                           std::uint32_t near, const Vec3& p) const noexcept {
    if (near == kNotCached) {
        return itemDistanceToSkin(scene, item, p);
    }
    const NearTriangle& t = mTriangleData[near];
    return triangleSkinDistance(
        t.face.normal, t.face.offset, [&]() -> const NearTriangle& { return t; }, p, kSkinM);
}

bool GodObjectRenderer::addNear(std::uint32_t item) noexcept {
    if (mNearOverflow) {
        return false;
    }
    for (std::uint32_t k = 0; k < mNearCount; ++k) {
        if (mNear[k] == item) {
            return false;
        }
    }
    if (mNearCount == kMaxNearObjects) {
        mNearOverflow = true;
        return false;
    }
    mNear[mNearCount++] = item;
    return true;
}

void GodObjectRenderer::buildNear(const Scene& scene, const CandidateSet& candidates,
                                  const Vec3& center, double reach,
                                  std::uint32_t& tested) noexcept {
    mNearCenter = center;
    mNearRadius = reach + kTriangleNearMarginM;
    mNearCount = 0;
    mNearOverflow = false;
    mNearTriangles = false;
    // Triangles get a tight ball (the reach plus 1 µm) so that a fine mesh adds only the few
    // triangles the proxy can touch this tick; boxes and spheres keep a generous one (room for
    // a friction lag up to mu_d = 1, plus 1 mm), as cheap as it is few.
    const double radius = (1.0 + kFrictionCover) * reach + kNearMarginM;
    const double triangleReach = mNearRadius + kSkinM;
    const std::uint32_t n = scene.size();
    std::uint32_t triangles = 0; // valid triangle candidates so far (an item once)
    for (std::size_t s = 0; s < candidates.count && s < CandidateSet::kMaxSpans; ++s) {
        tested += static_cast<std::uint32_t>(candidates.spans[s].size());
        for (const std::uint32_t item : candidates.spans[s]) {
            if (mNearOverflow) {
                break;
            }
            // Neighbouring leaves share the triangles that straddle them: an item an earlier
            // span listed was decided there (the same test gives the same answer). Leaf lists
            // are sorted; an unsorted span (the moving list) is only ever not found in.
            if (std::any_of(candidates.spans.begin(), candidates.spans.begin() + s,
                            [&](const std::span<const std::uint32_t> earlier) {
                                return std::binary_search(earlier.begin(), earlier.end(), item);
                            })) {
                continue;
            }
            if (isTriangleItem(item)) {
                if (validItem(scene, item)) {
                    mNearTriangles = true;
                    // The k-th candidate triangle is the same in every list of the tick (the
                    // same spans, in the same order): what an earlier list read, it reuses.
                    const std::uint32_t k = triangles++;
                    NearTriangle* t = k < kCachedTriangles ? &mTriangleData[k] : nullptr;
                    if (t && (k >= mTriangleCount || t->item != item)) {
                        // Field by field: the corners and edges are written when first needed.
                        t->item = item;
                        t->hasCorners = false;
                        t->hasEdges = false;
                        t->face = scene.triangleFace(item);
                        mTriangleCount = k + 1;
                    }
                    // The distance to the plane bounds the distance to the triangle: most
                    // candidates end at one dot product.
                    const WorldFace f = t ? t->face : scene.triangleFace(item);
                    if (std::abs(glm::dot(f.normal, center) - f.offset) > triangleReach) {
                        continue;
                    }
                    if (t && !t->hasCorners) {
                        t->corners = scene.triangleCorners(item);
                        t->hasCorners = true;
                    }
                    const std::array<Vec3, 3> v = t ? t->corners : scene.triangleCorners(item);
                    // A corner well inside the ball (by far more than rounding) makes the
                    // triangle near without the closest-point test.
                    const double r2 = triangleReach * triangleReach;
                    const bool cornerInside =
                        std::min({length2(v[0] - center), length2(v[1] - center),
                                  length2(v[2] - center)}) < r2 * (1.0 - 1e-9);
                    if ((!cornerInside && triangleDistance2(center, v) > r2) || !addNear(item)) {
                        continue;
                    }
                    if (t && !t->hasEdges) {
                        t->edges = triangleEdges(v, f.normal);
                        t->mesh = scene.objectSlotOf(item);
                        t->hasEdges = true;
                    }
                    mNearCached[mNearCount - 1] =
                        static_cast<std::uint8_t>(t ? k : kCachedTriangles);
                }
                continue;
            }
            if (item >= n) {
                continue;
            }
            const RenderBody& o = scene.body(item);
            const double reach = radius + o.radius + kSkinM;
            if (length2(o.center - center) > reach * reach) {
                continue;
            }
            if (o.shape == Shape::Mesh) {
                // A moving mesh (or an index that holds whole meshes): its triangles near the
                // ball, from the mesh's own frame.
                mNearTriangles = true;
                forEachMeshTriangleNear(scene, item, center, mNearRadius, [&](std::uint32_t t) {
                    if (addNear(t)) {
                        mNearCached[mNearCount - 1] = kCachedTriangles;
                    }
                });
                continue;
            }
            if (addNear(item)) {
                mNearCached[mNearCount - 1] = kCachedTriangles;
            }
        }
    }
}

GodObjectRenderer::Hit GodObjectRenderer::sweep(const Scene& scene, const CandidateSet& candidates,
                                                const Vec3& from, const Vec3& to) const noexcept {
    Hit best;
    forEachNear(scene, candidates, [&](std::uint32_t item, std::uint32_t near) {
        SweptEntry e;
        if (near != kNotCached) {
            const NearTriangle& t = mTriangleData[near];
            e = sweepTriangleFront(
                t.face.normal, t.face.offset, [&]() -> const NearTriangle& { return t; }, from, to,
                kSkinM, kShrinkM, kOnM);
        } else if (isTriangleItem(item)) {
            const WorldFace tp = scene.triangleFace(item);
            e = sweepTriangleFront(
                tp.normal, tp.offset, [&] { return fetchTriangle(scene, item, tp.normal); }, from,
                to, kSkinM, kShrinkM, kOnM);
        } else {
            const RenderBody& o = scene.body(item);
            if (o.shape == Shape::Sphere) {
                e = sweepSphere(o.center, o.halfExtents.x, from, to, kSkinM, kShrinkM);
            } else {
                const Vec3 a = o.toLocal(from);
                e = sweepBoxLocal(o.halfExtents, a, o.toLocal(to) - a, kSkinM, kShrinkM);
            }
        }
        if (e.found && e.t < best.t) {
            best = {true, e.t, e.tStop, item, e.axis, e.sign, near};
        }
    });
    return best;
}

bool GodObjectRenderer::covered(const Scene& scene, const CandidateSet& candidates,
                                const Vec3& probe, std::uint32_t self) const noexcept {
    bool inside = false;
    // Boxes and spheres only: flush meshes are not looked for (see DESIGN, "Triangles").
    forEachNear(scene, candidates, [&](std::uint32_t item, std::uint32_t) {
        if (!inside && item != self && !isTriangleItem(item)) {
            inside = insideSkin(scene.body(item), probe);
        }
    });
    return inside;
}

GodObjectRenderer::Solve GodObjectRenderer::solve(const Scene& scene,
                                                  const CandidateSet& candidates, const Vec3& start,
                                                  const Vec3& goal) noexcept {
    Solve s;
    Vec3 p = start;
    visit(p);

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
            pruneNonBinding(p);
            if (isTriangleItem(hit.item)) {
                const WorldFace tp = hit.near != kNotCached ? mTriangleData[hit.near].face
                                                            : scene.triangleFace(hit.item);
                if (!addPlane({tp.normal, tp.offset + kSkinM, hit.item, hit.near})) {
                    break;
                }
                // On an edge or a vertex: every other triangle of the same mesh there (the
                // proxy is on its skin plane, over it grown by the skin, as on a box's edge)
                // that the goal is behind. Coplanar neighbours give the same plane, which
                // addPlane keeps once.
                const std::uint32_t mesh = hit.near != kNotCached ? mTriangleData[hit.near].mesh
                                                                  : scene.objectSlotOf(hit.item);
                forEachNear(scene, candidates, [&](std::uint32_t other, std::uint32_t near) {
                    if (other == hit.item || !isTriangleItem(other)) {
                        return;
                    }
                    const NearTriangle* t = near != kNotCached ? &mTriangleData[near] : nullptr;
                    if ((t ? t->mesh : scene.objectSlotOf(other)) != mesh) {
                        return;
                    }
                    const WorldFace op = t ? t->face : scene.triangleFace(other);
                    const double offset = op.offset + kSkinM;
                    if (op.normal == Vec3(0.0) ||
                        glm::dot(op.normal, goal) >= offset - kFeasibleM ||
                        glm::dot(op.normal, p) < offset - kOnM ||
                        !(t ? overGrownTriangle(p, t->corners, op.normal, t->edges, kSkinM + kOnM)
                            : overGrownTriangle(p, scene.triangleCorners(other), op.normal,
                                                kSkinM + kOnM))) {
                        return;
                    }
                    addPlane({op.normal, offset, other, near});
                });
                continue;
            }
            const RenderBody& o = scene.body(hit.item);
            if (o.shape == Shape::Sphere) {
                Vec3 n = p - o.center;
                const double len = glm::length(n);
                n = len > 0.0 ? n / len : glm::normalize(p - target);
                if (!addPlane({n, glm::dot(n, o.center) + o.halfExtents.x + kSkinM, hit.item})) {
                    break;
                }
                continue;
            }
            const Vec3 entered = hit.sign * o.axes[hit.axis];
            if (!addPlane({entered, glm::dot(entered, o.center) + o.halfExtents[hit.axis] + kSkinM,
                           hit.item})) {
                break;
            }
            // On an edge or a corner: every other face there that the goal is behind, unless
            // another object covers it (flush neighbours make internal faces).
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
                    addPlane({n, offset, hit.item});
                }
            }
            continue;
        }
        p = target;
        visit(p);
        pruneNonBinding(p);
        if (it + 1 >= mConfig.maxIterations) {
            break;
        }
        // Drop planes whose object the proxy has slid off; then sweep on toward the goal.
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
    return update(scene, candidates, devicePosition, devicePosition, deviceVelocity, dtSeconds);
}

RenderOutput GodObjectRenderer::update(const Scene& scene, const CandidateSet& candidates,
                                       const Vec3& devicePosition, const Vec3& goal,
                                       const Vec3& deviceVelocity, double dtSeconds) noexcept {
    RenderOutput out;
    ++mState.counters.ticks;
    mNearRadius = -1.0;
    mNearCount = 0;
    mTriangleCount = 0;
    mNearOverflow = false;
    mNearTriangles = false;
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
    Vec3 velocity = deviceVelocity;
    if (!finite(velocity)) {
        velocity = Vec3(0.0);
        if (mState.hasLastDevice && dtSeconds > 0.0 && std::isfinite(dtSeconds)) {
            velocity = (devicePosition - mState.lastDevice) / dtSeconds;
            if (!finite(velocity)) {
                velocity = Vec3(0.0);
            }
        }
    }
    mState.lastDevice = devicePosition;
    mState.hasLastDevice = true;
    visit(mState.proxy);

    Vec3 start = mState.proxy;
    std::uint32_t tested = 0;
    // Every point the proxy visits while solving toward g lies within |start - g| of g.
    auto ensureNear = [&](const Vec3& g, double need) {
        const double covers =
            mNearTriangles
                ? mNearRadius
                : (1.0 + kFrictionCover) * (mNearRadius - kTriangleNearMarginM) + kNearMarginM;
        if (mNearRadius < 0.0 || glm::length(g - mNearCenter) + need > covers) {
            buildNear(scene, candidates, g, need, tested);
        }
    };
    ensureNear(goal, glm::length(start - goal));

    // A touched object that moved carries the proxy with it: friction holds in the object's
    // frame, so an object that is pushed, carried or grasped takes its contact point along.
    // A touched triangle carries the proxy with its mesh's pose.
    for (std::uint32_t i = 0; i < mState.contactCount; ++i) {
        const std::uint32_t item = mState.contactSlots[i];
        const State::ContactPose& was = mState.contactPoses[i];
        if (!validItem(scene, item) || scene.object(scene.objectSlotOf(item)).id != was.id) {
            continue; // the world was re-indexed and the item now names another object
        }
        const SceneObject& o = scene.object(scene.objectSlotOf(item));
        if (o.center != was.center || o.rotation != was.rotation) {
            start = o.center + o.rotation * (glm::conjugate(was.rotation) * (start - was.center));
            ensureNear(goal, glm::length(start - goal));
            break;
        }
    }

    // A touched object that moved into the proxy pushes it back out to its surface (a touched
    // mesh has carried the proxy in its own frame above, so it stays on its skin).
    if (mState.contactCount > 0) {
        forEachNear(scene, candidates, [&](std::uint32_t slot, std::uint32_t) {
            if (isTriangleItem(slot)) {
                return;
            }
            const RenderBody& o = scene.body(slot);
            if (std::find(mState.contactSlots.begin(),
                          mState.contactSlots.begin() + mState.contactCount,
                          slot) != mState.contactSlots.begin() + mState.contactCount &&
                insideSkin(o, start)) {
                start = pushOut(o, start);
            }
        });
        ensureNear(goal, glm::length(start - goal));
    }

    const Solve free = solve(scene, candidates, start, goal);
    mVisitedSecond = mVisitedCount;
    Solve fin = free;
    std::uint32_t iterations = free.iterations;

    // Friction: the contact materials of the frictionless solution.
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
    bool stuck = false;
    const Vec3 toFree = free.proxy - goal;
    const double penetration = glm::length(toFree);
    if (freeContacts > 0 && penetration > 0.0 && (muStatic > 0.0 || muDynamic > 0.0)) {
        const Vec3 n = toFree / penetration;
        const Vec3 anchor =
            mState.contactCount > 0 ? start : (free.touched ? free.firstTouch : start);
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
            stuck = true;
            mState.slipping = false;
            fin.proxy = anchor;
        } else {
            mState.slipping = true;
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

    Vec3 force(0.0);
    if (out.contactCount > 0) {
        force = stiffness * (fin.proxy - devicePosition);
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
        mState.slipping = false;
    }

    out.proxy = fin.proxy;
    out.force = force;
    out.sliding = out.contactCount > 0 && !stuck && glm::length(fin.proxy - start) > kOnM;
    out.iterations = static_cast<std::uint8_t>(std::min<std::uint32_t>(iterations, 255));
    out.objectsTested = tested;
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
    }

    mState.proxy = out.proxy;
    mState.contactCount = out.contactCount;
    for (std::uint32_t i = 0; i < out.contactCount; ++i) {
        const SceneObject& o = scene.object(scene.objectSlotOf(out.contacts[i].slot));
        mState.contactSlots[i] = out.contacts[i].slot;
        mState.contactPoses[i] = {o.id, o.center, o.rotation};
    }
    return out;
}

} // namespace hapto
