#pragma once
/// Scenes, index specs and query points shared by the index tests: random, clustered and
/// lattice scenes, one full of degenerate objects, and one with meshes among boxes and spheres.

#include "TestMeshes.h"

#include "hapto/core/Random.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/Generators.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace hapto::test {

/// Thin, huge, partly outside, wholly outside, face-aligned, point-like boxes; spheres on cell
/// corners; a tight cluster; random rotated cubes. Bounds are the +-0.125 m cube, so octree
/// cell faces are exact binary fractions and several objects sit exactly on them.
inline Scene makeDegenerateScene() {
    std::vector<SceneObject> o;
    const auto rot = [](double angle, Vec3 axis) {
        return glm::angleAxis(angle, glm::normalize(axis));
    };
    o.push_back(makeBox(100, {0.01, 0.02, 0.03}, {0.03, 0.02, 1e-7}, rot(0.7, {1, 2, 3})));
    o.push_back(makeBox(101, {-0.02, 0.01, 0.0}, {0.05, 1e-8, 1e-8}, rot(1.1, {3, -1, 2})));
    o.push_back(makeBox(102, {0.05, 0.0, 0.0}, {0.3, 0.3, 0.3}, rot(0.2, {0, 0, 1})));
    o.push_back(makeBox(103, {0.12, 0.12, -0.12}, Vec3(0.02), rot(0.5, {1, 1, 0})));
    o.push_back(makeBox(104, {0.3, 0.0, 0.0}, Vec3(0.01)));
    o.push_back(makeBox(105, Vec3(0.015625), Vec3(0.015625)));
    o.push_back(makeBox(106, Vec3(-0.0625), Vec3(0.0625)));
    o.push_back(makeSphere(107, {0.0625, 0.0625, -0.0625}, 0.01));
    o.push_back(makeSphere(108, {0.03125, -0.03125, 0.0}, 1e-6));
    o.push_back(makeSphere(109, {-0.125, 0.0, 0.1}, 0.02));
    o.push_back(makeBox(110, {0.0625, 0.0, 0.0}, Vec3(1e-9)));
    o.push_back(makeBox(111, {0.0, 0.0625, 0.03125}, {0.03125, 0.0, 0.01})); // zero thickness
    Random rng(11);
    ObjectId id = 200;
    for (int i = 0; i < 30; ++i) { // a tight cluster: leaves reach the minimum size
        const Vec3 c =
            Vec3(-0.05, 0.05, 0.05) + 0.001 * Vec3(rng.normal(), rng.normal(), rng.normal());
        o.push_back(makeBox(id++, c, Vec3(0.001),
                            rot(rng.uniform(0, 3), {rng.uniform(-1, 1), 1, rng.uniform(-1, 1)})));
    }
    for (int i = 0; i < 150; ++i) {
        const Vec3 c(rng.uniform(-0.13, 0.13), rng.uniform(-0.13, 0.13), rng.uniform(-0.13, 0.13));
        o.push_back(makeBox(
            id++, c,
            Vec3(rng.uniform(0.001, 0.01), rng.uniform(0.001, 0.01), rng.uniform(0.0001, 0.01)),
            rot(rng.uniform(0, 3), {rng.uniform(-1, 1), rng.uniform(-1, 1), 1})));
    }
    for (int i = 0; i < 30; ++i) {
        const Vec3 c(rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12), rng.uniform(-0.12, 0.12));
        o.push_back(makeSphere(id++, c, rng.uniform(0.001, 0.02)));
    }
    return Scene({Vec3(-0.125), Vec3(0.125)}, std::move(o));
}

/// Boxes and spheres with two meshes among them (a closed icosphere of 1280 triangles and an
/// open wavy sheet of 512, both rotated; a small icosphere partly outside the bounds), so
/// object slots and triangle items mix and the meshes' own slots are not indexed.
inline Scene makeMeshScene() {
    std::vector<SceneObject> o;
    Random rng(23);
    ObjectId id = 1;
    for (int i = 0; i < 20; ++i) {
        const Vec3 c(rng.uniform(-0.11, 0.11), rng.uniform(-0.11, 0.11), rng.uniform(-0.11, 0.11));
        o.push_back(makeBox(id++, c, Vec3(rng.uniform(0.002, 0.01)),
                            glm::angleAxis(rng.uniform(0, 3), glm::normalize(Vec3(1, 2, 3)))));
    }
    o.push_back(makeMesh(id++, Vec3(0.02, -0.01, 0.0), test::makeIcosphere(3, 0.06),
                         glm::angleAxis(0.4, glm::normalize(Vec3(1, -1, 2)))));
    for (int i = 0; i < 10; ++i) {
        const Vec3 c(rng.uniform(-0.11, 0.11), rng.uniform(-0.11, 0.11), rng.uniform(-0.11, 0.11));
        o.push_back(makeSphere(id++, c, rng.uniform(0.002, 0.02)));
    }
    o.push_back(makeMesh(id++, Vec3(0.0, 0.0, -0.08), test::makeWavySheet(16, 0.2, 0.01),
                         glm::angleAxis(0.3, glm::normalize(Vec3(1, 0, 0)))));
    o.push_back(makeMesh(id++, Vec3(0.12, 0.12, 0.0), test::makeIcosphere(1, 0.02)));
    o.push_back(makeBox(id++, Vec3(0.0), Vec3(0.0625))); // faces on octree cell faces
    return Scene({Vec3(-0.125), Vec3(0.125)}, std::move(o));
}

