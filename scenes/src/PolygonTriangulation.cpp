// Model faces cut into triangles (MeshReading.h, triangulate). Design note: the cut is the one
// assimp 5.2.5's Triangulate step made when hapto read models with it (TriangulateProcess::
// TriangulateMesh in assimp's code/PostProcessing/TriangulateProcess.cpp, with NewellNormal,
// OnLeftSideOfLine2D and PointInTriangle2D from code/Common/PolyTools.h), computed the same way
// in 32-bit floats, so a model loads to the same triangles as before: a quadrilateral is cut
// along the diagonal from its concave corner (the first corner whose two angles to the opposite
// corner sum past pi; corner 0 when it is convex); a larger polygon is projected onto the plane
// its Newell normal is most nearly perpendicular to and cut ear by ear (an ear: a corner that is
// not concave and whose triangle holds no other corner), which is a fan from its last corner when
// it is convex; when no ear is left the rest of it is dropped, as assimp dropped it. Checked
// against assimp 5.2.5 itself on generated simple polygons (convex, concave, collinear corners,
// not quite planar): the same triangles. A polygon that is not simple (it crosses itself, or
// comes back to a corner it passed) may be cut otherwise than assimp cut it: that input has no
// right answer. Cost: O(n) per triangle of an n-gon, O(n^2) per polygon.

#include "MeshReading.h"

#include <cmath>
#include <span>
#include <utility>

