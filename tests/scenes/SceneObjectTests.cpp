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
