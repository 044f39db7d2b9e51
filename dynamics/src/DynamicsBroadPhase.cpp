// The broad phase: which static items and which other bodies each awake body may touch this
// step.
//
// Design note. A body's box is its shape's tightest AABB grown by the speculative margin plus
// the distance it can travel in one step, (|v| + |w| r) dt for r its bounding radius, so any
// surface it could reach before the next step is a candidate (speculative contacts need it).
// Static candidates come from the shared index's box query (SpatialIndex::visitLeaves, plus
// outsideObjects() where the box leaves the index's bounds): items of dynamic objects are
// skipped, an item met in several leaves is taken once (a stamp per item, sized by the
// constructor), and each body's candidates are sorted by item, so the contacts and their order
// do not depend on the index's kind or leaf order. The query is cached per body (a cursor of
// sorts, BodyWork::QueryCache): the index is asked for the swept box grown by kCacheSlackM, its
// static items kept sorted, and while later swept boxes stay inside that box each step only
// filters those items by their boxes. Every item a query of the swept box itself would give
// is in a leaf meeting the larger box, so the candidates are the same items in the same order
// (a resting body's step no longer walks the index, whose depth grows with the scene). A box
// whose items do not fit the cache is asked directly each step while the body stays inside
// it. Body pairs are tested in findContacts
// (every pair's swept boxes: O(bodies^2), fine for the tens of bodies here). Invariants: no
// allocation (the candidate list has a fixed capacity; the excess is counted, never stored);
// a sleeping body gathers nothing.

#include "DynamicsImpl.h"

#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cstddef>

