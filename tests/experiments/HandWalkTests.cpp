// The hand-speed walk shared by hapto_bench, `hapto bench query` and the cursor experiment.

#include "hapto/experiments/HandWalk.h"

#include <catch2/catch.hpp>

#include <vector>

using namespace hapto;

TEST_CASE("the hand walk stays in its box, moves at hand speed and repeats for a seed") {
    const Aabb box{Vec3(-0.05, -0.02, 0.0), Vec3(0.05, 0.02, 0.01)};
    experiments::HandWalk a(box, 3), b(box, 3), c(box, 4);
    Vec3 previous = a.position();
    CHECK(box.contains(previous));
    double travelled = 0.0;
    bool differs = false;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 p = a.next();
        REQUIRE(box.contains(p));
        const double step = glm::length(p - previous);
        REQUIRE(step <= 0.5 * 1e-3 * (1.0 + 1e-12)); // 0.5 m/s for 1 ms
        travelled += step;
        previous = p;
        REQUIRE(b.next() == p);
        differs = differs || c.next() != p;
    }
    CHECK(differs);
    CHECK(travelled > 0.5); // 20 s of motion covers well over half a metre
}

TEST_CASE("makeHandWalk gives the same positions as stepping a walk of the same seed") {
    const Aabb box{Vec3(0.0), Vec3(0.1)};
    const std::vector<Vec3> once = experiments::makeHandWalk(box, 9, 500);
    REQUIRE(once.size() == 500);
    CHECK(experiments::makeHandWalk(box, 9, 500) == once);
    experiments::HandWalk walk(box, 9);
    std::vector<Vec3> stepped;
    for (std::size_t i = 0; i < once.size(); ++i) {
        stepped.push_back(walk.next());
    }
    CHECK(stepped == once);
}

TEST_CASE("a held-back hand stays where it was held, slides along the wall and keeps hand speed") {
    // A wall at x = 0.06 that the hand feels: every step past it is held back onto it.
    const Aabb box{Vec3(0.0), Vec3(0.1)};
    experiments::HandWalk walk(box, 5);
    Vec3 previous = walk.position();
    int held = 0;
    double slidAlongWall = 0.0;
    bool wasHeld = false;
    for (int i = 0; i < 20000; ++i) {
        Vec3 p = walk.next();
        REQUIRE(glm::length(p - previous) <= 0.5 * 1e-3 * (1.0 + 1e-12));
        if (p.x > 0.06) {
            walk.holdBack(Vec3(0.06, p.y, p.z));
            REQUIRE(walk.position() == Vec3(0.06, p.y, p.z));
            if (wasHeld) {
                slidAlongWall += glm::length(Vec3(0.0, p.y - previous.y, p.z - previous.z));
            }
            p = walk.position();
            ++held;
            wasHeld = true;
        } else {
            wasHeld = false;
        }
        previous = p;
    }
    CHECK(held >= 20);            // 50 with this seed
    CHECK(slidAlongWall > 0.001); // pressed against the wall it still moves along it (4 mm)
    // Held back outside the box: the position stays in the box.
    walk.holdBack(Vec3(0.2, -0.1, 0.05));
    CHECK(walk.position() == Vec3(0.1, 0.0, 0.05));
}
