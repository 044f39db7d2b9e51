// Two convex polytopes (a: box or hull; b: box, hull or triangle): separating axes, then the
// contact points of the best axis by clipping (a face axis) or by the closest points of two
// edges (an edge-edge axis).
//
// Axes (Gottschalk, Lin and Manocha, "OBBTree", SIGGRAPH 1996, for two boxes: 15 axes): the
// face normals of a, the face normals of b, and the cross products of a's and b's edge
// directions (nearly parallel pairs skipped: their faces cover them). Along each axis the
// separation is the gap between the two shapes' projections (support functions), so the best
// axis gives the penetration depth exactly when the shapes overlap, and a lower bound of the
// gap when they are apart (exact for the face-to-face gap of resting and approaching bodies:
// speculative points are never reported later than they should be). Any axis separating by
// more than the margin ends the test with no points.
//
// Choice: the better face, a's or b's, when better by more than kAbsTolM + kRelTol |depth|;
// within that, the one meeting the other shape more squarely (so a resting pair keeps its
// reference face from step to step, and swapping a and b picks the same face); an edge pair
// only when better than the face by as much (Box2D's relative/absolute tolerances, Catto,
// "Contact Manifolds", GDC 2007). The depth reported may so exceed the least one by that
// tolerance, never fall below it.
//
// Points (Ericson, Real-Time Collision Detection, 2005, 8.3.4 (Sutherland-Hodgman) and
// Catto's GDC 2007 talk): the incident face (the other shape's face most anti-parallel to the
// reference normal) is clipped by the side planes of the reference face; each clipped corner
// within the margin of the reference plane is a point, midway between the corner and its
// projection. An edge pair gives one point: midway between the segments' closest points.
//
// One-sided triangle b: a body wholly behind its plane gets no points, and no axis whose
// normal would push a through the back (dot(normal, n) < 0) is chosen.
//
// Cost: the face axes F(a) V(b) + F(b) V(a) dot products, the edge axes E(a) E(b) (V(a) +
// V(b)) (a box: 6 faces, 3 edge directions, an O(1) support function), clipping O(face
// corners^2). Between two hulls of at most kGaussEdgeMax edges, Gregorius's Gauss-map pruning
// ("The Separating Axis Test between Convex Polyhedra", GDC 2013) keeps only the edge pairs
// that build a face of the Minkowski difference (the others never realise the separation):
// each edge's two faces come from the hull's derived topology (ConvexHull::edgeFaces), turned
// into the world per call, O(E); larger hulls test every pair.
//
// Features: a face point is (side of the reference << 31) | reference face << 23 | incident
// face << 15 | corner tag (an incident corner, or the clipping plane and the edge it cut); an
// edge point is 1 << 30 | edge of a << 15 | edge of b. Faces and edges beyond 255 and 32767
// wrap (features then may collide; they only key a warm start).

#include "ContactInternal.h"

#include <cmath>
#include <limits>

