// hapto::experiments' soak, in process: the pieces of its verdict and its refusal of a soak that
// could test nothing. (The whole soak runs in tests/tools/SoakCommandTests.cpp.)

#include "hapto/experiments/Soak.h"
#include "hapto/io/InputError.h"

#include <catch2/catch.hpp>

using namespace hapto;
using namespace hapto::experiments;

TEST_CASE("soak: the drift and memory trend is the least-squares slope, per hour") {
    // y = 2 + 0.5 x (x in s): 0.5 per second is 1800 per hour, whatever the noise-free offset.
    const std::vector<double> x{0, 10, 20, 30, 40};
    std::vector<double> y;
    for (double t : x) {
        y.push_back(2.0 + 0.5 * t);
    }
    CHECK(slopePerHour(x, y) == Approx(1800.0));
    // Symmetric scatter about a flat line has no trend.
    CHECK(slopePerHour({0, 1, 2, 3}, {1, -1, -1, 1}) == Approx(0.0).margin(1e-12));
    // Too few points, or no spread in x: no slope rather than a division by zero.
    CHECK(slopePerHour({5}, {3}) == 0.0);
    CHECK(slopePerHour({2, 2, 2}, {1, 2, 3}) == 0.0);
}

TEST_CASE("soak: a soak that would end before its first fault is refused, naming the option") {
    SoakOptions o;
    o.durationS = 10.0;
    o.faultEveryS = 15.0;
    o.durationOption = "--duration 10";
    CHECK_THROWS_AS(checkSoakOptions(o), InputError);
    CHECK_THROWS_WITH(checkSoakOptions(o),
                      Catch::Contains("--duration 10") && Catch::Contains("first fault"));
    // Faults stop a quiet tail before the end (3 watchdogs + 1 s + a reopen), so the last can
    // recover: long enough for one fault and its tail, it is accepted.
    o.durationS = 60.0;
    CHECK(soakQuietTailS(o) == Approx(3 * 0.05 + 1.0 + 1.0));
    CHECK_NOTHROW(checkSoakOptions(o));
    o.faultEveryS = 60.0 - soakQuietTailS(o);
    CHECK_THROWS_AS(checkSoakOptions(o), InputError);
}
