#pragma once
// Shapes and checks the narrow-phase tests share: random boxes and hulls, a box's hull, point
// sampling for brute-force depths, and tolerant comparisons.

#include "hapto/core/Random.h"
#include "hapto/core/ShapeGeometry.h"
#include "hapto/dynamics/Contact.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapto::contact_test {

inline Mat3 rotation(double angle, Vec3 axis) {
    return glm::mat3_cast(glm::angleAxis(angle, glm::normalize(axis)));
}

inline bool near(const Vec3& a, const Vec3& b, double tol = 1e-9) {
    return glm::length(a - b) <= tol;
}

inline ContactManifold collideOnce(const ConvexShape& a, const ConvexShape& b, double margin) {
    ContactManifold m;
    m.count = -1; // collide() must reset it
    collide(a, b, margin, m);
    return m;
}

inline bool hasPointAt(const ContactManifold& m, const Vec3& p, double tol) {
    return std::any_of(m.points.begin(), m.points.begin() + m.count,
                       [&](const ContactPoint& c) { return near(c.position, p, tol); });
}

inline double minSeparation(const ContactManifold& m) {
    double s = std::numeric_limits<double>::infinity();
    for (int i = 0; i < m.count; ++i) {
        s = std::min(s, m.points[static_cast<std::size_t>(i)].separation);
    }
    return s;
}

inline Vec3 randomVec(Random& rng, double half) {
    return {rng.uniform(-half, half), rng.uniform(-half, half), rng.uniform(-half, half)};
}

inline Mat3 randomRotation(Random& rng) {
    const Quat q = glm::normalize(Quat(rng.normal(), rng.normal(), rng.normal(), rng.normal()));
    return glm::mat3_cast(q);
}

inline ConvexShape randomBox(Random& rng) {
    const Vec3 half{rng.uniform(0.01, 0.1), rng.uniform(0.01, 0.1), rng.uniform(0.01, 0.1)};
    return ConvexShape::box(randomVec(rng, 0.1), randomRotation(rng), half);
}

/// A point of box `s` (local coordinates in [-1, 1]^3 scaled by its half extents).
inline Vec3 boxPoint(const ConvexShape& s, const Vec3& unit) {
    return s.center + s.axes * (unit * s.halfExtents);
}

/// How deep (m) the deepest of a 9^3 grid of points of box a (its corners among them) lies
/// inside box b; <= 0 when none is inside.
inline double deepestSampleInside(const ConvexShape& a, const Obb& b) {
    double deepest = -std::numeric_limits<double>::infinity();
    constexpr int kN = 9;
    for (int i = 0; i < kN; ++i) {
        for (int j = 0; j < kN; ++j) {
            for (int k = 0; k < kN; ++k) {
                const Vec3 unit = Vec3(i, j, k) * (2.0 / (kN - 1)) - Vec3(1.0);
                deepest = std::max(deepest, -boxSignedDistance(b, boxPoint(a, unit)));
            }
        }
    }
    return deepest;
}

} // namespace hapto::contact_test
