#pragma once
// The narrow phase's private parts, shared by its files (Contact.cpp: dispatch and manifold
// bookkeeping; ContactSphere.cpp: every pair with a sphere; ContactPolytope.cpp: boxes, hulls
// and triangles seen as one kind of convex polytope; ContactSat.cpp: separating axes and face
// clipping between two polytopes).
//
// Invariants: nothing here allocates or throws; every buffer is a fixed array whose capacity
// is named below; every loop runs in index order, so the same inputs give the same points in
// the same order, bit for bit.

#include "hapto/dynamics/Contact.h"

#include <array>
#include <cstdint>

namespace hapto::contact {

/// An int index (a face, corner or edge number) as a container index.
constexpr std::size_t at(int i) noexcept {
    return static_cast<std::size_t>(i);
}

/// Most corners of one face polygon the clipper reads (a hull face with more keeps its first
/// kFaceMax corners in angular order; convexHullOf's merged faces stay far below it).
inline constexpr int kFaceMax = 32;
/// Most points a clipped polygon can hold: an incident face of kFaceMax corners gains at most
/// one corner per side plane of a reference face of kFaceMax corners.
inline constexpr int kClipMax = 2 * kFaceMax;

/// A face polygon in world coordinates, counter-clockwise about its outward normal; tag[i]
/// names where corner i came from (for ContactPoint::feature).
struct Polygon {
    std::array<Vec3, kClipMax> points{};
    std::array<std::uint32_t, kClipMax> tag{};
    int count = 0;
};

/// A box, hull or triangle as a convex polytope in world coordinates: its corners, its faces
/// (outward unit normal, plane offset, polygon), its edges and its support function. A
/// triangle has two faces (+n, -n) when two-sided and only +n when one-sided; a box's edge
/// directions are its three axes. Borrowing view of a ConvexShape: no copies of hull data.
class Polytope {
public:
    /// The shape (kind Box, Hull or Triangle). A triangle of zero area is `degenerate()`.
    explicit Polytope(const ConvexShape& shape) noexcept;

    bool degenerate() const noexcept { return mDegenerate; }
    /// The hull of a Hull shape, else null.
    const ConvexHull* hull() const noexcept {
        return mShape.kind == ConvexShape::Kind::Hull ? mShape.hull : nullptr;
    }
    /// Turns a vector of the shape's own frame into world coordinates.
    Vec3 toWorld(const Vec3& local) const noexcept { return mShape.axes * local; }
    bool isTriangle() const noexcept { return mShape.kind == ConvexShape::Kind::Triangle; }
    /// True for a one-sided triangle (its only face is +n).
    bool oneSided() const noexcept { return mOneSided; }
    /// A triangle's unit normal (the given outward one, else the corners' right-hand normal).
    const Vec3& triangleNormal() const noexcept { return mTriNormal; }

    int vertexCount() const noexcept;
    Vec3 vertex(int i) const noexcept;
    /// max over corners of dot(dir, corner) (m times |dir|).
    double support(const Vec3& dir) const noexcept;
    /// A centre point (the box or hull origin, the triangle's centroid).
    Vec3 centroid() const noexcept;

    int faceCount() const noexcept;
    Vec3 faceNormal(int i) const noexcept;
    double faceOffset(int i) const noexcept;
    /// Face i's corners, counter-clockwise about faceNormal(i), tags = corner numbers.
    void facePolygon(int i, Polygon& out) const noexcept;

    /// Directions to cross with the other shape's for edge-edge axes (not unit).
    int edgeDirCount() const noexcept;
    Vec3 edgeDir(int i) const noexcept;
    int edgeCount() const noexcept;
    /// Edge i's end points (world).
    void edge(int i, Vec3& p, Vec3& q) const noexcept;

private:
    const ConvexShape& mShape;
    Vec3 mTriNormal{0.0};
    bool mOneSided = false;
    bool mDegenerate = false;
};

/// Collects candidate points and writes the manifold (deepest first, then those that span the
/// rest best) when there are more than ContactManifold::kMax.
class PointSink {
public:
    static constexpr int kCapacity = kClipMax;
    /// Adds a point if separation <= margin and there is room.
    void add(const Vec3& position, const Vec3& normal, double separation,
             std::uint32_t feature) noexcept;
    int count() const noexcept { return mCount; }
    /// Writes at most kMax points into out (out.count set).
    void write(ContactManifold& out) const noexcept;
    double margin = 0.0; ///< Points farther apart than this (m) are dropped.

private:
    std::array<ContactPoint, kCapacity> mPoints{};
    int mCount = 0;
};

/// Points of segments [p1, q1] and [p2, q2] nearest each other (Ericson, Real-Time Collision
/// Detection, 5.1.9).
void closestSegmentPoints(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2, Vec3& c1,
                          Vec3& c2) noexcept;

/// Sphere (centre, radius) against any shape b; normals from b towards the sphere.
void collideSphere(const Vec3& center, double radius, const ConvexShape& b,
                   PointSink& sink) noexcept;
/// Two polytopes (a: box or hull; b: box, hull or triangle); normals from b towards a.
void collidePolytopes(const Polytope& a, const Polytope& b, PointSink& sink) noexcept;

} // namespace hapto::contact
