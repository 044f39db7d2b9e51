// The narrow phase's front door: the shape constructors, collide()'s dispatch by pair, and the
// bookkeeping every pair shares (the point sink that keeps the kMax points spanning a large
// manifold, segment closest points).
//
// Dispatch: a sphere anywhere goes to ContactSphere.cpp (spheres are not polytopes); every
// other pair is two polytopes (ContactSat.cpp). A pair given with the body second (a triangle
// or a sphere as `a` against a box or hull) is computed the other way round and its normals
// turned, so collide(a, b) and collide(b, a) give opposite normals.
//
// Reduction (more than kMax points, e.g. two large hull faces): the deepest point first, then
// repeatedly the point farthest from every point already kept (ties: the earlier), so the
// kept points span the contact patch; deterministic.

#include "ContactInternal.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapto {

ConvexShape ConvexShape::box(const Vec3& center, const Mat3& axes,
                             const Vec3& halfExtents) noexcept {
    ConvexShape s;
    s.kind = Kind::Box;
    s.center = center;
    s.axes = axes;
    s.halfExtents = halfExtents;
    return s;
}

ConvexShape ConvexShape::sphere(const Vec3& center, double radius) noexcept {
    ConvexShape s;
    s.kind = Kind::Sphere;
    s.center = center;
    s.radius = radius;
    return s;
}

ConvexShape ConvexShape::hullAt(const ConvexHull& hull, const Vec3& origin,
                                const Mat3& axes) noexcept {
    ConvexShape s;
    s.kind = Kind::Hull;
    s.center = origin;
    s.axes = axes;
    s.hull = &hull;
    return s;
}

ConvexShape ConvexShape::triangleOf(const TriangleCorners& corners,
                                    const Vec3& outwardNormal) noexcept {
    ConvexShape s;
    s.kind = Kind::Triangle;
    s.triangle = corners;
    s.triangleNormal = outwardNormal;
    s.center = (corners[0] + corners[1] + corners[2]) / 3.0;
    return s;
}

Aabb ConvexShape::aabb() const noexcept {
    switch (kind) {
    case Kind::Box:
        return Obb{center, halfExtents, axes}.aabb();
    case Kind::Sphere:
        return {center - Vec3(radius), center + Vec3(radius)};
    case Kind::Triangle:
        return triangleAabb(triangle);
    case Kind::Hull:
        break;
    }
    Aabb box = Aabb::empty();
    if (hull != nullptr) {
        for (const Vec3& v : hull->vertices) {
            box.expand(center + axes * v);
        }
    }
    return box;
}

namespace {

bool isBody(const ConvexShape& s) noexcept {
    return s.kind != ConvexShape::Kind::Triangle;
}

bool usable(const ConvexShape& s) noexcept {
    return s.kind != ConvexShape::Kind::Hull || (s.hull != nullptr && !s.hull->vertices.empty());
}

void flipNormals(ContactManifold& m) noexcept {
    for (int i = 0; i < m.count; ++i) {
        m.points[static_cast<std::size_t>(i)].normal =
            -m.points[static_cast<std::size_t>(i)].normal;
    }
}

void collideOrdered(const ConvexShape& a, const ConvexShape& b, double marginM,
                    ContactManifold& out) noexcept {
    contact::PointSink sink;
    sink.margin = marginM;
    if (a.kind == ConvexShape::Kind::Sphere) {
        contact::collideSphere(a.center, a.radius, b, sink);
    } else {
        const contact::Polytope pa(a);
        const contact::Polytope pb(b);
        if (!pb.degenerate()) {
            contact::collidePolytopes(pa, pb, sink);
        }
    }
    sink.write(out);
}

} // namespace

void collide(const ConvexShape& a, const ConvexShape& b, double marginM,
             ContactManifold& out) noexcept {
    out.count = 0;
    if (!usable(a) || !usable(b) || !(marginM >= 0.0) || (!isBody(a) && !isBody(b))) {
        return;
    }
    // The body (or the sphere) goes first; the answer is turned back to the order asked.
    const bool swap =
        !isBody(a) || (b.kind == ConvexShape::Kind::Sphere && a.kind != ConvexShape::Kind::Sphere);
    if (swap) {
        collideOrdered(b, a, marginM, out);
        flipNormals(out);
    } else {
        collideOrdered(a, b, marginM, out);
    }
}

namespace contact {

void PointSink::add(const Vec3& position, const Vec3& normal, double separation,
                    std::uint32_t feature) noexcept {
    if (!(separation <= margin) || mCount >= kCapacity) {
        return;
    }
    mPoints[static_cast<std::size_t>(mCount++)] = {position, normal, separation, feature};
}

namespace {

// Index of the deepest point (the first on ties).
int deepest(const std::array<ContactPoint, PointSink::kCapacity>& p, int count) noexcept {
    int best = 0;
    for (int i = 1; i < count; ++i) {
        if (p[static_cast<std::size_t>(i)].separation <
            p[static_cast<std::size_t>(best)].separation) {
            best = i;
        }
    }
    return best;
}

} // namespace

void PointSink::write(ContactManifold& out) const noexcept {
    constexpr int kMax = ContactManifold::kMax;
    if (mCount <= kMax) {
        std::copy_n(mPoints.begin(), mCount, out.points.begin());
        out.count = mCount;
        return;
    }
    // Farthest-point selection: nearest[i] = squared distance from i to the kept set.
    std::array<double, kCapacity> nearest{};
    nearest.fill(std::numeric_limits<double>::infinity());
    int pick = deepest(mPoints, mCount);
    for (int k = 0; k < kMax; ++k) {
        const ContactPoint& chosen = mPoints[static_cast<std::size_t>(pick)];
        out.points[static_cast<std::size_t>(k)] = chosen;
        int next = -1;
        for (int i = 0; i < mCount; ++i) {
            const Vec3 d = mPoints[static_cast<std::size_t>(i)].position - chosen.position;
            double& n = nearest[static_cast<std::size_t>(i)];
            n = std::min(n, glm::dot(d, d));
            if (n > 0.0 && (next < 0 || n > nearest[static_cast<std::size_t>(next)])) {
                next = i;
            }
        }
        nearest[static_cast<std::size_t>(pick)] = -1.0; // kept: never picked again
        if (next < 0) {
            out.count = k + 1;
            return;
        }
        pick = next;
    }
    out.count = kMax;
}

void closestSegmentPoints(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3& c1,
                          Vec3& c2) noexcept {
    const Vec3 d1 = q1 - p1;
    const Vec3 d2 = q2 - p2;
    const Vec3 r = p1 - p2;
    const double a = glm::dot(d1, d1);
    const double e = glm::dot(d2, d2);
    const double f = glm::dot(d2, r);
    constexpr double kTiny = 1e-300;
    double s = 0.0;
    double t = 0.0;
    if (a <= kTiny && e <= kTiny) {
        c1 = p1;
        c2 = p2;
        return;
    }
    if (a <= kTiny) {
        t = std::clamp(f / e, 0.0, 1.0);
    } else {
        const double c = glm::dot(d1, r);
        if (e <= kTiny) {
            s = std::clamp(-c / a, 0.0, 1.0);
        } else {
            const double b = glm::dot(d1, d2);
            const double denom = a * e - b * b;
            s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = std::clamp(-c / a, 0.0, 1.0);
            } else if (t > 1.0) {
                t = 1.0;
                s = std::clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    c1 = p1 + d1 * s;
    c2 = p2 + d2 * t;
}

} // namespace contact

} // namespace hapto
