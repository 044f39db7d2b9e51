#include "SceneQueries.h"

#include "hapto/core/ShapeGeometry.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace hapto::detail {

namespace {

/// The distance along the ray o + s d (s >= 0) to the nearest of the mesh's triangles, placed
/// by the object's pose (Moeller-Trumbore, both sides); none when the ray misses. O(triangles).
std::optional<double> rayToMesh(const SceneObject& object, const Vec3& o, const Vec3& d) {
    const TriangleMesh& mesh = *object.mesh;
    const Mat3 r = glm::mat3_cast(object.rotation);
    std::optional<double> best;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const auto [la, lb, lc] = mesh.corners(t);
        const Vec3 a = object.center + r * la;
        const Vec3 e1 = r * (lb - la), e2 = r * (lc - la);
        const Vec3 q = glm::cross(d, e2);
        const double det = glm::dot(e1, q);
        if (std::abs(det) < 1e-300) {
            continue;
        }
        const Vec3 w = o - a;
        const double u = glm::dot(w, q) / det;
        const Vec3 wc = glm::cross(w, e1);
        const double v = glm::dot(d, wc) / det;
        const double s = glm::dot(e2, wc) / det;
        if (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && s >= 0.0 && (!best || s < *best)) {
            best = s;
        }
    }
    return best;
}

} // namespace

double signedDistance(const SceneObject& object, const Vec3& p) {
    // A mesh plans by its oriented bounding box: never nearer than the mesh itself, so a path
    // kept clear of the box is clear of the mesh.
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
    const Vec3 onBox = box.center + box.axes * local;
    if (object.shape == Shape::Mesh) {
        // The mesh's own surface below that face point, pressed along the face normal; the
        // face point itself when the mesh leaves a hole there.
        if (const auto s = rayToMesh(object, onBox, -normal)) {
            return {onBox - *s * normal, normal};
        }
    }
    return {onBox, normal};
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
