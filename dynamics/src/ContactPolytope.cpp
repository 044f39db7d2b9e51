// Boxes, hulls and triangles as one kind of convex polytope (ContactInternal.h: Polytope), so
// one separating-axis test and one clipper serve box-box, box-hull, hull-hull, box-triangle
// and hull-triangle.
//
// A box is made on the spot from its centre, axes and half extents (8 corners, 6 faces, 12
// edges, 3 edge directions); a hull is read through its borrowed ConvexHull, placed by its
// origin and axes (the axes are a rotation, so planes move with n' = R n, d' = d + n'.origin);
// a triangle is a flat polytope with two faces (+n, -n), or one (+n) when one-sided.
//
// A hull's face polygons are its derived topology (ConvexHull::deriveTopology: the corners in
// its plane, in angular order), read per call in O(corners); a support query is O(vertices).

#include "ContactInternal.h"

#include <algorithm>
#include <cmath>

namespace hapto::contact {

namespace {

double boxSign(int bits, int k) noexcept {
    return ((bits >> k) & 1) != 0 ? 1.0 : -1.0;
}

// Reverses polygon p when it turns clockwise about n.
void makeCounterClockwise(Polygon& p, const Vec3& n) noexcept {
    if (p.count < 3) {
        return;
    }
    Vec3 area{0.0};
    for (int i = 0; i < p.count; ++i) {
        area += glm::cross(p.points[at(i)], p.points[at((i + 1) % p.count)]);
    }
    if (glm::dot(area, n) < 0.0) {
        std::reverse(p.points.begin(), p.points.begin() + p.count);
        std::reverse(p.tag.begin(), p.tag.begin() + p.count);
    }
}

// The corners of hull face f (own frame), in angular order about their mean (ConvexHull's
// derived topology); a face of more than kFaceMax corners gives kFaceMax of them, evenly spaced.
void hullFaceLocal(const ConvexHull& hull, int f, Polygon& out) noexcept {
    out.count = 0;
    if (!hull.hasTopology()) {
        return; // collide() needs a hull with its topology (ConvexHull::deriveTopology)
    }
    const std::uint32_t begin = hull.faceCornerBegin[at(f)];
    const std::uint32_t n = hull.faceCornerBegin[at(f) + 1] - begin;
    const std::uint32_t take = std::min<std::uint32_t>(n, kFaceMax);
    for (std::uint32_t c = 0; c < take; ++c) {
        const std::uint32_t v = hull.faceCorners[begin + (n == take ? c : c * n / take)];
        out.points[at(out.count)] = hull.vertices[v];
        out.tag[at(out.count++)] = v;
    }
}

} // namespace

Polytope::Polytope(const ConvexShape& shape) noexcept : mShape(shape) {
    if (shape.kind != ConvexShape::Kind::Triangle) {
        return;
    }
    const TriangleCorners& t = shape.triangle;
    const Vec3 e1 = t[1] - t[0];
    const Vec3 e2 = t[2] - t[0];
    const Vec3 cross = glm::cross(e1, e2);
    const double len = glm::length(cross);
    mDegenerate = !(len > 1e-12 * (glm::dot(e1, e1) + glm::dot(e2, e2)));
    mOneSided = shape.triangleNormal != Vec3(0.0);
    if (mOneSided) {
        mTriNormal = glm::normalize(shape.triangleNormal);
    } else if (!mDegenerate) {
        mTriNormal = cross / len;
    }
}

int Polytope::vertexCount() const noexcept {
    switch (mShape.kind) {
    case ConvexShape::Kind::Box:
        return 8;
    case ConvexShape::Kind::Hull:
        return static_cast<int>(mShape.hull->vertices.size());
    default:
        return 3;
    }
}

Vec3 Polytope::vertex(int i) const noexcept {
    switch (mShape.kind) {
    case ConvexShape::Kind::Box: {
        Vec3 p = mShape.center;
        for (int k = 0; k < 3; ++k) {
            p += mShape.axes[k] * (boxSign(i, k) * mShape.halfExtents[k]);
        }
        return p;
    }
    case ConvexShape::Kind::Hull:
        return mShape.center + mShape.axes * mShape.hull->vertices[at(i)];
    default:
        return mShape.triangle[at(i)];
    }
}

double Polytope::support(const Vec3& dir) const noexcept {
    if (mShape.kind == ConvexShape::Kind::Box) {
        double s = glm::dot(dir, mShape.center);
        for (int k = 0; k < 3; ++k) {
            s += mShape.halfExtents[k] * std::abs(glm::dot(dir, mShape.axes[k]));
        }
        return s;
    }
    if (mShape.kind == ConvexShape::Kind::Hull) { // in own frame: one rotation, not V
        const Vec3 local = glm::transpose(mShape.axes) * dir;
        double s = -std::numeric_limits<double>::infinity();
        for (const Vec3& v : mShape.hull->vertices) {
            s = std::max(s, glm::dot(local, v));
        }
        return s + glm::dot(dir, mShape.center);
    }
    const TriangleCorners& t = mShape.triangle;
    return std::max({glm::dot(dir, t[0]), glm::dot(dir, t[1]), glm::dot(dir, t[2])});
}

Vec3 Polytope::centroid() const noexcept {
    return mShape.center;
}

int Polytope::faceCount() const noexcept {
    switch (mShape.kind) {
    case ConvexShape::Kind::Box:
        return 6;
    case ConvexShape::Kind::Hull:
        return static_cast<int>(mShape.hull->faces.size());
    default:
        return mDegenerate ? 0 : (mOneSided ? 1 : 2);
    }
}

Vec3 Polytope::faceNormal(int i) const noexcept {
    switch (mShape.kind) {
    case ConvexShape::Kind::Box:
        return mShape.axes[i / 2] * (i % 2 == 0 ? 1.0 : -1.0);
    case ConvexShape::Kind::Hull:
        return mShape.axes * mShape.hull->faces[at(i)].normal;
    default:
        return i == 0 ? mTriNormal : -mTriNormal;
    }
}

double Polytope::faceOffset(int i) const noexcept {
    const Vec3 n = faceNormal(i);
    switch (mShape.kind) {
    case ConvexShape::Kind::Box:
        return glm::dot(n, mShape.center) + mShape.halfExtents[i / 2];
    case ConvexShape::Kind::Hull:
        return glm::dot(n, mShape.center) + mShape.hull->faces[at(i)].offset;
    default:
        return glm::dot(n, mShape.triangle[0]);
    }
}

void Polytope::facePolygon(int i, Polygon& out) const noexcept {
    out.count = 0;
    if (mShape.kind == ConvexShape::Kind::Box) {
        const int k = i / 2;
        const int u = (k + 1) % 3;
        const int v = (k + 2) % 3;
        constexpr double kSu[4] = {1.0, -1.0, -1.0, 1.0};
        constexpr double kSv[4] = {1.0, 1.0, -1.0, -1.0};
        const Vec3 faceCenter = mShape.center + faceNormal(i) * mShape.halfExtents[k];
        for (int c = 0; c < 4; ++c) {
            out.points[at(c)] = faceCenter + mShape.axes[u] * (kSu[c] * mShape.halfExtents[u]) +
                                mShape.axes[v] * (kSv[c] * mShape.halfExtents[v]);
            out.tag[at(c)] = static_cast<std::uint32_t>(c);
        }
        out.count = 4;
    } else if (mShape.kind == ConvexShape::Kind::Hull) {
        hullFaceLocal(*mShape.hull, i, out);
        for (int c = 0; c < out.count; ++c) {
            out.points[at(c)] = mShape.center + mShape.axes * out.points[at(c)];
        }
    } else {
        for (int c = 0; c < 3; ++c) {
            out.points[at(c)] = mShape.triangle[at(c)];
            out.tag[at(c)] = static_cast<std::uint32_t>(c);
        }
        out.count = 3;
    }
    makeCounterClockwise(out, faceNormal(i));
}

int Polytope::edgeDirCount() const noexcept {
    return mShape.kind == ConvexShape::Kind::Box ? 3 : edgeCount();
}

Vec3 Polytope::edgeDir(int i) const noexcept {
    if (mShape.kind == ConvexShape::Kind::Box) {
        return mShape.axes[i];
    }
    Vec3 p{0.0};
    Vec3 q{0.0};
    edge(i, p, q);
    return q - p;
}

int Polytope::edgeCount() const noexcept {
    switch (mShape.kind) {
    case ConvexShape::Kind::Box:
        return 12;
    case ConvexShape::Kind::Hull:
        return static_cast<int>(mShape.hull->edges.size());
    default:
        return 3;
    }
}

void Polytope::edge(int i, Vec3& p, Vec3& q) const noexcept {
    if (mShape.kind == ConvexShape::Kind::Box) {
        const int k = i / 4;
        const int u = (k + 1) % 3;
        const int v = (k + 2) % 3;
        const Vec3 mid = mShape.center + mShape.axes[u] * (boxSign(i, 0) * mShape.halfExtents[u]) +
                         mShape.axes[v] * (boxSign(i, 1) * mShape.halfExtents[v]);
        p = mid - mShape.axes[k] * mShape.halfExtents[k];
        q = mid + mShape.axes[k] * mShape.halfExtents[k];
    } else if (mShape.kind == ConvexShape::Kind::Hull) {
        const auto& e = mShape.hull->edges[at(i)];
        p = vertex(static_cast<int>(e[0]));
        q = vertex(static_cast<int>(e[1]));
    } else {
        p = mShape.triangle[at(i)];
        q = mShape.triangle[at((i + 1) % 3)];
    }
}

} // namespace hapto::contact
