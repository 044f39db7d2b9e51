#include "hapto/scenes/TriangleMesh.h"

#include "hapto/core/Finite.h"
#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace hapto {

namespace {

/// Relative area below which a triangle counts as degenerate: |cross|^2 <= this x (longest
/// edge)^4, i.e. the triangle is thinner than 1e-12 of its longest edge.
constexpr double kDegenerateRelative2 = 1e-24;

bool degenerate(const TriangleIndices& t, std::span<const Vec3> v) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        return true;
    }
    const Vec3 e0 = v[t[1]] - v[t[0]];
    const Vec3 e1 = v[t[2]] - v[t[0]];
    const Vec3 e2 = v[t[2]] - v[t[1]];
    const double longest2 = std::max({glm::dot(e0, e0), glm::dot(e1, e1), glm::dot(e2, e2)});
    const Vec3 c = glm::cross(e0, e1);
    return !(glm::dot(c, c) > kDegenerateRelative2 * longest2 * longest2);
}

/// A triangle's corner positions in lexicographic order, -0 read as +0: two triangles with the
/// same three corner positions, in any order, have equal keys.
using CornerKey = std::array<Vec3, 3>;

CornerKey cornerKey(const TriangleIndices& t, std::span<const Vec3> v) {
    CornerKey k{v[t[0]] + Vec3(0.0), v[t[1]] + Vec3(0.0), v[t[2]] + Vec3(0.0)};
    const auto less = [](const Vec3& a, const Vec3& b) {
        return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
    };
    if (less(k[1], k[0])) {
        std::swap(k[0], k[1]);
    }
    if (less(k[2], k[1])) {
        std::swap(k[1], k[2]);
    }
    if (less(k[1], k[0])) {
        std::swap(k[0], k[1]);
    }
    return k;
}

std::uint64_t hashOf(const CornerKey& k) {
    std::uint64_t h = 0x9E3779B97F4A7C15ull;
    for (const Vec3& p : k) {
        for (int i = 0; i < 3; ++i) {
            h = (h ^ std::bit_cast<std::uint64_t>(p[i])) * 0xFF51AFD7ED558CCDull;
            h ^= h >> 32;
        }
    }
    return h;
}

/// Keeps the first of every set of triangles with the same corner positions (in any order) and
/// returns how many others it dropped. Open addressing in a table of at least twice as many
/// slots as triangles, each holding a kept triangle's position: O(n) expected, 8 bytes or
/// less per triangle.
std::uint64_t dropDuplicates(std::vector<TriangleIndices>& triangles, std::span<const Vec3> v) {
    constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
    std::size_t slots = 16;
    while (slots < 2 * triangles.size()) {
        slots *= 2;
    }
    std::vector<std::uint32_t> table(slots, kEmpty);
    std::size_t kept = 0;
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        const CornerKey key = cornerKey(triangles[i], v);
        std::size_t slot = hashOf(key) & (slots - 1);
        while (table[slot] != kEmpty && cornerKey(triangles[table[slot]], v) != key) {
            slot = (slot + 1) & (slots - 1);
        }
        if (table[slot] == kEmpty) {
            table[slot] = static_cast<std::uint32_t>(kept);
            triangles[kept++] = triangles[i];
        }
    }
    const std::uint64_t dropped = triangles.size() - kept;
    triangles.resize(kept);
    return dropped;
}

