#pragma once
/// Small triangle meshes for the renderer and grasp tests, built with TriangleMesh::make: a
/// flat square, a closed box, an open concave corner, a closed L-shaped prism and a torus.

#include "hapto/scenes/Scene.h"
#include "hapto/scenes/TriangleMesh.h"

#include <glm/gtc/constants.hpp>

#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <vector>

namespace hapto::test {

/// The square [-h, h]^2 in the local x-z plane at y = 0, facing +y, as two triangles that
/// share the diagonal from (-h, -h) to (h, h) (x, z).
inline std::shared_ptr<const TriangleMesh> squareMesh(double h) {
    std::vector<Vec3> v{{-h, 0, -h}, {h, 0, -h}, {h, 0, h}, {-h, 0, h}};
    // Counter-clockwise seen from +y: (v1 - v0) x (v2 - v0) points up.
    std::vector<TriangleIndices> t{{0, 2, 1}, {0, 3, 2}};
    return TriangleMesh::make(std::move(v), std::move(t), {}, "square");
}

/// The closed box [-h, h] (local), 12 triangles, outward normals.
inline std::shared_ptr<const TriangleMesh> boxMesh(const Vec3& h) {
    std::vector<Vec3> v;
    for (int i = 0; i < 8; ++i) {
        v.emplace_back((i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z);
    }
    // Each face as a quad (a, b, c, d) counter-clockwise seen from outside.
    const std::uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                       {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    std::vector<TriangleIndices> t;
    for (const auto& q : quads) {
        t.push_back({q[0], q[1], q[2]});
        t.push_back({q[0], q[2], q[3]});
    }
    return TriangleMesh::make(std::move(v), std::move(t), {}, "box");
}

/// An open concave corner at the local origin: the floor y = 0 (x, z in [0, s]) facing +y,
/// and the walls x = 0 (facing +x) and z = 0 (facing +z), each a two-triangle square.
inline std::shared_ptr<const TriangleMesh> cornerMesh(double s) {
    std::vector<Vec3> v{{0, 0, 0}, {s, 0, 0}, {s, 0, s}, {0, 0, s}, // floor
                        {0, s, 0}, {0, s, s},                       // wall x = 0, top edge
                        {s, s, 0}};                                 // wall z = 0, top corner
    std::vector<TriangleIndices> t{
        {0, 2, 1}, {0, 3, 2}, // floor, up
        {0, 5, 3}, {0, 4, 5}, // x = 0, normal +x
        {0, 1, 6}, {0, 6, 4}, // z = 0, normal +z
    };
    return TriangleMesh::make(std::move(v), std::move(t), {}, "corner");
}

/// A closed L-shaped prism: the L (0,0) (2a,0) (2a,a) (a,a) (a,2a) (0,2a) in the local x-y
/// plane, extruded over z in [-d, d]. Its inner corner is a concave edge.
inline std::shared_ptr<const TriangleMesh> lPrismMesh(double a, double d) {
    const double xy[6][2] = {{0, 0}, {2 * a, 0}, {2 * a, a}, {a, a}, {a, 2 * a}, {0, 2 * a}};
    std::vector<Vec3> v;
    for (const double z : {-d, d}) {
        for (const auto& p : xy) {
            v.emplace_back(p[0], p[1], z);
        }
    }
    std::vector<TriangleIndices> t;
    for (std::uint32_t i = 1; i + 1 < 6; ++i) { // the L is star-shaped from (0, 0): two fans
        t.push_back({0, i + 1, i});             // bottom (z = -d), facing -z
        t.push_back({6, 6 + i, 6 + i + 1});     // top (z = d), facing +z
    }
    for (std::uint32_t i = 0; i < 6; ++i) { // the sides, facing out of the counter-clockwise L
        const std::uint32_t j = (i + 1) % 6;
        t.push_back({i, j, 6 + j});
        t.push_back({i, 6 + j, 6 + i});
    }
    return TriangleMesh::make(std::move(v), std::move(t), {}, "L prism");
}

/// A torus about the local z axis (it stands in the x-y plane): ring radius `ring`, tube
/// radius `tube`, `around` x `across` quads split in two.
inline std::shared_ptr<const TriangleMesh> torusMesh(double ring, double tube, std::uint32_t around,
                                                     std::uint32_t across) {
    std::vector<Vec3> v;
    const double twoPi = 2.0 * glm::pi<double>();
    for (std::uint32_t i = 0; i < around; ++i) {
        const double u = twoPi * i / around;
        for (std::uint32_t j = 0; j < across; ++j) {
            const double w = twoPi * j / across;
            const double r = ring + tube * std::cos(w);
            v.emplace_back(r * std::cos(u), r * std::sin(u), tube * std::sin(w));
        }
    }
    std::vector<TriangleIndices> t;
    const auto at = [&](std::uint32_t i, std::uint32_t j) {
        return (i % around) * across + (j % across);
    };
    for (std::uint32_t i = 0; i < around; ++i) {
        for (std::uint32_t j = 0; j < across; ++j) {
            // Outward: along u then along w turns away from the tube's centre line.
            t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
    }
    return TriangleMesh::make(std::move(v), std::move(t), {}, "torus");
}

/// A flat grid of 2 n^2 triangles over [-h, h]^2 in the local x-z plane at y = 0, facing +y.
inline std::shared_ptr<const TriangleMesh> gridMesh(double h, std::uint32_t n) {
    std::vector<Vec3> v;
    for (std::uint32_t i = 0; i <= n; ++i) {
        for (std::uint32_t j = 0; j <= n; ++j) {
            v.emplace_back(-h + 2 * h * i / n, 0.0, -h + 2 * h * j / n);
        }
    }
    std::vector<TriangleIndices> t;
    for (std::uint32_t i = 0; i < n; ++i) {
        for (std::uint32_t j = 0; j < n; ++j) {
            const std::uint32_t a = i * (n + 1) + j, b = a + n + 1, c = b + 1, d = a + 1;
            t.push_back({a, c, b}); // up: (c - a) x (b - a) has +y
            t.push_back({a, d, c});
        }
    }
    return TriangleMesh::make(std::move(v), std::move(t), {}, "grid");
}

/// Every item of a scene an index would hold (box and sphere slots, triangle items).
inline std::vector<std::uint32_t> indexedItems(const Scene& scene) {
    std::vector<std::uint32_t> items;
    for (std::uint32_t i = 0; i < scene.itemCount(); ++i) {
        if (scene.isIndexed(scene.item(i))) {
            items.push_back(scene.item(i));
        }
    }
    return items;
}

} // namespace hapto::test