namespace hapto::contact {

namespace {

constexpr double kAbsTolM = 1e-6; // m
constexpr double kRelTol = 0.05;
constexpr double kParallel = 1e-6; // |sin| below which two edge directions are parallel
constexpr double kInf = std::numeric_limits<double>::infinity();

struct FaceQuery {
    double sep = -kInf;
    int face = -1;
};

struct EdgeQuery {
    double sep = -kInf;
    int dirA = -1;
    int dirB = -1;
    Vec3 axis{0.0}; // unit, from a towards b
};

// Best face of p against q; sets `apart` when some face separates by more than the margin.
// With `front` (a one-sided triangle's normal, q being that triangle), a face of p whose normal
// has dot(normal, front) > 0 separates but is never chosen: it would push p through the back.
FaceQuery queryFaces(const Polytope& p, const Polytope& q, double margin, const Vec3& front,
                     bool& apart) noexcept {
    FaceQuery best;
    for (int f = 0; f < p.faceCount(); ++f) {
        const Vec3 n = p.faceNormal(f);
        const double s = -q.support(-n) - p.faceOffset(f);
        if (s > margin) {
            apart = true;
            return best;
        }
        if (glm::dot(n, front) > kParallel) {
            continue;
        }
        if (s > best.sep) {
            best = {s, f};
        }
    }
    return best;
}

// Each edge's two face normals (world) for Gregorius's Gauss-map test, hull-hull only.
constexpr int kGaussEdgeMax = 512; // 2 x 24 KB of stack per call
struct EdgeFaces {
    std::array<Vec3, kGaussEdgeMax> n1;
    std::array<Vec3, kGaussEdgeMax> n2;
};

// Fills `out` for a hull of at most kGaussEdgeMax edges each lying on two faces (its derived
// topology, ConvexHull::edgeFaces); false otherwise (then every edge pair is tested).
bool edgeFaces(const Polytope& p, EdgeFaces& out) noexcept {
    const ConvexHull* hull = p.hull();
    if (hull == nullptr || hull->edges.size() > static_cast<std::size_t>(kGaussEdgeMax) ||
        !hull->hasTopology()) {
        return false;
    }
    for (std::size_t e = 0; e < hull->edges.size(); ++e) {
        const auto& f = hull->edgeFaces[e];
        if (f[0] == ConvexHull::kNoFace) {
            return false;
        }
        out.n1[e] = p.toWorld(hull->faces[f[0]].normal);
        out.n2[e] = p.toWorld(hull->faces[f[1]].normal);
    }
    return true;
}

// True when the arcs (a, b) and (c, d) of the Gauss map cross: the two edges build a face of
// the Minkowski difference (Gregorius, GDC 2013; c, d are the negated normals of b's edge).
bool minkowskiFace(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) noexcept {
    const Vec3 bxa = glm::cross(b, a);
    const Vec3 dxc = glm::cross(d, c);
    const double cba = glm::dot(c, bxa);
    const double dba = glm::dot(d, bxa);
    const double adc = glm::dot(a, dxc);
    const double bdc = glm::dot(b, dxc);
    return cba * dba < 0.0 && adc * bdc < 0.0 && cba * bdc > 0.0;
}

// Best edge-pair axis; sets `apart` when some axis separates by more than the margin. Between
// two hulls whose edges' faces are known, only the pairs building a Minkowski face are axes
// (the others never realise the separation); otherwise every pair of edge directions.
EdgeQuery queryEdges(const Polytope& a, const Polytope& b, double margin, bool& apart) noexcept {
    EdgeQuery best;
    EdgeFaces fa;
    EdgeFaces fb;
    const bool gauss = edgeFaces(a, fa) && edgeFaces(b, fb);
    for (int i = 0; i < a.edgeDirCount(); ++i) {
        const Vec3 da = a.edgeDir(i);
        for (int j = 0; j < b.edgeDirCount(); ++j) {
            if (gauss && !minkowskiFace(fa.n1[at(i)], fa.n2[at(i)], -fb.n1[at(j)], -fb.n2[at(j)])) {
                continue;
            }
            const Vec3 db = b.edgeDir(j);
            const Vec3 cross = glm::cross(da, db);
            const double len = glm::length(cross);
            if (!(len > kParallel * glm::length(da) * glm::length(db))) {
                continue;
            }
            const Vec3 l = cross / len;
            const double forward = -b.support(-l) - a.support(l); // b beyond a along +l
            const double backward = -a.support(-l) - b.support(l);
            const double sep = std::max(forward, backward);
            if (sep > margin) {
                apart = true;
                return best;
            }
            const Vec3 axis = forward >= backward ? l : -l;
            const bool pushesThrough =
                b.oneSided() && glm::dot(-axis, b.triangleNormal()) < -kParallel;
            if (!pushesThrough && sep > best.sep) {
                best = {sep, i, j, axis};
            }
        }
    }
    return best;
}

// Clips `in` by the plane {x : dot(side, x - origin) <= 0} into `out`; new corners' tags name
// the plane and the corner before them.
void clipBySide(const Polygon& in, const Vec3& side, const Vec3& origin, int plane,
                Polygon& out) noexcept {
    out.count = 0;
    for (int i = 0; i < in.count && out.count + 2 <= kClipMax; ++i) {
        const Vec3& p = in.points[at(i)];
        const Vec3& q = in.points[at((i + 1) % in.count)];
        const double dp = glm::dot(side, p - origin);
        const double dq = glm::dot(side, q - origin);
        if (dp <= 0.0) {
            out.points[at(out.count)] = p;
            out.tag[at(out.count++)] = in.tag[at(i)];
        }
        if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) {
            out.points[at(out.count)] = p + (q - p) * (dp / (dp - dq));
            out.tag[at(out.count++)] =
                0x4000u | (static_cast<std::uint32_t>(plane & 0x3F) << 7) | (in.tag[at(i)] & 0x7Fu);
        }
    }
}

// The face of p most anti-parallel to n.
int incidentFace(const Polytope& p, const Vec3& n) noexcept {
    int best = 0;
    double lowest = kInf;
    for (int f = 0; f < p.faceCount(); ++f) {
        const double d = glm::dot(p.faceNormal(f), n);
        if (d < lowest) {
            lowest = d;
            best = f;
        }
    }
    return best;
}

// The corner of p deepest along -n.
Vec3 deepestCorner(const Polytope& p, const Vec3& n) noexcept {
    Vec3 best = p.vertex(0);
    for (int i = 1; i < p.vertexCount(); ++i) {
        const Vec3 v = p.vertex(i);
        if (glm::dot(n, v) < glm::dot(n, best)) {
            best = v;
        }
    }
    return best;
}

// Points of reference face `face` of `ref` against the incident face of `inc`.
void faceContact(const Polytope& ref, int face, const Polytope& inc, bool refIsA,
                 PointSink& sink) noexcept {
    const Vec3 n = ref.faceNormal(face);
    const double offset = ref.faceOffset(face);
    const int incFace = incidentFace(inc, n);
    Polygon refPoly;
    ref.facePolygon(face, refPoly);
    Polygon buffers[2];
    inc.facePolygon(incFace, buffers[0]);
    int cur = 0;
    for (int k = 0; k < refPoly.count && buffers[cur].count > 0; ++k) {
        const Vec3& p = refPoly.points[at(k)];
        const Vec3 side = glm::cross(refPoly.points[at((k + 1) % refPoly.count)] - p, n);
        clipBySide(buffers[cur], side, p, k, buffers[1 - cur]);
        cur = 1 - cur;
    }
    const Vec3 normal = refIsA ? -n : n;
    const std::uint32_t base = (refIsA ? 0u : 1u << 31) |
                               (static_cast<std::uint32_t>(face & 0xFF) << 23) |
                               (static_cast<std::uint32_t>(incFace & 0xFF) << 15);
    const Polygon& clipped = buffers[cur];
    const int before = sink.count();
    for (int i = 0; i < clipped.count; ++i) {
        const Vec3& x = clipped.points[at(i)];
        const double sep = glm::dot(n, x) - offset;
        sink.add(x - n * (0.5 * sep), normal, sep, base | (clipped.tag[at(i)] & 0x7FFFu));
    }
    if (sink.count() == before) { // nothing survived the clipping: the deepest corner
        const Vec3 x = deepestCorner(inc, n);
        const double sep = glm::dot(n, x) - offset;
        sink.add(x - n * (0.5 * sep), normal, sep, base | 0x7FFFu);
    }
}

// Of p's edges parallel to dir, the one farthest along `towards` (its index).
int supportingEdge(const Polytope& p, const Vec3& dir, const Vec3& towards) noexcept {
    int best = -1;
    double farthest = -kInf;
    const double dirLen = glm::length(dir);
    for (int e = 0; e < p.edgeCount(); ++e) {
        Vec3 s{0.0};
        Vec3 t{0.0};
        p.edge(e, s, t);
        const Vec3 d = t - s;
        if (glm::length(glm::cross(d, dir)) > kParallel * glm::length(d) * dirLen) {
            continue;
        }
        const double along = glm::dot(towards, s + t);
        if (along > farthest) {
            farthest = along;
            best = e;
        }
    }
    return best;
}

void edgeContact(const Polytope& a, const Polytope& b, const EdgeQuery& q,
                 PointSink& sink) noexcept {
    const int ea = supportingEdge(a, a.edgeDir(q.dirA), q.axis);
    const int eb = supportingEdge(b, b.edgeDir(q.dirB), -q.axis);
    if (ea < 0 || eb < 0) {
        return;
    }
    Vec3 pa{0.0}, qa{0.0}, pb{0.0}, qb{0.0}, ca{0.0}, cb{0.0};
    a.edge(ea, pa, qa);
    b.edge(eb, pb, qb);
    closestSegmentPoints(pa, qa, pb, qb, ca, cb);
    const double sep = glm::dot(q.axis, cb - ca);
    const std::uint32_t feature = (1u << 30) | (static_cast<std::uint32_t>(ea & 0x7FFF) << 15) |
                                  static_cast<std::uint32_t>(eb & 0x7FFF);
    sink.add(0.5 * (ca + cb), -q.axis, sep, feature);
}

double tolerance(double sep) noexcept {
    return kAbsTolM + kRelTol * std::abs(sep);
}

// How squarely face f of p meets q: -dot of its normal and q's incident face's (1: antiparallel).
double faceToFace(const Polytope& p, int f, const Polytope& q) noexcept {
    const Vec3 n = p.faceNormal(f);
    return -glm::dot(q.faceNormal(incidentFace(q, n)), n);
}

// True when b's face is the reference. A face better by more than the tolerance wins; within
// it, the one meeting the other shape more squarely, then the deeper by a hair, then a's: the
// same face whichever shape is a, so collide(a, b) and collide(b, a) clip alike.
bool preferB(const Polytope& a, const FaceQuery& fa, const Polytope& b,
             const FaceQuery& fb) noexcept {
    if (fa.face < 0 || fb.face < 0) {
        return fa.face < 0 && fb.face >= 0;
    }
    if (std::abs(fa.sep - fb.sep) > tolerance(std::max(fa.sep, fb.sep))) {
        return fb.sep > fa.sep;
    }
    const double squareA = faceToFace(a, fa.face, b);
    const double squareB = faceToFace(b, fb.face, a);
    if (std::abs(squareA - squareB) > 1e-9) {
        return squareB > squareA;
    }
    return fb.sep > fa.sep;
}

} // namespace

void collidePolytopes(const Polytope& a, const Polytope& b, PointSink& sink) noexcept {
    if (b.oneSided() && a.support(b.triangleNormal()) < b.faceOffset(0)) {
        return; // wholly behind a one-sided triangle
    }
    bool apart = false;
    const Vec3 front = b.oneSided() ? b.triangleNormal() : Vec3(0.0);
    const FaceQuery faceA = queryFaces(a, b, sink.margin, front, apart);
    if (apart) {
        return;
    }
    const FaceQuery faceB = queryFaces(b, a, sink.margin, Vec3(0.0), apart);
    if (apart) {
        return;
    }
    const EdgeQuery edge = queryEdges(a, b, sink.margin, apart);
    if (apart) {
        return;
    }
    const bool useB = preferB(a, faceA, b, faceB);
    const double faceSep = useB ? faceB.sep : faceA.sep;
    if (edge.dirA >= 0 && edge.sep > faceSep + tolerance(faceSep)) {
        edgeContact(a, b, edge, sink);
    } else if (useB) {
        faceContact(b, faceB.face, a, false, sink);
    } else if (faceA.face >= 0) {
        faceContact(a, faceA.face, b, true, sink);
    }
}

} // namespace hapto::contact
