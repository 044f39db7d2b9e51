// Every pair with a sphere: sphere-sphere, sphere-box, sphere-triangle, sphere-hull. One point
// each, exact: the sphere's centre against the other shape's closest point (outside) or its
// nearest face (centre inside a box or hull), so separation = distance - radius.
//
// Conventions (Contact.h): the normal points from the other shape towards the sphere, the
// point lies midway between the sphere's surface point and the other shape's, and the
// feature names the other shape's region: a box's 27 regions (face, edge, corner, inside)
// by the sign of the clamped local coordinates, a hull's face, a triangle's face/edge/corner.
//
// A one-sided triangle (triangleNormal set) pushes only out of its front: a centre behind the
// plane gets the plane's normal when it lies over the face and the sphere reaches the front,
// and nothing otherwise (never a normal pointing through the wall).

#include "ContactInternal.h"

#include "hapto/core/ClosestPoint.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapto::contact {

namespace {

// Any unit vector when a direction is undefined (coincident centres): +y, as ContactPoint's
// default normal.
constexpr Vec3 kFallbackNormal{0.0, 1.0, 0.0};

// The point for a sphere whose centre is `center` and a surface point `onOther` of the other
// shape, with the normal n (unit, other -> sphere) and separation `gap`.
void addSpherePoint(const Vec3& center, double radius, const Vec3& n, double gap,
                    std::uint32_t feature, PointSink& sink) noexcept {
    const Vec3 onSphere = center - n * radius;
    const Vec3 onOther = onSphere - n * gap;
    sink.add(0.5 * (onSphere + onOther), n, gap, feature);
}

void sphereSphere(const Vec3& c, double r, const ConvexShape& b, PointSink& sink) noexcept {
    const Vec3 d = c - b.center;
    const double len = glm::length(d);
    const Vec3 n = len > 0.0 ? d / len : kFallbackNormal;
    addSpherePoint(c, r, n, len - r - b.radius, 0, sink);
}

// Region code of a box-local point clamped to the box: 3 digits in base 3 (-, 0, +) + 1.
std::uint32_t boxRegion(const Vec3& local, const Vec3& h) noexcept {
    std::uint32_t code = 0;
    for (int i = 2; i >= 0; --i) {
        const std::uint32_t digit = local[i] > h[i] ? 2u : (local[i] < -h[i] ? 0u : 1u);
        code = code * 3 + digit;
    }
    return code + 1;
}

void sphereBox(const Vec3& c, double r, const ConvexShape& b, PointSink& sink) noexcept {
    const Vec3 local = glm::transpose(b.axes) * (c - b.center);
    const Vec3& h = b.halfExtents;
    const Vec3 clamped = glm::clamp(local, -h, h);
    const Vec3 away = local - clamped;
    const double dist = glm::length(away);
    if (dist > 0.0) {
        addSpherePoint(c, r, b.axes * (away / dist), dist - r, boxRegion(local, h), sink);
        return;
    }
    // Centre inside (or on) the box: out through the nearest face.
    const int axis = dominantFaceAxis(local, h);
    const double sign = local[axis] >= 0.0 ? 1.0 : -1.0;
    const double depth = h[axis] - std::abs(local[axis]);
    addSpherePoint(c, r, b.axes[axis] * sign, -depth - r, 28u + 2u * axis + (sign > 0 ? 1u : 0u),
                   sink);
}

// Feature of the triangle region holding closest point q: 1 face, 2-4 edges, 5-7 corners.
std::uint32_t triangleRegion(const Vec3& q, const TriangleCorners& t) noexcept {
    const double scale = glm::length(t[1] - t[0]) + glm::length(t[2] - t[0]);
    const double tol = 1e-12 * std::max(scale, 1e-300);
    for (int i = 0; i < 3; ++i) {
        if (glm::length(q - t[i]) <= tol) {
            return 5u + i;
        }
    }
    for (int i = 0; i < 3; ++i) {
        const Vec3& p0 = t[i];
        const Vec3& p1 = t[(i + 1) % 3];
        const Vec3 e = p1 - p0;
        const Vec3 off = glm::cross(e, q - p0);
        if (glm::length(off) <= tol * glm::length(e)) {
            return 2u + i;
        }
    }
    return 1u;
}

void sphereTriangle(const Vec3& c, double r, const ConvexShape& b, PointSink& sink) noexcept {
    const TriangleCorners& t = b.triangle;
    const Vec3 q = closestPointOnTriangle(c, t);
    const Vec3 away = c - q;
    const double dist = glm::length(away);
    const std::uint32_t feature = triangleRegion(q, t);
    const Vec3 face = glm::cross(t[1] - t[0], t[2] - t[0]);
    const Vec3& front = b.triangleNormal;
    if (dist - r > sink.margin) {
        return; // farther than the margin from every point of the triangle
    }
    if (front != Vec3(0.0)) {
        const double height = glm::dot(c - t[0], front);
        if (height < 0.0) {
            // Centre behind: pushed out of the front when over the face; beside it, the
            // neighbouring face of the closed mesh owns the contact.
            if (feature == 1u && height + r >= 0.0) {
                addSpherePoint(c, r, front, height - r, feature, sink);
            }
            return;
        }
        addSpherePoint(c, r, dist > 0.0 ? away / dist : front, dist - r, feature, sink);
        return;
    }
    if (dist > 0.0) {
        addSpherePoint(c, r, away / dist, dist - r, feature, sink);
    } else if (glm::length(face) > 0.0) {
        addSpherePoint(c, r, glm::normalize(face), -r, feature, sink);
    } else {
        addSpherePoint(c, r, kFallbackNormal, -r, feature, sink);
    }
}

// Closest point of hull face `f` (own frame) to p: the nearest of the fan triangles of its
// corners (the corners in the face's plane, in angular order).
double closestOnHullFace(const Polytope& hull, int f, const Vec3& p, Vec3& best) noexcept {
    Polygon poly;
    hull.facePolygon(f, poly);
    double bestD2 = std::numeric_limits<double>::infinity();
    for (int i = 1; i + 1 < poly.count; ++i) {
        const TriangleCorners tri{poly.points[0], poly.points[static_cast<std::size_t>(i)],
                                  poly.points[static_cast<std::size_t>(i + 1)]};
        const Vec3 q = closestPointOnTriangle(p, tri);
        const double d2 = glm::dot(p - q, p - q);
        if (d2 < bestD2) {
            bestD2 = d2;
            best = q;
        }
    }
    if (poly.count == 1 || poly.count == 2) {
        Vec3 unused{0.0};
        closestSegmentPoints(poly.points[0], poly.points[static_cast<std::size_t>(poly.count - 1)],
                             p, p, best, unused);
        bestD2 = glm::dot(p - best, p - best);
    }
    return bestD2;
}

void sphereHull(const Vec3& c, double r, const ConvexShape& b, PointSink& sink) noexcept {
    const Polytope hull(b);
    int deepestFace = -1;
    double highest = -std::numeric_limits<double>::infinity();
    for (int f = 0; f < hull.faceCount(); ++f) {
        const double h = glm::dot(hull.faceNormal(f), c) - hull.faceOffset(f);
        if (h > highest) {
            highest = h;
            deepestFace = f;
        }
    }
    if (deepestFace < 0) {
        return;
    }
    if (highest <= 0.0) { // centre inside: out through the nearest face plane
        addSpherePoint(c, r, hull.faceNormal(deepestFace), highest - r,
                       static_cast<std::uint32_t>(deepestFace) + 1u, sink);
        return;
    }
    // Outside: the closest surface point lies on a face the centre is in front of.
    double bestD2 = std::numeric_limits<double>::infinity();
    Vec3 best{0.0};
    int bestFace = 0;
    for (int f = 0; f < hull.faceCount(); ++f) {
        if (glm::dot(hull.faceNormal(f), c) - hull.faceOffset(f) <= 0.0) {
            continue;
        }
        Vec3 q{0.0};
        const double d2 = closestOnHullFace(hull, f, c, q);
        if (d2 < bestD2) {
            bestD2 = d2;
            best = q;
            bestFace = f;
        }
    }
    const double dist = std::sqrt(bestD2);
    const Vec3 n = dist > 0.0 ? (c - best) / dist : hull.faceNormal(bestFace);
    addSpherePoint(c, r, n, dist - r, static_cast<std::uint32_t>(bestFace) + 1u, sink);
}

} // namespace

void collideSphere(const Vec3& center, double radius, const ConvexShape& b,
                   PointSink& sink) noexcept {
    switch (b.kind) {
    case ConvexShape::Kind::Sphere:
        sphereSphere(center, radius, b, sink);
        break;
    case ConvexShape::Kind::Box:
        sphereBox(center, radius, b, sink);
        break;
    case ConvexShape::Kind::Triangle:
        sphereTriangle(center, radius, b, sink);
        break;
    case ConvexShape::Kind::Hull:
        sphereHull(center, radius, b, sink);
        break;
    }
}

} // namespace hapto::contact
