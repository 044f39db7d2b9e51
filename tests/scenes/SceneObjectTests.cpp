#include "hapto/scenes/Scene.h"

#include <catch2/catch.hpp>

#include <glm/gtc/constants.hpp>

using namespace hapto;

TEST_CASE("a rotated box's AABB is tight and its OBB holds its own corners") {
    const Quat q = glm::angleAxis(glm::pi<double>() / 4, Vec3(0, 0, 1));
    const SceneObject box = makeBox(7, Vec3(1, 2, 3), Vec3(0.1, 0.2, 0.3), q);
    const Aabb a = box.aabb();
    const double ex = (0.1 + 0.2) * std::sqrt(0.5);
    CHECK(a.min.x == Approx(1 - ex));
    CHECK(a.max.y == Approx(2 + ex));
    CHECK(a.max.z == Approx(3.3));
    const Obb o = box.obb();
    for (int sx : {-1, 1}) {
        for (int sy : {-1, 1}) {
            const Vec3 corner = o.center + 0.999 * (sx * 0.1 * o.axes[0] + sy * 0.2 * o.axes[1]);
            CHECK(box.contains(corner));
            CHECK(a.contains(corner));
        }
    }
    CHECK_FALSE(box.contains(Vec3(1.0 + 0.25, 2, 3) + Vec3(0.0, 0.0, 0.0) + 0.2 * o.axes[0]));
}

TEST_CASE("a sphere contains its surface and nothing beyond") {
    const SceneObject s = makeSphere(1, Vec3(0), 0.5);
    CHECK(s.contains(Vec3(0.5, 0, 0)));
    CHECK_FALSE(s.contains(Vec3(0.36, 0.36, 0)));
    CHECK(s.aabb().max.z == 0.5);
}

TEST_CASE("a scene finds slots by id and refuses duplicates") {
    const Scene scene(Aabb{Vec3(-1), Vec3(1)},
                      {makeBox(40, Vec3(0), Vec3(0.1)), makeSphere(3, Vec3(0.5), 0.1)});
    REQUIRE(scene.slotOf(3) == 1u);
    REQUIRE(scene.slotOf(40) == 0u);
    REQUIRE_FALSE(scene.slotOf(4).has_value());
    CHECK_THROWS_AS(Scene(Aabb{Vec3(-1), Vec3(1)},
                          {makeBox(1, Vec3(0), Vec3(0.1)), makeBox(1, Vec3(0.2), Vec3(0.1))}),
                    std::invalid_argument);
    CHECK_THROWS_AS(Scene(Aabb{Vec3(1), Vec3(-1)}, {}), std::invalid_argument);
}

TEST_CASE("default bounds hold every object with a little padding") {
    const std::vector<SceneObject> objs{makeBox(0, Vec3(0), Vec3(0.05)),
                                        makeSphere(1, Vec3(0.2, 0, 0), 0.01)};
    const Aabb b = Scene::defaultBounds(objs);
    for (const auto& o : objs) {
        CHECK(b.contains(o.aabb().min));
        CHECK(b.contains(o.aabb().max));
    }
    CHECK(b.max.x > 0.21);
    CHECK(b.max.x < 0.25);
}

TEST_CASE("the render copy is each object's pose and size, and follows a move", "[rendercopy]") {
    const Quat q = glm::normalize(Quat(0.9, 0.1, -0.3, 0.2));
    const std::vector<Vec3> vertices{{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
    const std::vector<TriangleIndices> triangles{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    const auto mesh = TriangleMesh::make(vertices, triangles, {}, "tetrahedron");
    Scene scene(Aabb{Vec3(-1), Vec3(1)},
                {makeBox(1, Vec3(0.1, 0.2, 0.3), Vec3(0.01, 0.02, 0.03), q),
                 makeBox(2, Vec3(-0.1), Vec3(0.01)), makeSphere(3, Vec3(0.2), 0.05),
                 makeMesh(4, Vec3(0.3, -0.2, 0.1), mesh, q)});
    const auto sameObb = [](const Obb& a, const Obb& b) {
        return a.center == b.center && a.halfExtents == b.halfExtents && a.axes == b.axes;
    };
    for (std::uint32_t slot = 0; slot < 3; ++slot) {
        const SceneObject& o = scene.object(slot);
        const RenderBody& b = scene.body(slot);
        CHECK(sameObb(b.obb(), o.obb())); // bit for bit: the solver sees the same box
        CHECK(b.radius == o.radius());
        CHECK(b.shape == o.shape);
    }
    CHECK_FALSE(scene.body(0).axisAligned);
    CHECK(scene.body(1).axisAligned);
    CHECK(scene.body(2).axisAligned);
    CHECK_FALSE(scene.body(3).axisAligned);
    CHECK(scene.body(3).radius == scene.object(3).radius());

    // Each triangle's precomputed plane is the plane through its world corners, outward.
    const auto checkFaces = [&] {
        for (std::uint32_t t = 0; t < scene.triangleCount(); ++t) {
            const std::uint32_t item = kTriangleItemBit | t;
            const auto v = scene.triangleCorners(item);
            const Vec3 n = glm::normalize(glm::cross(v[1] - v[0], v[2] - v[0]));
            const WorldFace f = scene.triangleFace(item);
            CHECK(glm::length(f.normal - n) < 1e-14);
            for (const Vec3& corner : v) {
                CHECK(std::abs(glm::dot(f.normal, corner) - f.offset) < 1e-15);
            }
            const Quat r = scene.object(3).rotation;
            const auto local = mesh->corners(t);
            CHECK(glm::length(v[0] - (scene.object(3).center + r * local[0])) < 1e-15);
        }
    };
    checkFaces();

    // A move updates the copy: the moved box is no longer axis-aligned, the mesh turns back.
    scene.setPose(1, Vec3(0.05), q);
    scene.setPose(3, Vec3(-0.3, 0.2, 0.1), Quat(1, 0, 0, 0));
    CHECK(sameObb(scene.body(1).obb(), scene.object(1).obb()));
    CHECK_FALSE(scene.body(1).axisAligned);
    CHECK(scene.body(3).axisAligned);
    CHECK(scene.body(3).center == Vec3(-0.3, 0.2, 0.1));
    checkFaces();
    const Scene copy = scene; // snapshots copy it with the objects
    CHECK(sameObb(copy.body(1).obb(), scene.object(1).obb()));
}