/// Refuses a vertex beyond kMaxCoordinate, and triangles whose corners span less than
/// kMinSize (but are not all one point: those are degenerate).
void checkExtent(std::span<const Vec3> vertices, std::span<const TriangleIndices> triangles,
                 double scale, const std::string& where) {
    const std::string scaled = scale == 1.0 ? "" : " (after the scale " + json::show(scale) + ")";
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        const Vec3& p = vertices[i];
        if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) >
            TriangleMesh::kMaxCoordinate) {
            throw InputError(where + ": vertices[" + std::to_string(i) + "] (" + json::show(p.x) +
                             ", " + json::show(p.y) + ", " + json::show(p.z) + ")" + scaled +
                             " lies beyond " + json::show(TriangleMesh::kMaxCoordinate) +
                             " m from the mesh's origin, the farthest a mesh vertex may be");
        }
    }
    Aabb box = Aabb::empty();
    for (const TriangleIndices& t : triangles) {
        for (const std::uint32_t i : t) {
            box.expand(vertices[i]);
        }
    }
    const Vec3 size = triangles.empty() ? Vec3(0.0) : box.size();
    const double across = std::max({size.x, size.y, size.z});
    if (across > 0.0 && across < TriangleMesh::kMinSize) {
        throw InputError(where + ": the mesh is " + json::show(across) + " m across" + scaled +
                         ", less than the " + json::show(TriangleMesh::kMinSize) +
                         " m a mesh must span");
    }
}

/// True when every undirected edge is used by exactly two triangles.
bool everyEdgeShared(std::span<const TriangleIndices> triangles) {
    std::vector<std::uint64_t> edges;
    edges.reserve(triangles.size() * 3);
    for (const TriangleIndices& t : triangles) {
        for (int i = 0; i < 3; ++i) {
            const std::uint64_t a = t[i];
            const std::uint64_t b = t[(i + 1) % 3];
            edges.push_back(std::min(a, b) << 32 | std::max(a, b));
        }
    }
    std::sort(edges.begin(), edges.end());
    for (std::size_t i = 0; i < edges.size();) {
        std::size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) {
            ++j;
        }
        if (j - i != 2) {
            return false;
        }
        i = j;
    }
    return !edges.empty();
}

} // namespace

std::shared_ptr<const TriangleMesh> TriangleMesh::make(std::vector<Vec3> vertices,
                                                       std::vector<TriangleIndices> triangles,
                                                       MeshSource source,
                                                       const std::string& where) {
    if (vertices.size() > kMaxVertices) {
        throw InputError(where + ": " + std::to_string(vertices.size()) +
                         " vertices; a mesh may have at most " + std::to_string(kMaxVertices));
    }
    if (triangles.size() > kMaxTriangles) {
        throw InputError(where + ": " + std::to_string(triangles.size()) +
                         " triangles; a mesh may have at most " + std::to_string(kMaxTriangles));
    }
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        if (!finite(vertices[i])) {
            throw InputError(where + ": vertices[" + std::to_string(i) +
                             "] is not finite (after scaling)");
        }
    }
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            if (triangles[i][k] >= vertices.size()) {
                throw InputError(where + ": triangles[" + std::to_string(i) + "][" +
                                 std::to_string(k) + "]: vertex index " +
                                 std::to_string(triangles[i][k]) +
                                 " is out of range (the mesh has " +
                                 std::to_string(vertices.size()) + " vertices)");
            }
        }
    }
    checkExtent(vertices, triangles, source.scale, where);
    auto mesh = std::shared_ptr<TriangleMesh>(new TriangleMesh());
    mesh->mSource = std::move(source);
    std::size_t kept = 0;
    for (const TriangleIndices& t : triangles) {
        if (degenerate(t, vertices)) {
            ++mesh->mDropped;
            continue;
        }
        triangles[kept++] = t;
    }
    triangles.resize(kept);
    mesh->mDuplicates = dropDuplicates(triangles, vertices);
    if (triangles.empty()) {
        throw InputError(where + ": no triangles" +
                         (mesh->mDropped > 0
                              ? " left (all " + std::to_string(mesh->mDropped) + " were degenerate)"
                              : std::string()));
    }
    for (const TriangleIndices& t : triangles) {
        for (const std::uint32_t i : t) {
            mesh->mBounds.expand(vertices[i]);
            mesh->mRadius = std::max(mesh->mRadius, glm::length(vertices[i]));
        }
    }
    mesh->mClosed = everyEdgeShared(triangles);
    mesh->mVertices = std::move(vertices);
    mesh->mTriangles = std::move(triangles);
    mesh->mVertices.shrink_to_fit();
    mesh->mTriangles.shrink_to_fit();
    mesh->mFaces.resize(mesh->mTriangles.size());
    for (std::uint32_t t = 0; t < mesh->mTriangles.size(); ++t) {
        const auto [a, b, c] = mesh->corners(t);
        const Vec3 n = glm::cross(b - a, c - a);
        const double len = glm::length(n);
        if (len > 0.0 && std::isfinite(len)) {
            mesh->mFaces[t] = {n / len, glm::dot(n / len, a)};
        }
    }
    mesh->buildBvh();
    return mesh;
}

