/// The god-object renderer's candidate gathering: the near list and the mesh walk.
///
/// Design note
/// -----------
/// Idea. The candidate spans (leaves of the index, the moving objects) name every item the
/// proxy may meet this tick, many of them far away and many named twice (neighbouring leaves
/// share the triangles that straddle them). One pass over the spans keeps the items that can
/// matter in a deduplicated list (kMaxNearObjects): every point the proxy visits while solving
/// toward a goal g from a start s lies within |s - g| of g, so an item farther than that from
/// g cannot be touched. Boxes and spheres enter when their bounding sphere meets a generous
/// ball (twice the reach, room for a friction lag up to mu_d = 1, plus 1 mm); triangles only
/// when the triangle itself is within the reach plus 1 µm, so a fine mesh under a pressing
/// tool adds a handful of triangles, not every one within a millimetre. A moving mesh's slot
/// stands for its triangles near the ball, found through the mesh's own BVH in its frame.
///
/// Invariant. The list holds every valid item within the ball, once; when it would overflow
/// the tick runs on the raw spans instead (forEachNear), which gives the same answers more
/// slowly. The first kCachedTriangles candidate triangles are copied (plane, then corners,
/// then edges, each when first needed) into mTriangleData, and a second list in the same tick
/// (the friction solve's) meets them in the same order, so it reads nothing again.
///
/// Cost. One pass over the spans (an item already read is skipped: a table of the items read
/// since the list was built, open-addressed and keyed by the build's number so a new list
/// empties it without clearing; past kSeenFull items, a binary search of the earlier, sorted
/// leaf lists); two dot products reject most triangles by their plane; a corner
/// well inside the ball spares the closest-point test. The render copies of the objects new
/// spans name are asked for all at once before the pass reads them (prefetchBodies): the misses
/// of a leaf new to the cache overlap. A tick solved again over more spans (extendNextUpdate)
/// reads only the new ones: the spans are read in order, so the list so extended is the one a
/// build over all of them gives. No allocation.

#include "GodObjectParts.h"

#include <algorithm>
#include <cmath>
#include <span>

