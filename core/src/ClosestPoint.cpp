#include "hapto/core/ClosestPoint.h"

#include <algorithm>

namespace hapto {

Vec3 closestPointOnTriangle(const Vec3& p, const TriangleCorners& t) noexcept {
    const Vec3& a = t[0];
    const Vec3& b = t[1];
    const Vec3& c = t[2];
    const Vec3 ab = b - a;
    const Vec3 ac = c - a;
    const Vec3 ap = p - a;
    const double d1 = glm::dot(ab, ap);
    const double d2 = glm::dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) {
        return a;
    }
    const Vec3 bp = p - b;
    const double d3 = glm::dot(ab, bp);
    const double d4 = glm::dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) {
        return b;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        return a + (d1 / (d1 - d3)) * ab;
    }
    const Vec3 cp = p - c;
    const double d5 = glm::dot(ab, cp);
    const double d6 = glm::dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) {
        return c;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        return a + (d2 / (d2 - d6)) * ac;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
    }
    const double denom = 1.0 / (va + vb + vc);
    return a + (vb * denom) * ab + (vc * denom) * ac;
}

double triangleDistance2(const Vec3& p, const TriangleCorners& t) noexcept {
    const Vec3 d = p - closestPointOnTriangle(p, t);
    return glm::dot(d, d);
}

TriangleEdges triangleEdges(const TriangleCorners& t, const Vec3& normal) noexcept {
    TriangleEdges e;
    for (int i = 0; i < 3; ++i) {
        e.inward[i] = glm::cross(normal, t[(i + 1) % 3] - t[i]);
        e.length2[i] = glm::dot(e.inward[i], e.inward[i]);
    }
    return e;
}

double outsideTriangleEdges(const Vec3& p, const TriangleCorners& t,
                            const TriangleEdges& edges) noexcept {
    double worst = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i) {
        worst = std::max(worst, -glm::dot(edges.inward[i], p - t[i]) / std::sqrt(edges.length2[i]));
    }
    return worst;
}

bool overGrownTriangle(const Vec3& p, const TriangleCorners& t, const Vec3& normal,
                       const TriangleEdges& edges, double marginM) noexcept {
    bool over = true; // p projects into the triangle itself
    for (int i = 0; i < 3; ++i) {
        const double out = -glm::dot(edges.inward[i], p - t[i]); // distance outside x |inward|
        if (out > 0.0) {
            if (out * out > marginM * marginM * edges.length2[i]) {
                return false;
            }
            over = false;
        }
    }
    if (over) {
        return true;
    }
    const Vec3 onPlane = p - glm::dot(normal, p - t[0]) * normal;
    return triangleDistance2(onPlane, t) <= 2.25 * marginM * marginM;
}

bool overGrownTriangle(const Vec3& p, const TriangleCorners& t, const Vec3& normal,
                       double marginM) noexcept {
    return overGrownTriangle(p, t, normal, triangleEdges(t, normal), marginM);
}

Vec3 sphereSurfacePointNearest(const Vec3& center, double radius, const Vec3& p) noexcept {
    const Vec3 d = p - center;
    const double len = glm::length(d);
    const Vec3 n = len > 0.0 ? d / len : Vec3(0, 0, 1);
    return center + radius * n;
}

Vec3 boxSurfacePointNearestLocal(const Vec3& local, const Vec3& halfExtents) noexcept {
    Vec3 l = local;
    const int best = dominantFaceAxis(l, halfExtents); // the nearest face
    l[best] = (l[best] < 0.0 ? -1.0 : 1.0) * halfExtents[best];
    return l;
}

} // namespace hapto
