#include "SceneQueries.h"

#include "hapto/core/ShapeGeometry.h"

#include <algorithm>
#include <cmath>

namespace hapto::detail {

double signedDistance(const SceneObject& object, const Vec3& p) {
    return object.shape == Shape::Sphere
               ? sphereSignedDistance(object.center, object.halfExtents.x, p)
               : boxSignedDistance(object.obb(), p);
}

SurfacePoint contactPoint(const SceneObject& object, const Vec3& p, double edgeMarginM) {
    if (object.shape == Shape::Sphere) {
        Vec3 d = p - object.center;
        const double len = glm::length(d);
        d = len > 1e-12 ? d / len : Vec3(0.0, 1.0, 0.0);
        return {object.center + object.halfExtents.x * d, d};
    }
    const Obb box = object.obb();
    const Vec3 l = box.toLocal(p);
    // The face whose plane p lies farthest beyond (or, inside, the nearest face).
    const int axis = dominantFaceAxis(l, box.halfExtents);
    Vec3 local(0.0);
    for (int i = 0; i < 3; ++i) {
        if (i == axis) {
            local[i] = l[i] >= 0.0 ? box.halfExtents[i] : -box.halfExtents[i];
        } else {
            const double m = std::min(edgeMarginM, 0.5 * box.halfExtents[i]);
            local[i] = std::clamp(l[i], -box.halfExtents[i] + m, box.halfExtents[i] - m);
        }
    }
    const Vec3 normal = box.axes[axis] * (l[axis] >= 0.0 ? 1.0 : -1.0);
    return {box.center + box.axes * local, normal};
}

std::vector<std::uint32_t> objectsNear(const Scene& scene, const Aabb& region, double padM) {
    const Aabb padded{region.min - Vec3(padM), region.max + Vec3(padM)};
    std::vector<std::uint32_t> out;
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        if (scene.object(i).aabb().overlaps(padded)) {
            out.push_back(i);
        }
    }
    return out;
}

bool segmentClear(const Scene& scene, std::span<const std::uint32_t> slots, const Vec3& a,
                  const Vec3& b, double marginM, std::uint32_t ignore) {
    Aabb seg = Aabb::empty();
    seg.expand(a);
    seg.expand(b);
    seg.min -= Vec3(marginM);
    seg.max += Vec3(marginM);
    const double len = glm::length(b - a);
    const int steps = std::max(1, static_cast<int>(std::ceil(len / (0.5 * marginM))));
    for (const std::uint32_t slot : slots) {
        if (slot == ignore) {
            continue;
        }
        const SceneObject& o = scene.object(slot);
        if (!o.aabb().overlaps(seg)) {
            continue;
        }
        for (int s = 0; s <= steps; ++s) {
            const Vec3 p = a + (b - a) * (static_cast<double>(s) / steps);
            if (signedDistance(o, p) < marginM) {
                return false;
            }
        }
    }
    return true;
}

} // namespace hapto::detail
