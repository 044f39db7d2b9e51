// Pure tests of the Falcon kinematics: IK/FK round trips, the Jacobian, motor words.
#include "hapto/devices/FalconKinematics.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace hapto;
using namespace hapto::falcon;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// A grid over the reachable workspace (mechanism frame, m): +-4 cm across, z 8..15 cm.
template <class F> void forWorkspace(F&& f) {
    for (double x = -0.04; x <= 0.04 + 1e-9; x += 0.01) {
        for (double y = -0.04; y <= 0.04 + 1e-9; y += 0.01) {
            for (double z = 0.08; z <= 0.15 + 1e-9; z += 0.01) {
                f(Vec3(x, y, z));
            }
        }
    }
}

} // namespace

TEST_CASE("encoder counts map to arm angles: 35 degrees at zero, ~0.0364 degrees per count",
          "[kinematics]") {
    CHECK(FalconKinematics::encoderToAngle(0) == Approx(35.0 * kPi / 180.0));
    const double perCount =
        FalconKinematics::encoderToAngle(1) - FalconKinematics::encoderToAngle(0);
    CHECK(perCount * 180.0 / kPi == Approx((0.01425 / 1280.0) / (0.110 / 360.0)));
    for (std::int16_t c :
         {std::int16_t{-3000}, std::int16_t{0}, std::int16_t{17}, std::int16_t{2500}}) {
        CHECK(FalconKinematics::angleToEncoder(FalconKinematics::encoderToAngle(c)) == c);
    }
    CHECK(FalconKinematics::angleToEncoder(1e9) == 32767);
    CHECK(FalconKinematics::angleToEncoder(-1e9) == -32768);
}

TEST_CASE("FK(IK(p)) == p over the workspace, from the default start", "[kinematics]") {
    const FalconKinematics k;
    int checked = 0;
    forWorkspace([&](const Vec3& p) {
        const auto angles = k.inverse(p);
        REQUIRE(angles.has_value());
        const auto back = k.forward(*angles);
        REQUIRE(back.has_value());
        CHECK(glm::length(*back - p) < 1e-9);
        const Vec3 res = k.residual(p, *angles);
        CHECK(std::abs(res.x) + std::abs(res.y) + std::abs(res.z) < 1e-12);
        ++checked;
    });
    CHECK(checked == 9 * 9 * 8);
}

TEST_CASE("FK from a warm start next door converges to the same point", "[kinematics]") {
    const FalconKinematics k;
    const Vec3 p(0.013, -0.021, 0.142);
    const auto angles = k.inverse(p);
    REQUIRE(angles);
    const auto back = k.forward(*angles, p + Vec3(0.002, -0.001, 0.003));
    REQUIRE(back);
    CHECK(glm::length(*back - p) < 1e-9);
}

TEST_CASE("IK refuses out-of-reach points and FK refuses non-finite angles", "[kinematics]") {
    const FalconKinematics k;
    CHECK_FALSE(k.inverse(Vec3(0, 0, 0.5)).has_value());
    CHECK_FALSE(k.inverse(Vec3(0.3, 0, 0.1)).has_value());
    CHECK_FALSE(k.inverseLeg(3, Vec3(0, 0, 0.12)).has_value());
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CHECK_FALSE(k.forward({nan, 0.5, 0.5}).has_value());
}

TEST_CASE("the Jacobian matches finite differences of FK", "[kinematics]") {
    const FalconKinematics k;
    const double h = 1e-6;
    forWorkspace([&](const Vec3& p) {
        if (std::fmod(std::round(p.z * 100), 2) != 0) {
            return; // every other layer is plenty
        }
        const auto a = k.inverse(p);
        REQUIRE(a);
        const auto j = k.jacobian(p, *a);
        REQUIRE(j);
        for (std::size_t col = 0; col < 3; ++col) {
            Angles up = *a, down = *a;
            up[col] += h;
            down[col] -= h;
            const auto pu = k.forward(up, p);
            const auto pd = k.forward(down, p);
            REQUIRE(pu);
            REQUIRE(pd);
            const Vec3 fd = (*pu - *pd) / (2 * h);
            const Vec3 an = (*j)[static_cast<int>(col)];
            CHECK(glm::length(fd - an) < 1e-6 * (1.0 + glm::length(an)));
        }
    });
}