/// The scenes every index test runs over.
inline std::vector<std::pair<std::string, Scene>> testScenes() {
    std::vector<std::pair<std::string, Scene>> s;
    RandomOptions r;
    r.count = 300;
    r.seed = 5;
    r.cubeSize = 0.02;
    r.rotate = true;
    s.emplace_back("random rotated", makeRandomScene(r));
    ClusterOptions c;
    c.count = 1500;
    c.clusters = 5;
    c.cubeSize = 0.003;
    c.spread = 0.006;
    c.rotate = true;
    c.seed = 9;
    s.emplace_back("clustered rotated", makeClusterScene(c));
    LatticeOptions l;
    l.perSide = 6;
    l.cubeSize = 0.02;
    l.gap = 0.0; // faces touch
    s.emplace_back("lattice touching", makeLatticeScene(l));
    l.perSide = 5;
    l.cubeSize = 0.05;
    l.gap = 0.01; // the paper's experiment 1
    s.emplace_back("lattice paper", makeLatticeScene(l));
    s.emplace_back("degenerate", makeDegenerateScene());
    s.emplace_back("meshes", makeMeshScene());
    return s;
}

/// The index specs every index test runs over, in both overlap modes.
inline std::vector<IndexSpec> testSpecs() {
    std::vector<IndexSpec> specs;
    for (const OverlapMode m : {OverlapMode::Obb, OverlapMode::Aabb}) {
        specs.push_back(IndexSpec::grid(1, m));
        specs.push_back(IndexSpec::grid(5, m));
        specs.push_back(IndexSpec::grid(16, m));
        specs.push_back(IndexSpec::octree(2, 0.005, m));
        specs.push_back(IndexSpec::octree(1, 0.001, m));
        specs.push_back(IndexSpec::octree(8, 0.02, m));
    }
    specs.push_back(IndexSpec::brute());
    return specs;
}

/// Corners, edge midpoints, face centres and centre of a box (27 points).
inline void addBoxPoints(const Aabb& b, std::vector<Vec3>& out) {
    for (int z = 0; z < 3; ++z) {
        for (int y = 0; y < 3; ++y) {
            for (int x = 0; x < 3; ++x) {
                const auto pick = [&](int i, int a) {
                    return i == 0 ? b.min[a] : i == 2 ? b.max[a] : 0.5 * (b.min[a] + b.max[a]);
                };
                out.emplace_back(pick(x, 0), pick(y, 1), pick(z, 2));
            }
        }
    }
}