namespace hapto::detail {
namespace {

/// A position or a direction in 32-bit floats (assimp's aiVector3D).
struct F3 {
    float x, y, z;
    float operator[](unsigned c) const { return c == 0 ? x : c == 1 ? y : z; }
};

/// A point on the projection plane (assimp's aiVector2D).
struct F2 {
    float x, y;
};

F3 minus(F3 a, F3 b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}

float dot(F3 a, F3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

/// The unit vector along `v` (unchanged when it is zero), as aiVector3D::Normalize.
F3 unit(F3 v) {
    const float length = std::sqrt(dot(v, v));
    if (length == 0.0f) {
        return v;
    }
    const float inverse = 1.0f / length;
    return {v.x * inverse, v.y * inverse, v.z * inverse};
}

/// The signed area of the triangle (a, b, c), in doubles as PolyTools' GetArea2D.
double area(F2 a, F2 b, F2 c) {
    return 0.5 * (a.x * (static_cast<double>(c.y) - b.y) + b.x * (static_cast<double>(a.y) - c.y) +
                  c.x * (static_cast<double>(b.y) - a.y));
}

/// True when `p` lies strictly inside the triangle (a, b, c) (barycentric, as PointInTriangle2D).
bool inside(F2 a, F2 b, F2 c, F2 p) {
    const F2 v0{b.x - a.x, b.y - a.y};
    const F2 v1{c.x - a.x, c.y - a.y};
    const F2 v2{p.x - a.x, p.y - a.y};
    const double d00 = v0.x * v0.x + v0.y * v0.y;
    const double d01 = v0.x * v1.x + v0.y * v1.y;
    const double d02 = v0.x * v2.x + v0.y * v2.y;
    const double d11 = v1.x * v1.x + v1.y * v1.y;
    const double d12 = v1.x * v2.x + v1.y * v2.y;
    const double denominator = d00 * d11 - d01 * d01;
    if (denominator == 0.0) {
        return false;
    }
    const double inverse = 1.0 / denominator;
    const double u = (d11 * d02 - d01 * d12) * inverse;
    const double v = (d00 * d12 - d01 * d02) * inverse;
    return u > 0 && v > 0 && u + v < 1;
}

/// Collects triangles, rotating their corners as assimp's n-gon encoding did: a triangle whose
/// first corner is the previous triangle's first corner is rotated (c, a, b), a quadrilateral's
/// pair is fanned from its opposite corner instead.
class TriangleSink {
public:
    TriangleSink(std::vector<TriangleIndices>& out, bool rotate) : mOut(out), mRotate(rotate) {}

    /// Starts a face; `shared`: false when no corner of it is a corner of an earlier face.
    void beginFace(bool shared) {
        if (!shared) {
            mLastFirst = ~0u;
        }
    }

    void triangle(TriangleIndices t) {
        if (mRotate && t[0] == mLastFirst) {
            t = {t[2], t[0], t[1]};
        }
        mLastFirst = t[0];
        mOut.push_back(t);
    }

    void quad(TriangleIndices a, TriangleIndices b) {
        if (mRotate && a[0] == mLastFirst) {
            a = {a[2], a[0], a[1]};
            b = {b[1], b[2], b[0]};
        }
        mLastFirst = a[0];
        mOut.push_back(a);
        mOut.push_back(b);
    }

private:
    std::vector<TriangleIndices>& mOut;
    bool mRotate;
    std::uint32_t mLastFirst = ~0u;
};

constexpr float kPi = 3.1415926538f; // assimp's AI_MATH_PI_F

/// The corner of a quadrilateral to cut from: the first whose angles to its neighbours through
/// the opposite corner sum past pi (a concave corner), else 0.
unsigned quadStart(const F3 (&v)[4]) {
    for (unsigned i = 0; i < 4; ++i) {
        const F3 left = unit(minus(v[(i + 3) % 4], v[i]));
        const F3 diagonal = unit(minus(v[(i + 2) % 4], v[i]));
        const F3 right = unit(minus(v[(i + 1) % 4], v[i]));
        const float angle = std::acos(dot(left, diagonal)) + std::acos(dot(right, diagonal));
        if (angle > kPi) {
            return i;
        }
    }
    return 0;
}

/// The polygon's corners projected onto the plane its Newell normal is nearest to perpendicular
/// to, oriented so that the polygon winds counter-clockwise there.
std::vector<F2> project(const std::vector<F3>& p) {
    const std::size_t n = p.size();
    float xy = 0.0f, yz = 0.0f, zx = 0.0f;
    for (std::size_t i = 0; i < n; ++i) {
        const F3& at = p[(i + 1) % n];
        const F3& low = p[i];
        const F3& high = p[(i + 2) % n];
        xy += at.x * (high.y - low.y);
        yz += at.y * (high.z - low.z);
        zx += at.z * (high.x - low.x);
    }
    const float ax = std::abs(yz), ay = std::abs(zx), az = std::abs(xy);
    unsigned a = 0, b = 1;
    float sign = xy;
    if (ax > ay) {
        if (ax > az) {
            a = 1, b = 2, sign = yz;
        }
    } else if (ay > az) {
        a = 2, b = 0, sign = zx;
    }
    if (sign < 0.0f) {
        std::swap(a, b);
    }
    std::vector<F2> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        out[i] = {p[i][a], p[i][b]};
    }
    return out;
}

/// True when corner `ear` (between `prev` and `next`) is an ear of the projected polygon.
bool isEar(const std::vector<F2>& q, int prev, int ear, int next) {
    const F2 p0 = q[prev], p1 = q[ear], p2 = q[next];
    if (area(p0, p1, p2) > 0) {
        return false; // a concave corner
    }
    for (const F2& v : q) {
        const bool corner = (v.x == p0.x && v.y == p0.y) || (v.x == p1.x && v.y == p1.y) ||
                            (v.x == p2.x && v.y == p2.y);
        if (!corner && inside(p0, p1, p2, v)) {
            return false;
        }
    }
    return true;
}

/// Cuts an n-gon (n > 4) ear by ear into `sink`; `idx` are its vertex indices.
void cutEars(const std::vector<F2>& q, std::span<const std::uint32_t> idx, TriangleSink& sink) {
    const int max = static_cast<int>(q.size());
    std::vector<char> done(q.size(), 0);
    int num = max, prev = max - 1, next = 0, ear = 0;
    while (num > 3) {
        int passes = 0;
        for (ear = next;; prev = ear, ear = next) {
            for (next = ear + 1; done[(next >= max ? next = 0 : next)]; ++next) {
            }
            if (next < ear && ++passes == 2) {
                break;
            }
            if (isEar(q, prev, ear, next)) {
                break;
            }
        }
        if (passes == 2) {
            return; // no ear: not a simple polygon; the rest of it is dropped
        }
        sink.triangle({idx[prev], idx[ear], idx[next]});
        done[ear] = 1;
        --num;
    }
    TriangleIndices last{};
    int t = 0;
    for (std::uint32_t& corner : last) {
        while (done[t]) {
            ++t;
        }
        corner = idx[t++];
    }
    sink.triangle(last);
}

F3 positionOf(const ModelFaces& model, std::uint32_t i) {
    const Vec3& v = model.vertices[i];
    return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}

} // namespace

std::vector<TriangleIndices> triangulate(const ModelFaces& model, NgonRotation rotation) {
    std::vector<TriangleIndices> out;
    out.reserve(model.corners.size() - 2 * model.faceSizes.size());
    bool polygons = false;
    for (const std::uint16_t n : model.faceSizes) {
        polygons = polygons || n > 3;
    }
    // assimp's step left a mesh of triangles alone: no rotation there.
    TriangleSink sink(out, rotation != NgonRotation::None && polygons);
    std::size_t at = 0;
    for (const std::uint16_t n : model.faceSizes) {
        const std::span<const std::uint32_t> idx(model.corners.data() + at, n);
        at += n;
        sink.beginFace(rotation == NgonRotation::AcrossFaces);
        if (n == 3) {
            sink.triangle({idx[0], idx[1], idx[2]});
        } else if (n == 4) {
            const F3 v[4] = {positionOf(model, idx[0]), positionOf(model, idx[1]),
                             positionOf(model, idx[2]), positionOf(model, idx[3])};
            const unsigned s = quadStart(v);
            sink.quad({idx[s], idx[(s + 1) % 4], idx[(s + 2) % 4]},
                      {idx[s], idx[(s + 2) % 4], idx[(s + 3) % 4]});
        } else {
            std::vector<F3> p(n);
            for (std::size_t i = 0; i < n; ++i) {
                p[i] = positionOf(model, idx[i]);
            }
            cutEars(project(p), idx, sink);
        }
    }
    return out;
}

} // namespace hapto::detail