TEST_CASE("force to torque is J^T F, and does the same work as the force", "[kinematics]") {
    const FalconKinematics k;
    const Vec3 p(0.01, 0.02, 0.13);
    const auto a = k.inverse(p);
    REQUIRE(a);
    const auto j = k.jacobian(p, *a);
    REQUIRE(j);
    const Vec3 f(1.5, -2.0, 3.0);
    const Vec3 tau = FalconKinematics::forceToTorque(*j, f);
    // Virtual work: tau . dtheta == F . dp for dp = J dtheta.
    const Vec3 dtheta(0.001, -0.002, 0.0015);
    const Vec3 dp = (*j) * dtheta;
    CHECK(glm::dot(tau, dtheta) == Approx(glm::dot(f, dp)).epsilon(1e-12));
}

TEST_CASE("motor words are -tau * 1e4, scaled down together over the limit, clamped to int16",
          "[kinematics]") {
    CHECK(FalconKinematics::torqueToMotorWord(0.1234) == -1234);
    CHECK(FalconKinematics::torqueToMotorWord(-0.5) == 5000);
    CHECK(FalconKinematics::torqueToMotorWord(10.0) == -32768);
    CHECK(FalconKinematics::torqueToMotorWord(-10.0) == 32767);
    CHECK(FalconKinematics::torqueToMotorWord(std::numeric_limits<double>::quiet_NaN()) == 0);
    CHECK(FalconKinematics::torqueToMotorWord(std::numeric_limits<double>::infinity()) == -32768);

    const MotorWords within = FalconKinematics::torqueToMotorWords(Vec3(0.1, -0.2, 0.3));
    CHECK(within == MotorWords{-1000, 2000, -3000});

    // Over a 1000-count limit: words {-1e4, 2e4, -4e4} are scaled by 1000 / 4e4 together.
    const MotorWords scaled = FalconKinematics::torqueToMotorWords(Vec3(1.0, -2.0, 4.0), 1000);
    CHECK(scaled == MotorWords{-250, 500, -1000});
    // The default limit is 4096 counts (the public headers' cap), not what an int16 can say.
    CHECK(kDefaultMotorWordLimit == 4096);
    const MotorWords big = FalconKinematics::torqueToMotorWords(Vec3(100.0, 50.0, -25.0));
    CHECK(big == MotorWords{-4096, -2048, 1024});
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CHECK(FalconKinematics::torqueToMotorWords(Vec3(nan, 1, 1)) == MotorWords{0, 0, 0});
    CHECK(FalconKinematics::torqueToMotorWords(Vec3(1, std::numeric_limits<double>::infinity(), 1),
                                               4096) == MotorWords{0, 0, 0});
}

TEST_CASE("over the word limit, the three words keep their ratios and the largest is the limit",
          "[kinematics]") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> torque(-5.0, 5.0); // up to 50000 counts
    for (const int limit : {1, 1000, 4095, 4096, 32767}) {
        for (int trial = 0; trial < 2000; ++trial) {
            const Vec3 tau(torque(rng), torque(rng), torque(rng));
            const MotorWords w = FalconKinematics::torqueToMotorWords(tau, limit);
            const Vec3 raw = -tau * kMotorWordPerNm;
            const double largest = std::max({std::abs(raw.x), std::abs(raw.y), std::abs(raw.z)});
            const double scale = largest > limit ? limit / largest : 1.0;
            INFO("limit " << limit << " tau " << tau.x << ", " << tau.y << ", " << tau.z);
            int biggest = 0;
            for (int i = 0; i < 3; ++i) {
                // Each word is the raw word times one common factor, rounded: same direction.
                CHECK(std::abs(w[static_cast<std::size_t>(i)] - raw[i] * scale) <= 0.5 + 1e-9);
                biggest = std::max(biggest, std::abs(int{w[static_cast<std::size_t>(i)]}));
            }
            CHECK(biggest <= limit);
            if (largest > limit) {
                CHECK(biggest == limit);
            }
        }
    }
}
