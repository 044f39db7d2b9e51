#include "hapto/runtime/ForceSafety.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

using namespace hapto;

TEST_CASE("the default safety limits are a PHANToM 1.0's peak force and 1 N per tick") {
    const ForceSafety safety;
    CHECK(safety.config().maxForceN == 8.5);
    CHECK(safety.config().maxForceStepN == 1.0);
}

TEST_CASE("small forces pass through unchanged") {
    ForceSafety safety;
    const Vec3 f(0.3, -0.4, 0.5);
    CHECK(safety.filter(f) == f);
    CHECK(safety.filter(f) == f);
    const SafetyCounters c = safety.counters();
    CHECK(c.filtered == 2);
    CHECK(c.clamped == 0);
    CHECK(c.rateLimited == 0);
    CHECK(c.nonFinite == 0);
}

TEST_CASE("a large force is clamped to the maximum along its own direction") {
    ForceSafety safety({3.0, std::numeric_limits<double>::infinity()});
    const Vec3 out = safety.filter(Vec3(0.0, 30.0, 40.0));
    CHECK(glm::length(out) == Approx(3.0));
    CHECK(out.y == Approx(1.8));
    CHECK(out.z == Approx(2.4));
    CHECK(safety.counters().clamped == 1);
    CHECK(safety.counters().rateLimited == 0);
}

TEST_CASE("a jump is spread over ticks at maxForceStepN per tick") {
    ForceSafety safety({8.5, 0.5});
    const Vec3 target(0.0, 0.0, 2.0);
    for (int tick = 1; tick <= 4; ++tick) {
        const Vec3 out = safety.filter(target);
        CHECK(out.z == Approx(0.5 * tick));
    }
    CHECK(safety.counters().rateLimited == 3); // the fourth step is exactly 0.5 N
    CHECK(safety.filter(target).z == Approx(2.0));
    // Reversal: also limited, through zero.
    CHECK(safety.filter(-target).z == Approx(1.5));
    safety.reset();
    CHECK(safety.filter(target).z == Approx(0.5)); // after reset the ramp starts from zero
}

TEST_CASE("a release passes at once: letting go is never rate-limited") {
    ForceSafety safety({8.5, 0.5});
    for (int tick = 0; tick < 20; ++tick) {
        safety.filter(Vec3(0.0, 4.0, 0.0));
    }
    REQUIRE(safety.filter(Vec3(0.0, 4.0, 0.0)).y == Approx(4.0));
    const auto limitedBefore = safety.counters().rateLimited;
    CHECK(safety.filter(Vec3(0.0, 1.0, 0.0)).y == Approx(1.0)); // smaller, same direction
    CHECK(safety.filter(Vec3(0.0)) == Vec3(0.0));               // contact lost
    CHECK(safety.counters().rateLimited == limitedBefore);
    CHECK(safety.filter(Vec3(0.0, 4.0, 0.0)).y == Approx(0.5)); // growing again ramps
}

TEST_CASE("NaN gives zero force, is counted, and the next force ramps from zero") {
    ForceSafety safety({8.5, 1.0});
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    safety.filter(Vec3(0.0, 0.9, 0.0));
    CHECK(safety.filter(Vec3(nan, 0.0, 0.0)) == Vec3(0.0));
    CHECK(safety.filter(Vec3(inf, nan, 0.0)) == Vec3(0.0)); // inf with NaN: no direction
    const SafetyCounters c = safety.counters();
    CHECK(c.nonFinite == 2);
    CHECK(c.overflowed == 0);
    CHECK(c.filtered == 3);
    CHECK(safety.filter(Vec3(0.0, 5.0, 0.0)).y == Approx(1.0));
}

TEST_CASE("an overflowing force is the maximum in its direction, not zero") {
    const double inf = std::numeric_limits<double>::infinity();
    // Rate limiting off: the clamp alone decides.
    ForceSafety safety({8.5, inf});
    CHECK(safety.filter(Vec3(0.0, inf, 0.0)) == Vec3(0.0, 8.5, 0.0));
    CHECK(safety.filter(Vec3(0.0, 0.0, -inf)) == Vec3(0.0, 0.0, -8.5));
    const Vec3 diagonal = safety.filter(Vec3(inf, -inf, 3.0)); // the finite part is negligible
    CHECK(diagonal.x == Approx(8.5 / std::sqrt(2.0)));
    CHECK(diagonal.y == Approx(-8.5 / std::sqrt(2.0)));
    CHECK(diagonal.z == 0.0);
    // Finite components whose length overflows (a 1e200 N/m wall met 1e108 m deep).
    const Vec3 big = safety.filter(Vec3(3e307, 4e307, 0.0));
    CHECK(big.x == Approx(8.5 * 0.6));
    CHECK(big.y == Approx(8.5 * 0.8));
    CHECK(glm::length(big) <= 8.5 + 1e-12);
    const SafetyCounters c = safety.counters();
    CHECK(c.overflowed == 4);
    CHECK(c.clamped == 4);
    CHECK(c.nonFinite == 0);
}

TEST_CASE("an overflowing force still ramps at the rate limit from the last force") {
    const double inf = std::numeric_limits<double>::infinity();
    ForceSafety safety({8.5, 1.0});
    CHECK(safety.filter(Vec3(inf, 0.0, 0.0)).x == Approx(1.0));
    CHECK(safety.filter(Vec3(inf, 0.0, 0.0)).x == Approx(2.0));
    CHECK(safety.counters().rateLimited == 2);
}

TEST_CASE("the output never exceeds the maximum, whatever comes in") {
    ForceSafety safety({2.0, 0.7});
    double worst = 0.0;
    std::uint64_t state = 12345;
    for (int i = 0; i < 20000; ++i) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        const double scale = static_cast<double>(state >> 40) / static_cast<double>(1 << 24);
        const Vec3 f(scale * 20 - 10, std::sin(i * 0.37) * 30.0, (i % 7) - 3.0);
        worst = std::max(worst, glm::length(safety.filter(f)));
    }
    CHECK(worst <= 2.0 + 1e-12);
}

TEST_CASE("bad limits are refused at construction") {
    CHECK_THROWS_AS(ForceSafety({0.0, 1.0}), std::invalid_argument);
    CHECK_THROWS_AS(ForceSafety({-1.0, 1.0}), std::invalid_argument);
    CHECK_THROWS_AS(ForceSafety({std::numeric_limits<double>::quiet_NaN(), 1.0}),
                    std::invalid_argument);
    CHECK_THROWS_AS(ForceSafety({8.5, 0.0}), std::invalid_argument);
}

TEST_CASE("a copied filter keeps its counters") {
    ForceSafety a({1.0, 10.0});
    a.filter(Vec3(5.0, 0.0, 0.0));
    const ForceSafety b = a;
    CHECK(b.counters().clamped == 1);
    CHECK(b.lastForce() == a.lastForce());
}