namespace hapto {

using namespace godobject;

namespace {

/// Distance (m) from p to the object's skin, 0 inside (a box's frame as in insideSkin).
double distanceToSkin(const RenderBody& o, const Vec3& p) {
    return o.shape == Shape::Sphere
               ? std::max(0.0, sphereSignedDistance(o.center, o.halfExtents.x + kSkinM, p))
               : boxDistanceOutsideLocal(o.halfExtents, o.toLocal(p), kSkinM);
}

/// True when a span before span s lists the item: it was decided there (the same test gives
/// the same answer). Leaf lists are sorted; an unsorted span (the moving list) is only ever
/// not found in.
bool listedEarlier(const CandidateSet& candidates, std::size_t s, std::uint32_t item) {
    return std::any_of(candidates.spans.begin(), candidates.spans.begin() + s,
                       [&](const std::span<const std::uint32_t> earlier) {
                           return std::binary_search(earlier.begin(), earlier.end(), item);
                       });
}

} // namespace

void GodObjectRenderer::poseAt(const Scene& scene, std::uint32_t slot, Vec3& center,
                               Quat& rotation) const noexcept {
    const DynamicBodySet::Entry* e = mDynamic != nullptr ? mDynamic->find(slot) : nullptr;
    center = e != nullptr ? e->center : scene.object(slot).center;
    rotation = e != nullptr ? e->rotation : scene.object(slot).rotation;
}

WorldFace GodObjectRenderer::faceAt(const Scene& scene, std::uint32_t item) const noexcept {
    if (mDynamic == nullptr || mDynamic->count == 0) {
        return scene.triangleFace(item);
    }
    // Scene::triangleFace with the placed body: the same arithmetic, another pose.
    const TriangleRef ref = scene.triangle(item);
    const RenderBody& b = bodyAt(scene, ref.objectSlot);
    const TriangleFace& f = scene.object(ref.objectSlot).mesh->face(ref.triangle);
    const Vec3 n = b.rotate(f.normal);
    return {n, f.offset + glm::dot(n, b.center)};
}

std::array<Vec3, 3> GodObjectRenderer::cornersAt(const Scene& scene,
                                                 std::uint32_t item) const noexcept {
    if (mDynamic == nullptr || mDynamic->count == 0) {
        return scene.triangleCorners(item);
    }
    const TriangleRef ref = scene.triangle(item);
    const RenderBody& b = bodyAt(scene, ref.objectSlot);
    const auto [p, q, r] = scene.object(ref.objectSlot).mesh->corners(ref.triangle);
    return {b.toWorld(p), b.toWorld(q), b.toWorld(r)};
}

bool GodObjectRenderer::skipItem(const Scene& scene, std::uint32_t item) const noexcept {
    if (mDynamic == nullptr || !mDynamic->active) {
        return false;
    }
    if (isTriangleItem(item)) {
        return validItem(scene, item) && scene.object(scene.triangle(item).objectSlot).body.dynamic;
    }
    return item < scene.size() && scene.object(item).body.dynamic &&
           mDynamic->find(item) == nullptr;
}

/// The scene numbers triangles mesh by mesh in slot order, so a binary search over the numbers
/// finds a mesh's first. O(log triangles x log meshes).
std::uint32_t godobject::firstTriangleItem(const Scene& scene, std::uint32_t slot) noexcept {
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

double GodObjectRenderer::distanceToSkinOf(const Scene& scene, std::uint32_t item,
                                           std::uint32_t near, const Vec3& p) const noexcept {
    if (near == kNotCached) {
        if (!isTriangleItem(item)) {
            return distanceToSkin(bodyAt(scene, item), p);
        }
        const WorldFace tp = faceAt(scene, item);
        return triangleSkinDistance(
            tp.normal, tp.offset, [&] { return fetchTriangle(cornersAt(scene, item), tp.normal); },
            p, kSkinM);
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

void GodObjectRenderer::ensureNear(const Scene& scene, const CandidateSet& candidates,
                                   const Vec3& goal, double need, std::uint32_t& tested) noexcept {
    const double covers =
        mNearTriangles
            ? mNearRadius
            : (1.0 + kFrictionCover) * (mNearRadius - kTriangleNearMarginM) + kNearMarginM;
    if (mNearRadius < 0.0 || glm::length(goal - mNearCenter) + need > covers) {
        buildNear(scene, candidates, goal, need, tested);
    }
}

void GodObjectRenderer::buildNear(const Scene& scene, const CandidateSet& candidates,
                                  const Vec3& center, double reach,
                                  std::uint32_t& tested) noexcept {
    mNearCenter = center;
    mNearReach = reach;
    mNearRadius = reach + kTriangleNearMarginM;
    mNearCount = 0;
    mNearOverflow = false;
    mNearTriangles = false;
    mNearSpans = 0;
    mNearTriangleItems = 0;
    mSeenCount = 0;
    if (++mSeenBuild == 0) { // a wrap every 2^32 builds: the old numbers must not match
        mSeen.fill(0);
        mSeenBuild = 1;
    }
    addNearSpans(scene, candidates, tested);
}

bool GodObjectRenderer::seenBefore(const CandidateSet& candidates, std::size_t s,
                                   std::uint32_t item) noexcept {
    // Fibonacci hashing into the 2^8 slots, linear probing; the table never fills (at most
    // kSeenFull < kSeenSlots entries a build), so every probe ends at an empty slot.
    static_assert(kSeenSlots == 256 && kSeenFull < kSeenSlots);
    const std::uint64_t key = (std::uint64_t{mSeenBuild} << 32) | item;
    std::size_t slot = (item * 2654435769u) >> 24;
    for (;; slot = (slot + 1) % kSeenSlots) {
        const std::uint64_t there = mSeen[slot];
        if (there == key) {
            return true;
        }
        if ((there >> 32) != mSeenBuild) {
            break; // an empty slot: not recorded this build
        }
    }
    if (mSeenCount < kSeenFull) {
        mSeen[slot] = key;
        ++mSeenCount;
        return false;
    }
    return listedEarlier(candidates, s, item);
}

bool GodObjectRenderer::extendsNearSpans(const CandidateSet& candidates) const noexcept {
    if (mNearRadius < 0.0 || candidates.count < mNearSpans) {
        return false;
    }
    if (mNearSpans == 0) {
        return true;
    }
    const std::span<const std::uint32_t> last = candidates.spans[mNearSpans - 1];
    return last.data() == mNearLastSpan.data() && last.size() == mNearLastSpan.size();
}

void GodObjectRenderer::addNearSpans(const Scene& scene, const CandidateSet& candidates,
                                     std::uint32_t& tested) noexcept {
    // Triangles get a tight ball (the reach plus 1 µm) so that a fine mesh adds only the few
    // triangles the proxy can touch this tick; boxes and spheres keep a generous one (room for
    // a friction lag up to mu_d = 1, plus 1 mm), as cheap as it is few. Spans are read in
    // order, so a list extended by later spans is the list one build over them all gives.
    const double radius = (1.0 + kFrictionCover) * mNearReach + kNearMarginM;
    const std::uint32_t n = scene.size();
    const std::size_t count = std::min<std::size_t>(candidates.count, CandidateSet::kMaxSpans);
    prefetchBodies(scene, candidates, count);
    for (std::size_t s = mNearSpans; s < count; ++s) {
        tested += static_cast<std::uint32_t>(candidates.spans[s].size());
        for (const std::uint32_t item : candidates.spans[s]) {
            if (mNearOverflow) {
                break;
            }
            if (seenBefore(candidates, s, item) || skipItem(scene, item)) {
                continue;
            }
            if (isTriangleItem(item)) {
                if (validItem(scene, item)) {
                    mNearTriangles = true;
                    considerTriangle(scene, item, mNearTriangleItems++);
                }
            } else if (item < n) {
                considerObject(scene, item, radius);
            }
        }
    }
    mNearSpans = static_cast<std::uint8_t>(count);
    mNearLastSpan = count > 0 ? candidates.spans[count - 1] : std::span<const std::uint32_t>();
}

void GodObjectRenderer::prefetchBodies(const Scene& scene, const CandidateSet& candidates,
                                       std::size_t count) const noexcept {
    // Every object's render copy the list is about to read is asked for at once, so that the
    // misses of a leaf new to the cache overlap instead of coming one after another.
    const std::uint32_t n = scene.size();
    std::uint32_t asked = 0;
    for (std::size_t s = mNearSpans; s < count && asked < kPrefetchBodies; ++s) {
        for (const std::uint32_t item : candidates.spans[s]) {
            if (item < n) {
                const char* at = reinterpret_cast<const char*>(&scene.body(item));
                __builtin_prefetch(at);
                __builtin_prefetch(at + 64);
                __builtin_prefetch(at + sizeof(RenderBody) - 1);
                if (++asked == kPrefetchBodies) {
                    break;
                }
            }
        }
    }
}

void GodObjectRenderer::considerTriangle(const Scene& scene, std::uint32_t item,
                                         std::uint32_t k) noexcept {
    const Vec3& center = mNearCenter;
    const double triangleReach = mNearRadius + kSkinM;
    // The k-th candidate triangle is the same in every list of the tick (the same spans, in the
    // same order): what an earlier list read, it reuses.
    NearTriangle* t = k < kCachedTriangles ? &mTriangleData[k] : nullptr;
    if (t && (k >= mTriangleCount || t->item != item)) {
        // Field by field: the corners and edges are written when first needed.
        t->item = item;
        t->hasCorners = false;
        t->hasEdges = false;
        t->face = faceAt(scene, item);
        mTriangleCount = k + 1;
    }
    // The distance to the plane bounds the distance to the triangle: most candidates end at
    // one dot product.
    const WorldFace f = t ? t->face : faceAt(scene, item);
    if (std::abs(glm::dot(f.normal, center) - f.offset) > triangleReach) {
        return;
    }
    if (t && !t->hasCorners) {
        t->corners = cornersAt(scene, item);
        t->hasCorners = true;
    }
    const std::array<Vec3, 3> v = t ? t->corners : cornersAt(scene, item);
    // A corner well inside the ball (by far more than rounding) makes the triangle near
    // without the closest-point test.
    const double r2 = triangleReach * triangleReach;
    const bool cornerInside = std::min({length2(v[0] - center), length2(v[1] - center),
                                        length2(v[2] - center)}) < r2 * (1.0 - 1e-9);
    if ((!cornerInside && triangleDistance2(center, v) > r2) || !addNear(item)) {
        return;
    }
    if (t && !t->hasEdges) {
        t->edges = triangleEdges(v, f.normal);
        t->mesh = scene.objectSlotOf(item);
        t->hasEdges = true;
    }
    mNearCached[mNearCount - 1] = static_cast<std::uint8_t>(t ? k : kCachedTriangles);
}

void GodObjectRenderer::considerObject(const Scene& scene, std::uint32_t item,
                                       double radius) noexcept {
    const RenderBody& o = bodyAt(scene, item);
    const double reach = radius + o.radius + kSkinM;
    if (length2(o.center - mNearCenter) > reach * reach) {
        return;
    }
    if (o.shape == Shape::Mesh) {
        // A moving mesh (or an index that holds whole meshes): its triangles near the ball,
        // from the mesh's own frame.
        mNearTriangles = true;
        forEachMeshTriangleNear(scene, item, mNearCenter, mNearRadius, [&](std::uint32_t t) {
            if (addNear(t)) {
                mNearCached[mNearCount - 1] = kCachedTriangles;
            }
        });
        return;
    }
    if (addNear(item)) {
        mNearCached[mNearCount - 1] = kCachedTriangles;
    }
}

} // namespace hapto
