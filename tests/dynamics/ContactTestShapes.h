#pragma once
// Shapes and checks the narrow-phase tests share: random boxes and hulls, a box's hull, point
// sampling for brute-force depths, and tolerant comparisons.

#include "hapto/core/Random.h"
#include "hapto/core/ShapeGeometry.h"
#include "hapto/dynamics/Contact.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

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

namespace hapto::contact_test {

/// The convex hull of `points` (every one a corner of it), by brute force: a face for each
/// plane through three points with all points on its inner side (coplanar triples merged), an
/// edge for each pair of points two faces share. O(n^4): for the tests' small solids only.
inline ConvexHull hullOfPoints(const std::vector<Vec3>& points) {
    ConvexHull h;
    h.vertices = points;
    const std::size_t n = points.size();
    double size = 0.0;
    for (const Vec3& p : points) {
        size = std::max(size, glm::length(p));
    }
    const double eps = 1e-9 * size;
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = i + 1; j < n; ++j) {
            for (std::size_t k = j + 1; k < n; ++k) {
                Vec3 nrm = glm::cross(points[j] - points[i], points[k] - points[i]);
                if (glm::length(nrm) <= eps * size) {
                    continue;
                }
                nrm = glm::normalize(nrm);
                double d = glm::dot(nrm, points[i]);
                bool above = false;
                bool below = false;
                for (const Vec3& p : points) {
                    above = above || glm::dot(nrm, p) > d + eps;
                    below = below || glm::dot(nrm, p) < d - eps;
                }
                if (above && below) {
                    continue;
                }
                if (above) {
                    nrm = -nrm;
                    d = -d;
                }
                const bool known = std::any_of(h.faces.begin(), h.faces.end(), [&](const auto& f) {
                    return glm::length(f.normal - nrm) < 1e-9;
                });
                if (!known) {
                    h.faces.push_back({nrm, d});
                }
            }
        }
    }
    for (std::uint32_t i = 0; i < n; ++i) {
        for (std::uint32_t j = i + 1; j < n; ++j) {
            int shared = 0;
            for (const auto& f : h.faces) {
                const bool on = std::abs(glm::dot(f.normal, points[i]) - f.offset) <= eps &&
                                std::abs(glm::dot(f.normal, points[j]) - f.offset) <= eps;
                shared += on ? 1 : 0;
            }
            if (shared >= 2) {
                h.edges.push_back({i, j});
            }
        }
    }
    h.deriveTopology();
    return h;
}

/// A box's hull (half extents h, centred on its own origin).
inline ConvexHull boxHull(const Vec3& h) {
    std::vector<Vec3> corners;
    for (int i = 0; i < 8; ++i) {
        corners.push_back(Vec3(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z));
    }
    return hullOfPoints(corners);
}

/// A regular octahedron of circumradius r.
inline ConvexHull octahedron(double r) {
    return hullOfPoints({{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}});
}

/// How deep (m) point p lies inside hull shape s: the least distance to a face plane (< 0
/// outside).
inline double hullDepth(const ConvexShape& s, const Vec3& p) {
    const Vec3 local = glm::transpose(s.axes) * (p - s.center);
    double depth = std::numeric_limits<double>::infinity();
    for (const auto& f : s.hull->faces) {
        depth = std::min(depth, f.offset - glm::dot(f.normal, local));
    }
    return depth;
}

} // namespace hapto::contact_test
