// The convex hull of a point set, through qhull's reentrant C API (libqhull_r; Barber, Dobkin
// and Huhdanpaa, "The Quickhull algorithm for convex hulls", ACM TOMS 22(4), 1996; qhull.org).
// Design note: qhull computes the hull with its default 3-d premerge (C-0), so facets that are
// coplanar within rounding become one facet with one outward unit normal; we then order each
// facet's vertices counter-clockwise about its normal (an angle sort in the facet's plane), which
// gives the face's polygon, its fan of outward triangles and its edges (each edge lies on two
// faces and is kept once). Vertices are copies of input points (qh_pointid maps them back), so a
// hull of a mesh's vertices has exactly the mesh's coordinates. Cost: qhull's O(n log n), then
// O(f) for f facets (a merged facet's vertices sorted by angle). qhull reports errors through its
// exit code and a message stream; we give the message to nobody and say what is wrong in our own
// words.

#include "hapto/scenes/ConvexHullOf.h"

#include "hapto/core/Finite.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace hapto {
namespace {

/// qhull's state and its message stream, freed in every case.
class Qhull {
public:
    Qhull() : mErr(open_memstream(&mErrText, &mErrSize)) { qh_zero(&mQh, mErr); }
    ~Qhull() {
        int curlong = 0, totlong = 0;
        qh_freeqhull(&mQh, !qh_ALL);
        qh_memfreeshort(&mQh, &curlong, &totlong);
        if (mErr) {
            std::fclose(mErr);
        }
        std::free(mErrText);
    }
    Qhull(const Qhull&) = delete;
    Qhull& operator=(const Qhull&) = delete;

    /// Runs qhull on n points (x, y, z each); true on success.
    bool run(std::vector<coordT>& coords, int n) {
        char command[] = "qhull";
        return mErr && qh_new_qhull(&mQh, 3, n, coords.data(), False, command, nullptr, mErr) == 0;
    }
    qhT* get() { return &mQh; }

private:
    qhT mQh{};
    char* mErrText = nullptr;
    std::size_t mErrSize = 0;
    std::FILE* mErr = nullptr;
};

/// One facet's vertices (input point ids), ordered counter-clockwise about `n`: a triangle by
/// the sign of its normal, a merged facet by angle about its centroid in its plane.
std::vector<int> orderedFacet(qhT* qh, facetT* facet, const Vec3& n, std::span<const Vec3> points) {
    std::vector<int> ids;
    vertexT *vertex, **vertexp;
    FOREACHvertex_(facet->vertices) {
        ids.push_back(qh_pointid(qh, vertex->point));
    }
    const auto at = [&points](int id) { return points[static_cast<std::size_t>(id)]; };
    if (ids.size() == 3) {
        if (glm::dot(glm::cross(at(ids[1]) - at(ids[0]), at(ids[2]) - at(ids[0])), n) < 0.0) {
            std::swap(ids[1], ids[2]);
        }
        return ids;
    }
    Vec3 c(0.0);
    for (const int id : ids) {
        c += at(id);
    }
    c /= static_cast<double>(ids.size());
    const Vec3 u = glm::normalize(std::abs(n.x) < 0.9 ? glm::cross(n, Vec3(1, 0, 0))
                                                      : glm::cross(n, Vec3(0, 1, 0)));
    const Vec3 v = glm::cross(n, u);
    std::vector<std::pair<double, int>> byAngle;
    for (const int id : ids) {
        const Vec3 d = at(id) - c;
        byAngle.emplace_back(std::atan2(glm::dot(d, v), glm::dot(d, u)), id);
    }
    std::sort(byAngle.begin(), byAngle.end());
    for (std::size_t i = 0; i < ids.size(); ++i) {
        ids[i] = byAngle[i].second;
    }
    return ids;
}

/// Adds one ordered face: its plane, its fan of triangles and its edges (dense vertex indices).
void addFace(ConvexHullSurface& out, const std::vector<std::uint32_t>& polygon, const Vec3& n,
             double offset) {
    out.hull.faces.push_back({n, offset});
    for (std::size_t i = 1; i + 1 < polygon.size(); ++i) {
        out.triangles.push_back({polygon[0], polygon[i], polygon[i + 1]});
    }
    for (std::size_t i = 0; i < polygon.size(); ++i) {
        const std::uint32_t a = polygon[i], b = polygon[(i + 1) % polygon.size()];
        out.hull.edges.push_back({std::min(a, b), std::max(a, b)});
    }
}

} // namespace

ConvexHullSurface convexHullOf(std::span<const Vec3> points) {
    if (points.size() < 4) {
        throw std::invalid_argument("a convex hull needs at least 4 points, got " +
                                    std::to_string(points.size()));
    }
    if (points.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / 3)) {
        throw std::invalid_argument("too many points for a convex hull");
    }
    std::vector<coordT> coords;
    coords.reserve(points.size() * 3);
    for (const Vec3& p : points) {
        if (!finite(p)) {
            throw std::invalid_argument("a convex hull's points must be finite");
        }
        coords.insert(coords.end(), {p.x, p.y, p.z});
    }
    Qhull q;
    if (!q.run(coords, static_cast<int>(points.size()))) {
        throw std::invalid_argument("the points span no volume (they lie in one plane or on "
                                    "one line), so they have no convex hull");
    }
    qhT* qh = q.get();
    ConvexHullSurface out;
    constexpr std::uint32_t kNone = 0xFFFFFFFFu;
    std::vector<std::uint32_t> dense(points.size(), kNone); // input point id -> hull vertex
    facetT* facet;
    FORALLfacets {
        const Vec3 n(facet->normal[0], facet->normal[1], facet->normal[2]);
        std::vector<std::uint32_t> polygon;
        for (const int id : orderedFacet(qh, facet, n, points)) {
            std::uint32_t& index = dense[static_cast<std::size_t>(id)];
            if (index == kNone) {
                index = static_cast<std::uint32_t>(out.hull.vertices.size());
                out.hull.vertices.push_back(points[static_cast<std::size_t>(id)]);
            }
            polygon.push_back(index);
        }
        addFace(out, polygon, glm::normalize(n), -facet->offset);
    }
    std::sort(out.hull.edges.begin(), out.hull.edges.end());
    out.hull.edges.erase(std::unique(out.hull.edges.begin(), out.hull.edges.end()),
                         out.hull.edges.end());
    out.hull.deriveTopology(); // what the narrow phase reads per call, found once
    return out;
}

} // namespace hapto