namespace hapto::dyn {

ConvexShape placeShape(const BodyWork& w, const BodyState& b) noexcept {
    const Mat3 r = glm::mat3_cast(b.orientation);
    const Vec3 origin = b.position - r * w.comLocal; // the object's own centre
    ConvexShape s = w.shapeTemplate;
    s.center = origin;
    s.axes = r;
    return s;
}

ConvexShape staticShape(const Scene& scene, std::uint32_t item) noexcept {
    if (isTriangleItem(item)) {
        const TriangleRef ref = scene.triangle(item);
        const bool closed = scene.object(ref.objectSlot).mesh->closed();
        const auto c = scene.triangleCorners(item);
        const Vec3 normal = closed ? scene.triangleFace(item).normal : Vec3(0.0);
        return ConvexShape::triangleOf({c[0], c[1], c[2]}, normal);
    }
    const SceneObject& o = scene.object(item);
    if (o.shape == Shape::Sphere) {
        return ConvexShape::sphere(o.center, o.halfExtents.x);
    }
    return ConvexShape::box(o.center, glm::mat3_cast(o.rotation), o.halfExtents);
}

static bool overlaps(const Aabb& a, const Aabb& b) noexcept {
    return a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y &&
           a.min.z <= b.max.z && b.min.z <= a.max.z;
}

// The item's world AABB (m).
static Aabb itemBox(const Scene& scene, std::uint32_t item) noexcept {
    if (isTriangleItem(item)) {
        const auto c = scene.triangleCorners(item);
        return triangleAabb({c[0], c[1], c[2]});
    }
    return scene.object(item).aabb();
}

// The body's swept box: its AABB grown by the margin and one step's travel.
static Aabb sweptBox(const BodyWork& w, const BodyState& b, double marginM, double dtS) noexcept {
    const ConvexShape s = placeShape(w, b);
    if (s.kind == ConvexShape::Kind::Hull && s.hull == nullptr) {
        return Aabb::empty();
    }
    Aabb box = s.aabb();
    const double r = glm::length(box.halfExtents());
    const double grow =
        moves(b) ? marginM + (glm::length(b.velocity) + glm::length(b.angularVelocity) * r) * dtS
                 : marginM;
    box.min -= Vec3(grow);
    box.max += Vec3(grow);
    return box;
}

namespace {

// Adds `item` as a candidate of `body` if it is static, new for this body and its box
// overlaps the body's swept box.
void consider(const Scene& scene, Dynamics::Impl& impl, std::uint32_t body,
              std::uint32_t item) noexcept {
    const std::uint32_t dense =
        isTriangleItem(item) ? scene.size() + (item & ~kTriangleItemBit) : item;
    if (impl.seenStamp[dense] == impl.stamp) {
        return; // already seen through another leaf
    }
    impl.seenStamp[dense] = impl.stamp;
    if (scene.object(scene.objectSlotOf(item)).body.dynamic ||
        !overlaps(impl.work[body].sweptBox, itemBox(scene, item))) {
        return;
    }
    if (impl.candidates.size() == impl.candidates.capacity()) {
        ++impl.droppedCandidates;
        return;
    }
    impl.candidates.push_back({body, item});
}

// Body i's static candidates through the index's box query, in ascending item order.
void gatherDirect(const Scene& scene, Dynamics::Impl& impl, std::uint32_t i) noexcept {
    ++impl.stamp;
    const std::size_t begin = impl.candidates.size();
    const Aabb& box = impl.work[i].sweptBox;
    auto visit = [&](std::uint32_t leaf) {
        for (const std::uint32_t item : impl.index->leafObjects(leaf)) {
            consider(scene, impl, i, item);
        }
        return true;
    };
    impl.index->visitLeavesWith(box, visit);
    if (impl.index->reachesOutside(box)) {
        for (const std::uint32_t item : impl.index->outsideObjects()) {
            consider(scene, impl, i, item);
        }
    }
    // Ascending items: the same contacts in the same order whatever the index's leaf order.
    std::sort(impl.candidates.begin() + static_cast<std::ptrdiff_t>(begin), impl.candidates.end(),
              [](const Candidate& a, const Candidate& b) { return a.item < b.item; });
}

/// How far the cached query's box reaches beyond the swept box it was made for (m): a body
/// may move this far before its cache is made again.
constexpr double kCacheSlackM = 0.005;

bool contains(const Aabb& outer, const Aabb& inner) noexcept {
    return outer.min.x <= inner.min.x && outer.min.y <= inner.min.y && outer.min.z <= inner.min.z &&
           inner.max.x <= outer.max.x && inner.max.y <= outer.max.y && inner.max.z <= outer.max.z;
}

// Makes body i's cache for its swept box grown by kCacheSlackM.
void refillCache(const Scene& scene, Dynamics::Impl& impl, std::uint32_t i) noexcept {
    BodyWork::QueryCache& c = impl.work[i].cache;
    c.box = impl.work[i].sweptBox;
    c.box.min -= Vec3(kCacheSlackM);
    c.box.max += Vec3(kCacheSlackM);
    c.count = 0;
    c.overflow = false;
    ++impl.stamp;
    const auto add = [&](std::uint32_t item) {
        const std::uint32_t dense =
            isTriangleItem(item) ? scene.size() + (item & ~kTriangleItemBit) : item;
        if (impl.seenStamp[dense] == impl.stamp ||
            scene.object(scene.objectSlotOf(item)).body.dynamic) {
            return;
        }
        impl.seenStamp[dense] = impl.stamp;
        if (c.count == c.items.size()) {
            c.overflow = true;
            return;
        }
        c.items[c.count++] = item;
    };
    auto visit = [&](std::uint32_t leaf) {
        for (const std::uint32_t item : impl.index->leafObjects(leaf)) {
            add(item);
        }
        return !c.overflow;
    };
    impl.index->visitLeavesWith(c.box, visit);
    if (!c.overflow && impl.index->reachesOutside(c.box)) {
        for (const std::uint32_t item : impl.index->outsideObjects()) {
            add(item);
        }
    }
    c.valid = !c.overflow;
    std::sort(c.items.begin(), c.items.begin() + c.count);
}

// Body i's static candidates, from its cached query when its swept box is inside the cache's
// box (made again when not), else asked directly; ascending items either way.
void gatherBody(const Scene& scene, Dynamics::Impl& impl, std::uint32_t i) noexcept {
    BodyWork& w = impl.work[i];
    if (!contains(w.cache.box, w.sweptBox)) {
        refillCache(scene, impl, i);
    }
    if (!w.cache.valid) {
        gatherDirect(scene, impl, i); // too many items near it to cache
        return;
    }
    for (std::uint32_t k = 0; k < w.cache.count; ++k) {
        const std::uint32_t item = w.cache.items[k];
        if (!overlaps(w.sweptBox, itemBox(scene, item))) {
            continue;
        }
        if (impl.candidates.size() == impl.candidates.capacity()) {
            ++impl.droppedCandidates;
            continue;
        }
        impl.candidates.push_back({i, item});
    }
}

} // namespace

void gatherCandidates(const Scene& scene, std::span<const BodyState> bodies, Dynamics::Impl& impl,
                      const DynamicsOptions& options, double dtS) noexcept {
    impl.candidates.clear();
    for (std::uint32_t i = 0; i < bodies.size(); ++i) {
        impl.work[i].sweptBox = sweptBox(impl.work[i], bodies[i], options.speculativeMarginM, dtS);
        if (moves(bodies[i]) && !impl.work[i].sweptBox.isEmpty()) {
            gatherBody(scene, impl, i);
        }
    }
}

bool sweptBoxesOverlap(const BodyWork& a, const BodyWork& b) noexcept {
    return !a.sweptBox.isEmpty() && !b.sweptBox.isEmpty() && overlaps(a.sweptBox, b.sweptBox);
}

} // namespace hapto::dyn