/// Query points for a scene: random ones, points on octree and grid cell faces, edges and
/// corners (binary and decimal fractions of the bounds), on object corners and faces, on the
/// bounds' faces and corners, and outside.
inline std::vector<Vec3> queryPoints(const Scene& scene, std::uint64_t seed, int randomCount) {
    Random rng(seed);
    const Aabb& b = scene.bounds();
    const Vec3 size = b.size();
    std::vector<Vec3> p;
    for (int i = 0; i < randomCount; ++i) {
        p.emplace_back(rng.uniform(b.min.x, b.max.x), rng.uniform(b.min.y, b.max.y),
                       rng.uniform(b.min.z, b.max.z));
    }
    // Lattice points of octree levels 1..6 and grids 5 and 16: faces, edges, corners.
    for (const int div : {2, 4, 8, 16, 32, 64, 5}) {
        for (int i = 0; i < 60; ++i) {
            Vec3 q(0.0);
            for (int a = 0; a < 3; ++a) {
                const bool onPlane = rng.uniform() < 0.7;
                q[a] = onPlane
                           ? b.min[a] + static_cast<double>(rng.below(div + 1)) * (size[a] / div)
                           : rng.uniform(b.min[a], b.max[a]);
            }
            p.push_back(q);
        }
    }
    addBoxPoints(b, p);
    // Outside the bounds, in a shell a fifth of their size deep: objects reach out there too.
    for (int i = 0; i < randomCount / 4; ++i) {
        Vec3 q(0.0);
        for (int a = 0; a < 3; ++a) {
            q[a] = rng.uniform(b.min[a] - 0.2 * size[a], b.max[a] + 0.2 * size[a]);
        }
        p.push_back(q);
    }
    // Object corners and face centres: on the surface, so inside the closed solid.
    for (std::uint32_t s = 0; s < scene.size() && s < 400; ++s) {
        const Obb o = scene.object(s).obb();
        for (int k = 0; k < 8; ++k) {
            const Vec3 sign((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
            p.push_back(o.center + o.axes * (sign * o.halfExtents));
        }
        p.push_back(o.center + o.axes[0] * o.halfExtents.x);
        p.push_back(o.center);
    }
    // Triangle corners, edge midpoints and points inside triangles: on mesh surfaces.
    for (std::uint32_t i = 0, used = 0; i < scene.itemCount() && used < 600; ++i) {
        const std::uint32_t item = scene.item(i);
        if (!isTriangleItem(item) || rng.uniform() > 0.3) {
            continue;
        }
        ++used;
        const auto [a, b, c] = scene.triangleCorners(item);
        p.push_back(a);
        p.push_back(0.5 * (a + b));
        const double u = rng.uniform(), v = rng.uniform() * (1.0 - u);
        p.push_back(a + u * (b - a) + v * (c - a));
    }
    // Outside.
    p.emplace_back(b.max.x + 1e-3, b.center().y, b.center().z);
    p.emplace_back(b.min.x - 1e-9, b.min.y, b.min.z);
    p.emplace_back(b.center().x, b.max.y * 10, b.center().z);
    p.emplace_back(1e300, -1e300, 0.0);
    p.emplace_back(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
    return p;
}

/// The ground truth: which items hold a point: a box's or sphere's solid
/// (SceneObject::contains), a triangle's own points (the exact triangle test against the point
/// as a box, no tolerance); each after a slightly widened AABB reject so it stays fast. A mesh
/// object's slot is no item (its triangles are).
class Containment {
public:
    explicit Containment(const Scene& scene) : mScene(scene) {
        for (std::uint32_t i = 0; i < scene.itemCount(); ++i) {
            const std::uint32_t item = scene.item(i);
            if (!scene.isIndexed(item)) {
                continue;
            }
            Aabb b = isTriangleItem(item) ? triangleAabb(scene.triangleCorners(item))
                                          : scene.object(item).aabb();
            b.min -= Vec3(1e-9);
            b.max += Vec3(1e-9);
            mItems.push_back(item);
            mBoxes.push_back(b);
        }
    }
    /// The items holding p, ascending.
    std::vector<std::uint32_t> operator()(const Vec3& p) const {
        std::vector<std::uint32_t> items;
        for (std::size_t k = 0; k < mItems.size(); ++k) {
            if (!mBoxes[k].contains(p)) {
                continue;
            }
            const std::uint32_t item = mItems[k];
            if (isTriangleItem(item)
                    ? overlapsTriangleAabb(mScene.triangleCorners(item), {p, p}, 0.0)
                    : mScene.object(item).contains(p)) {
                items.push_back(item);
            }
        }
        return items;
    }

private:
    const Scene& mScene;
    std::vector<std::uint32_t> mItems;
    std::vector<Aabb> mBoxes;
};

/// Every indexed item's bounds, prepared like the builders do, with its item id.
inline std::vector<std::pair<std::uint32_t, OverlapShape>> itemShapes(const Scene& scene) {
    std::vector<std::pair<std::uint32_t, OverlapShape>> shapes;
    for (std::uint32_t i = 0; i < scene.itemCount(); ++i) {
        const std::uint32_t item = scene.item(i);
        if (scene.isIndexed(item)) {
            shapes.emplace_back(item, OverlapShape::of(scene, item));
        }
    }
    return shapes;
}

/// True when every element of `needles` (sorted) is in `haystack` (sorted).
inline bool includesAll(std::span<const std::uint32_t> haystack,
                        const std::vector<std::uint32_t>& needles) {
    return std::includes(haystack.begin(), haystack.end(), needles.begin(), needles.end());
}

/// True when the point is strictly outside the scene bounds (or NaN).
inline bool clearlyOutside(const Scene& scene, const Vec3& p) {
    return !scene.bounds().contains(p);
}

} // namespace hapto::test
