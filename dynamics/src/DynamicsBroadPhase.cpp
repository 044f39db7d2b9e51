// The broad phase: which static items and which other bodies each awake body may touch this
// step.
//
// Design note. A body's box is its shape's tightest AABB grown by the speculative margin plus
// the distance it can travel in one step, (|v| + |w| r) dt for r its bounding radius, so any
// surface it could reach before the next step is a candidate (speculative contacts need it).
// Static candidates are items of the scene whose object is not dynamic; items of dynamic
// objects are skipped. TEMPORARY: until the index has a box query (SpatialIndex::visitLeaves,
// helper C), the candidates come from a loop over the scene's items, O(items) a body; the
// switch keeps the same order (ascending item) so results stay deterministic. Body pairs are
// tested in findContacts. Invariants: no allocation (the candidate list has a fixed capacity;
// the excess is counted, never stored); a sleeping body gathers nothing.

#include "DynamicsImpl.h"

#include <glm/gtc/quaternion.hpp>

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

void gatherCandidates(const Scene& scene, std::span<const BodyState> bodies, Dynamics::Impl& impl,
                      const DynamicsOptions& options, double dtS) noexcept {
    impl.candidates.clear();
    const std::size_t capacity = impl.candidates.capacity();
    for (std::uint32_t i = 0; i < bodies.size(); ++i) {
        impl.work[i].sweptBox = sweptBox(impl.work[i], bodies[i], options.speculativeMarginM, dtS);
        if (!moves(bodies[i]) || impl.work[i].sweptBox.isEmpty()) {
            continue;
        }
        // TEMPORARY loop over the scene's items until the index's box query lands.
        for (std::uint32_t k = 0; k < scene.itemCount(); ++k) {
            const std::uint32_t item = scene.item(k);
            if (!scene.isIndexed(item) || scene.object(scene.objectSlotOf(item)).body.dynamic ||
                !overlaps(impl.work[i].sweptBox, itemBox(scene, item))) {
                continue;
            }
            if (impl.candidates.size() == capacity) {
                ++impl.droppedCandidates;
                continue;
            }
            impl.candidates.push_back({i, item});
        }
    }
}

bool sweptBoxesOverlap(const BodyWork& a, const BodyWork& b) noexcept {
    return !a.sweptBox.isEmpty() && !b.sweptBox.isEmpty() && overlaps(a.sweptBox, b.sweptBox);
}

} // namespace hapto::dyn
