// Mass properties. Design note: every solid is described at unit density (volume, centroid,
// inertia about the centroid), and a body's mass scales it; so a mass given in the file and a
// density give the same centre and the same shape of tensor. The surface integrals are Eberly's
// "Polyhedral Mass Properties (Revisited)" (Geometric Tools, 2002; after Mirtich, J. Graphics
// Tools 1(2), 1996): for each triangle, the divergence theorem turns the volume integrals of 1,
// x, y, z, x^2, y^2, z^2, xy, yz, zx into polynomials of its corners. The corners are taken
// relative to the surface's bounds centre first, so a mesh far from its origin loses no digits
// to cancellation. Invariant: the tensors made here are exactly symmetric (each off-diagonal
// product is computed once and stored twice).

#include "hapto/scenes/MassProperties.h"

#include "hapto/io/JsonInput.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace hapto {
namespace {

/// Eberly's subexpressions of one coordinate over a triangle's three corners.
struct Sub {
    double f1, f2, f3, g0, g1, g2;
};

Sub subexpressions(double w0, double w1, double w2) {
    const double t0 = w0 + w1;
    const double f1 = t0 + w2;
    const double t1 = w0 * w0;
    const double t2 = t1 + w1 * t0;
    const double f2 = t2 + w2 * f1;
    const double f3 = w0 * t1 + w1 * t2 + w2 * f2;
    return {f1, f2, f3, f2 + w0 * (f1 + w0), f2 + w1 * (f1 + w1), f2 + w2 * (f1 + w2)};
}

/// A symmetric tensor from its diagonal and its off-diagonal (xy, yz, zx) entries.
Mat3 symmetric(double xx, double yy, double zz, double xy, double yz, double zx) {
    Mat3 m(0.0);
    m[0][0] = xx;
    m[1][1] = yy;
    m[2][2] = zz;
    m[0][1] = m[1][0] = xy;
    m[1][2] = m[2][1] = yz;
    m[0][2] = m[2][0] = zx;
    return m;
}

/// The ten volume integrals (1, x, y, z, x^2, y^2, z^2, xy, yz, zx) of the solid the triangles
/// bound, corners taken relative to `origin`.
std::array<double, 10> volumeIntegrals(std::span<const Vec3> vertices,
                                       std::span<const TriangleIndices> triangles,
                                       const Vec3& origin) {
    std::array<double, 10> in{};
    for (const TriangleIndices& t : triangles) {
        const Vec3 p0 = vertices[t[0]] - origin, p1 = vertices[t[1]] - origin,
                   p2 = vertices[t[2]] - origin;
        const Vec3 d = glm::cross(p1 - p0, p2 - p0);
        const Sub x = subexpressions(p0.x, p1.x, p2.x);
        const Sub y = subexpressions(p0.y, p1.y, p2.y);
        const Sub z = subexpressions(p0.z, p1.z, p2.z);
        in[0] += d.x * x.f1;
        in[1] += d.x * x.f2;
        in[2] += d.y * y.f2;
        in[3] += d.z * z.f2;
        in[4] += d.x * x.f3;
        in[5] += d.y * y.f3;
        in[6] += d.z * z.f3;
        in[7] += d.x * (p0.y * x.g0 + p1.y * x.g1 + p2.y * x.g2);
        in[8] += d.y * (p0.z * y.g0 + p1.z * y.g1 + p2.z * y.g2);
        in[9] += d.z * (p0.x * z.g0 + p1.x * z.g1 + p2.x * z.g2);
    }
    constexpr std::array<double, 10> kScale = {1.0 / 6,  1.0 / 24, 1.0 / 24,  1.0 / 24,  1.0 / 60,
                                               1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
    for (std::size_t i = 0; i < in.size(); ++i) {
        in[i] *= kScale[i];
    }
    return in;
}

} // namespace

SolidProperties boxSolid(const Vec3& h) {
    const double v = 8.0 * h.x * h.y * h.z;
    const Vec3 sq = h * h;
    return {v, Vec3(0.0),
            symmetric(v * (sq.y + sq.z) / 3.0, v * (sq.z + sq.x) / 3.0, v * (sq.x + sq.y) / 3.0,
                      0.0, 0.0, 0.0)};
}

SolidProperties sphereSolid(double r) {
    const double v = 4.0 / 3.0 * std::numbers::pi * r * r * r;
    const double i = 0.4 * v * r * r;
    return {v, Vec3(0.0), symmetric(i, i, i, 0.0, 0.0, 0.0)};
}

std::optional<SolidProperties> surfaceSolid(std::span<const Vec3> vertices,
                                            std::span<const TriangleIndices> triangles) {
    if (vertices.empty()) {
        return std::nullopt;
    }
    Vec3 lo = vertices[0], hi = vertices[0];
    for (const Vec3& v : vertices) {
        lo = glm::min(lo, v);
        hi = glm::max(hi, v);
    }
    const Vec3 origin = 0.5 * (lo + hi);
    std::array<double, 10> in = volumeIntegrals(vertices, triangles, origin);
    if (in[0] < 0.0) { // wound inward: every integral changes sign
        for (double& x : in) {
            x = -x;
        }
    }
    const double v = in[0];
    // A volume lost in rounding: far below the surface's bounding box (a flat surface).
    const Vec3 size = hi - lo;
    const double extent = std::max({size.x, size.y, size.z});
    if (!(v > 1e-12 * extent * extent * extent) || !std::isfinite(v)) {
        return std::nullopt;
    }
    const Vec3 c(in[1] / v, in[2] / v, in[3] / v);
    return SolidProperties{v, origin + c,
                           symmetric(in[5] + in[6] - v * (c.y * c.y + c.z * c.z),
                                     in[4] + in[6] - v * (c.z * c.z + c.x * c.x),
                                     in[4] + in[5] - v * (c.x * c.x + c.y * c.y),
                                     -(in[7] - v * c.x * c.y), -(in[8] - v * c.y * c.z),
                                     -(in[9] - v * c.z * c.x))};
}

ObjectSolid solidOf(const SceneObject& o) {
    if (o.shape == Shape::Box) {
        return {boxSolid(o.halfExtents), nullptr, false};
    }
    if (o.shape == Shape::Sphere) {
        return {sphereSolid(o.halfExtents.x), nullptr, false};
    }
    const TriangleMesh& mesh = *o.mesh;
    ConvexHullSurface hull = convexHullOf(mesh.vertices());
    ObjectSolid out;
    out.hull = std::make_shared<const ConvexHull>(hull.hull);
    if (mesh.closed()) {
        if (auto solid = surfaceSolid(mesh.vertices(), mesh.triangles())) {
            out.solid = *solid;
            return out;
        }
    }
    auto solid = surfaceSolid(hull.hull.vertices, hull.triangles);
    if (!solid) {
        throw std::invalid_argument("the mesh's convex hull has no volume");
    }
    out.solid = *solid;
    out.fromHull = true;
    return out;
}

void fillMassProperties(SceneObject& o, std::optional<double> massKg,
                        std::optional<double> densityKgPerM3, std::optional<Mat3> inertia) {
    const ObjectSolid s = solidOf(o);
    const double mass = massKg ? *massKg : *densityKgPerM3 * s.solid.volumeM3;
    if (!(mass > 0.0) || !std::isfinite(mass)) {
        throw std::invalid_argument("the density times the volume (" +
                                    json::show(s.solid.volumeM3) +
                                    " m^3) is not a finite mass > 0");
    }
    o.body.massKg = mass;
    o.body.centerOfMassLocal = s.solid.centroid;
    o.body.inertia = inertia ? *inertia : s.solid.inertiaPerDensity * (mass / s.solid.volumeM3);
    o.body.hull = s.hull;
}

} // namespace hapto