namespace {

float roundDown(double v) {
    float f = static_cast<float>(v);
    return f > v ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}

float roundUp(double v) {
    float f = static_cast<float>(v);
    return f < v ? std::nextafter(f, std::numeric_limits<float>::infinity()) : f;
}

} // namespace

void TriangleMesh::buildBvh() {
    // Design note in the header. Per triangle, its local AABB and centroid once; then ranges of
    // the order array are split at their median centroid (nth_element) along the longest axis
    // of their centroids' box, depth first, so the left child is always the next node.
    const std::uint32_t n = triangleCount();
    std::vector<Aabb> boxes(n);
    std::vector<Vec3> centroids(n);
    for (std::uint32_t t = 0; t < n; ++t) {
        const auto [a, b, c] = corners(t);
        boxes[t] = {glm::min(glm::min(a, b), c), glm::max(glm::max(a, b), c)};
        centroids[t] = (a + b + c) / 3.0;
    }
    mBvhOrder.resize(n);
    for (std::uint32_t t = 0; t < n; ++t) {
        mBvhOrder[t] = t;
    }
    mBvhNodes.clear();
    mBvhNodes.reserve(2 * (n / kBvhLeafTriangles + 1));
    mBvhDepth = 0;
    // Recursion depth is the tree's, at most kBvhMaxDepth (median splits).
    const auto build = [&](const auto& self, std::uint32_t begin, std::uint32_t end,
                           int depth) -> void {
        Aabb box = Aabb::empty();
        Aabb spread = Aabb::empty();
        for (std::uint32_t k = begin; k < end; ++k) {
            box.expand(boxes[mBvhOrder[k]]);
            spread.expand(centroids[mBvhOrder[k]]);
        }
        const std::uint32_t at = static_cast<std::uint32_t>(mBvhNodes.size());
        MeshBvhNode node;
        for (int a = 0; a < 3; ++a) {
            node.min[a] = roundDown(box.min[a]);
            node.max[a] = roundUp(box.max[a]);
        }
        node.first = begin;
        node.count = end - begin;
        mBvhNodes.push_back(node);
        mBvhDepth = std::max(mBvhDepth, depth);
        if (end - begin <= kBvhLeafTriangles) {
            return;
        }
        const Vec3 size = spread.size();
        const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
        // Half the leaves to each side, the left ones full: leaves of 4, n / 2 nodes.
        const std::uint32_t leaves = (end - begin + kBvhLeafTriangles - 1) / kBvhLeafTriangles;
        const std::uint32_t mid = begin + (leaves + 1) / 2 * kBvhLeafTriangles;
        std::nth_element(mBvhOrder.begin() + begin, mBvhOrder.begin() + mid,
                         mBvhOrder.begin() + end, [&](std::uint32_t l, std::uint32_t r) {
                             return centroids[l][axis] < centroids[r][axis];
                         });
        self(self, begin, mid, depth + 1); // the left child: node at + 1
        mBvhNodes[at].count = 0;
        mBvhNodes[at].first = static_cast<std::uint32_t>(mBvhNodes.size());
        self(self, mid, end, depth + 1);
    };
    build(build, 0, n, 0);
    mBvhNodes.shrink_to_fit();
}

} // namespace hapto
