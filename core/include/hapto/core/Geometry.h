#pragma once
/// Geometry shared by every module: vectors, axis-aligned and oriented boxes (SI units, metres).

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <limits>
#include <type_traits>

namespace hapto {

using Vec3 =
    glm::dvec3; ///< A point or vector in metres (or N for forces), world frame unless named.
using Quat =
    glm::dquat; ///< A unit quaternion; GLM stores it (x, y, z, w), constructs it (w, x, y, z).
using Mat3 = glm::dmat3; ///< A 3x3 matrix, column-major (GLM).

// Plain values: they cross threads through Mailbox and SpscRing by memcpy. A default-declared
// `Vec3 v;` is uninitialised (like a double): write `Vec3 v{0.0}`; `Quat()` is all zeros, not
// the identity: write `Quat{1, 0, 0, 0}`.
static_assert(std::is_trivially_copyable_v<Vec3> && std::is_trivially_copyable_v<Quat> &&
              std::is_trivially_copyable_v<Mat3>);

/// An axis-aligned box [min, max] in metres. An empty box has min > max.
struct Aabb {
    Vec3 min{0.0}; ///< Lower corner (m).
    Vec3 max{0.0}; ///< Upper corner (m).

    /// The empty box: expanding it by anything gives that thing. [any thread]
    static Aabb empty() {
        constexpr double inf = std::numeric_limits<double>::infinity();
        return {Vec3(inf), Vec3(-inf)};
    }
    /// True when min > max on some axis. [any thread]
    bool isEmpty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
    /// Centre point (m). [any thread]
    Vec3 center() const { return 0.5 * (min + max); }
    /// Half the size along each axis (m). [any thread]
    Vec3 halfExtents() const { return 0.5 * (max - min); }
    /// Full size along each axis (m). [any thread]
    Vec3 size() const { return max - min; }
    /// True when p lies inside or on the boundary. [any thread]
    bool contains(const Vec3& p) const {
        return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z &&
               p.z <= max.z;
    }
    /// True when the two closed boxes share at least one point. [any thread]
    bool overlaps(const Aabb& o) const {
        return min.x <= o.max.x && max.x >= o.min.x && min.y <= o.max.y && max.y >= o.min.y &&
               min.z <= o.max.z && max.z >= o.min.z;
    }
    /// Grows the box to hold p. [any thread]
    void expand(const Vec3& p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    /// Grows the box to hold o. [any thread]
    void expand(const Aabb& o) {
        min = glm::min(min, o.min);
        max = glm::max(max, o.max);
    }
};

/// An oriented box: a centre, half extents along its own axes, and those axes (m).
struct Obb {
    Vec3 center{0.0};      ///< Centre in world coordinates (m).
    Vec3 halfExtents{0.0}; ///< Half size along each of its own axes (m), all >= 0.
    Mat3 axes{1.0};        ///< Column i is the box's i-th unit axis in world coordinates.

    /// The tightest world AABB around this box. [any thread]
    Aabb aabb() const {
        Vec3 r(0.0);
        for (int i = 0; i < 3; ++i) {
            r += glm::abs(axes[i]) * halfExtents[i];
        }
        return {center - r, center + r};
    }
    /// p expressed in the box's own frame (m). [any thread]
    Vec3 toLocal(const Vec3& p) const { return glm::transpose(axes) * (p - center); }
    /// True when p lies inside or on the box. [any thread]
    bool contains(const Vec3& p) const {
        const Vec3 l = glm::abs(toLocal(p));
        return l.x <= halfExtents.x && l.y <= halfExtents.y && l.z <= halfExtents.z;
    }
};

} // namespace hapto
