// ConvexHull::deriveTopology: the face polygons and the edges' faces that the narrow phase
// (dynamics/src/ContactPolytope.cpp, ContactSat.cpp) reads on every call, found once. Design
// note: a vertex lies on a face when within kOnFaceTolerance * radiusM of its plane (merged
// nearly coplanar facets stay one face); a face's corners are sorted by their angle about the
// corners' mean in the face's plane (a stable sort, so equal angles keep index order), which
// orders a convex polygon's corners around it. Cost: O(F V) for the corners, O(E F) for the
// edges' faces, once per hull. Everything in index order: the same hull gives the same arrays.

#include "hapto/core/ConvexHull.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace hapto {

namespace {

// Appends face `face`'s corners (vertices within `tol` of its plane) in angular order.
void appendCorners(const ConvexHull& hull, const ConvexHull::Face& face, double tol,
                   std::vector<std::uint32_t>& out) {
    std::vector<std::pair<double, std::uint32_t>> corners;
    Vec3 mean{0.0};
    for (std::uint32_t i = 0; i < hull.vertices.size(); ++i) {
        if (std::abs(glm::dot(face.normal, hull.vertices[i]) - face.offset) <= tol) {
            corners.emplace_back(0.0, i);
            mean += hull.vertices[i];
        }
    }
    if (corners.empty()) {
        return;
    }
    mean /= static_cast<double>(corners.size());
    const Vec3 n = face.normal;
    const Vec3 helper = std::abs(n.x) < 0.6 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    const Vec3 u = glm::normalize(glm::cross(n, helper));
    const Vec3 w = glm::cross(n, u);
    for (auto& [angle, i] : corners) {
        const Vec3 d = hull.vertices[i] - mean;
        angle = std::atan2(glm::dot(w, d), glm::dot(u, d));
    }
    std::stable_sort(corners.begin(), corners.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& c : corners) {
        out.push_back(c.second);
    }
}

} // namespace

void ConvexHull::deriveTopology() {
    radiusM = 0.0;
    for (const Vec3& v : vertices) {
        radiusM = std::max(radiusM, glm::length(v));
    }
    const double tol = kOnFaceTolerance * radiusM;
    faceCorners.clear();
    faceCornerBegin.assign(1, 0);
    for (const Face& f : faces) {
        appendCorners(*this, f, tol, faceCorners);
        faceCornerBegin.push_back(static_cast<std::uint32_t>(faceCorners.size()));
    }
    edgeFaces.assign(edges.size(), {kNoFace, kNoFace});
    for (std::size_t e = 0; e < edges.size(); ++e) {
        const Vec3& s = vertices[edges[e][0]];
        const Vec3& t = vertices[edges[e][1]];
        std::array<std::uint32_t, 2> found{kNoFace, kNoFace};
        std::size_t count = 0;
        for (std::uint32_t f = 0; f < faces.size() && count < 2; ++f) {
            const Face& face = faces[f];
            if (std::abs(glm::dot(face.normal, s) - face.offset) <= tol &&
                std::abs(glm::dot(face.normal, t) - face.offset) <= tol) {
                found[count++] = f; // the first two faces it lies on
            }
        }
        if (count == 2) {
            edgeFaces[e] = found;
        }
    }
}

} // namespace hapto
