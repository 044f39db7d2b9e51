#include "hapto/io/InputError.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/SceneFile.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

using namespace hapto;

TEST_CASE("a lattice has K^3 cubes with gaps, inside bounds a little larger") {
    LatticeOptions opt;
    opt.perSide = 4;
    const Scene s = makeLatticeScene(opt);
    REQUIRE(s.size() == 64);
    for (const SceneObject& o : s.objects()) {
        CHECK(o.halfExtents == Vec3(0.025));
        CHECK(s.bounds().contains(o.aabb().min));
        CHECK(s.bounds().contains(o.aabb().max));
    }
    // Neighbours along x are one pitch apart, so they do not touch.
    CHECK(s.object(1).center.x - s.object(0).center.x == Approx(0.06));
    CHECK(s.bounds().max.x == Approx(2 * 0.06));
}

TEST_CASE("random scenes keep the centre clear and stay inside the work cube") {
    RandomOptions opt;
    opt.count = 400;
    opt.seed = 3;
    opt.rotate = true;
    opt.keepClear = 0.03;
    const Scene s = makeRandomScene(opt);
    REQUIRE(s.size() == 400);
    CHECK(s.bounds().max == Vec3(0.125));
    for (const SceneObject& o : s.objects()) {
        CHECK_FALSE(o.contains(Vec3(0)));
        // No point within keepClear of the centre is inside the cube: sample toward it.
        const Vec3 towards = glm::normalize(o.center) * 0.0299;
        CHECK_FALSE(o.contains(towards));
        const Aabb grown{s.bounds().min - Vec3(1e-9), s.bounds().max + Vec3(1e-9)};
        CHECK(grown.contains(o.aabb().min));
        CHECK(grown.contains(o.aabb().max));
    }
}

TEST_CASE("generators are deterministic: same arguments, same bytes, another seed differs") {
    RandomOptions a;
    a.count = 300;
    a.seed = 42;
    CHECK(sceneToJson(makeRandomScene(a)) == sceneToJson(makeRandomScene(a)));
    RandomOptions b = a;
    b.seed = 43;
    CHECK(sceneToJson(makeRandomScene(a)) != sceneToJson(makeRandomScene(b)));
    ClusterOptions c;
    c.count = 300;
    CHECK(sceneToJson(makeClusterScene(c)) == sceneToJson(makeClusterScene(c)));
    CHECK(sceneToJson(makeDefaultScene()) == sceneToJson(makeDefaultScene()));
}

TEST_CASE("clusters are strongly non-uniform") {
    ClusterOptions c;
    c.count = 5000;
    c.clusters = 4;
    c.seed = 5;
    const Scene s = makeClusterScene(c);
    // Count objects per cell of a 5x5x5 grid: the fullest cell holds far more than 1/125.
    std::vector<int> cells(125, 0);
    for (const SceneObject& o : s.objects()) {
        const Vec3 t = (o.center - s.bounds().min) / s.bounds().size();
        const int ix = std::min(4, int(t.x * 5)), iy = std::min(4, int(t.y * 5)),
                  iz = std::min(4, int(t.z * 5));
        ++cells[(iz * 5 + iy) * 5 + ix];
    }
    CHECK(*std::max_element(cells.begin(), cells.end()) > 10 * 5000 / 125);
}

TEST_CASE("a keep-clear region larger than the work cube is refused") {
    RandomOptions opt;
    opt.count = 10;
    opt.keepClear = 1.0;
    CHECK_THROWS_AS(makeRandomScene(opt), InputError);
}

TEST_CASE("generators refuse lengths that would write non-finite numbers, naming the option") {
    const double inf = std::numeric_limits<double>::infinity();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    LatticeOptions lattice;
    lattice.cubeSize = 1e308;
    lattice.gap = 1e308; // size + gap overflows
    CHECK_THROWS_WITH(makeLatticeScene(lattice),
                      "lattice scene: --size must be a finite length > 0 of at most 1e+06 m, "
                      "got 1e+308");
    lattice = {};
    lattice.gap = inf;
    CHECK_THROWS_WITH(makeLatticeScene(lattice), Catch::StartsWith("lattice scene: --gap must"));
    lattice = {};
    lattice.gap = nan;
    CHECK_THROWS_AS(makeLatticeScene(lattice), InputError);

    RandomOptions random;
    random.count = 10;
    random.workspace = 1e308; // 1 µm rounding of such coordinates overflows
    CHECK_THROWS_WITH(makeRandomScene(random), Catch::StartsWith("random scene: --workspace"));
    random = {};
    random.count = 10;
    random.keepClear = nan;
    CHECK_THROWS_WITH(makeRandomScene(random), Catch::StartsWith("random scene: --keep-clear"));

    ClusterOptions cluster;
    cluster.count = 10;
    cluster.spread = inf;
    CHECK_THROWS_WITH(makeClusterScene(cluster), Catch::StartsWith("cluster scene: --spread"));
    cluster = {};
    cluster.count = 10;
    cluster.cubeSize = -1.0;
    CHECK_THROWS_WITH(makeClusterScene(cluster), Catch::StartsWith("cluster scene: --size"));

    // The largest allowed lengths give finite scenes.
    lattice = {};
    lattice.perSide = 2;
    lattice.cubeSize = kMaxGeneratedLength;
    lattice.gap = kMaxGeneratedLength;
    const Scene big = makeLatticeScene(lattice);
    for (const SceneObject& o : big.objects()) {
        CHECK(std::isfinite(o.center.x + o.center.y + o.center.z));
    }
    CHECK(std::isfinite(big.bounds().max.x - big.bounds().min.x));
}

TEST_CASE("impossible counts are refused before anything is allocated") {
    RandomOptions random;
    random.count = 4'000'000'000; // 448 GB of objects: must fail at once, not in reserve()
    CHECK_THROWS_WITH(makeRandomScene(random),
                      Catch::StartsWith("random scene: --count asks for 4e+09 objects; a "
                                        "generated scene holds at most 1e+08"));
    ClusterOptions cluster;
    cluster.count = kMaxGeneratedObjects + 1;
    CHECK_THROWS_WITH(makeClusterScene(cluster), Catch::StartsWith("cluster scene: --count"));
    LatticeOptions lattice;
    lattice.perSide = 465; // 465^3 > 10^8
    CHECK_THROWS_WITH(makeLatticeScene(lattice),
                      Catch::StartsWith("lattice scene: --per-side (cubed) asks for"));
}

TEST_CASE("a lattice smaller than the 1 um rounding still gets non-empty bounds") {
    LatticeOptions lattice;
    lattice.perSide = 1;
    lattice.cubeSize = 1e-7;
    lattice.gap = 0.0;
    const Scene s = makeLatticeScene(lattice);
    CHECK(s.bounds().max.x == 1e-6);
    CHECK(s.bounds().min.x == -1e-6);
}
