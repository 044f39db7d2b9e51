#pragma once
/// Meshes built in test code (the index, BVH and timing tests): an icosphere and an open,
/// wavy sheet, made with TriangleMesh::make so they are validated like loaded ones; and the
/// volume a mesh encloses (the mesh reader and generator tests).

#include "hapto/scenes/TriangleMesh.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

namespace hapto::test {

/// A closed icosphere about the local origin: 20 * 4^subdivisions triangles, CCW from
/// outside, radius in m.
inline std::shared_ptr<const TriangleMesh> makeIcosphere(int subdivisions, double radius) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3> v{{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                        {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    std::vector<TriangleIndices> f{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (Vec3& p : v) {
        p = glm::normalize(p);
    }
    for (int s = 0; s < subdivisions; ++s) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
        const auto middle = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            const auto [it, added] = mid.try_emplace({key.first, key.second}, 0u);
            if (added) {
                it->second = static_cast<std::uint32_t>(v.size());
                v.push_back(glm::normalize(v[a] + v[b]));
            }
            return it->second;
        };
        std::vector<TriangleIndices> next;
        next.reserve(4 * f.size());
        for (const TriangleIndices& tri : f) {
            const std::uint32_t a = middle(tri[0], tri[1]), b = middle(tri[1], tri[2]),
                                c = middle(tri[2], tri[0]);
            next.push_back({tri[0], a, c});
            next.push_back({tri[1], b, a});
            next.push_back({tri[2], c, b});
            next.push_back({a, b, c});
        }
        f = std::move(next);
    }
    for (Vec3& p : v) {
        p *= radius;
    }
    return TriangleMesh::make(std::move(v), std::move(f), {}, "test icosphere");
}

/// An open sheet of n x n quads (2 n^2 triangles) over [-size/2, size/2]^2 in local x, y,
/// its height a smooth wave of amplitude `amplitude` (m).
inline std::shared_ptr<const TriangleMesh> makeWavySheet(int n, double size, double amplitude) {
    std::vector<Vec3> v;
    std::vector<TriangleIndices> f;
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
            const double x = size * (double(i) / n - 0.5), y = size * (double(j) / n - 0.5);
            v.emplace_back(x, y, amplitude * std::sin(9.0 * x / size) * std::cos(7.0 * y / size));
        }
    }
    const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            f.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            f.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
    return TriangleMesh::make(std::move(v), std::move(f), {}, "test sheet");
}

/// The volume the triangles enclose, (1/6) sum v0 . (v1 x v2) (divergence theorem), in m^3:
/// positive when they face outward.
inline double signedVolume(const TriangleMesh& m) {
    double v = 0.0;
    for (std::uint32_t t = 0; t < m.triangleCount(); ++t) {
        const auto c = m.corners(t);
        v += glm::dot(c[0], glm::cross(c[1], c[2]));
    }
    return v / 6.0;
}

} // namespace hapto::test
