#include "hapto/core/Clock.h"
#include "hapto/core/CpuPause.h"
#include "hapto/core/Finite.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <cstdint>
#include <ctime>
#include <limits>

using namespace hapto;

TEST_CASE("clock: monotonicNs never goes back and is the clock steady_clock reads") {
    const auto toNs = [](std::chrono::steady_clock::time_point t) {
        return static_cast<std::uint64_t>(
            std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count());
    };
    std::uint64_t last = monotonicNs();
    for (int i = 0; i < 1000; ++i) {
        const std::uint64_t before = toNs(std::chrono::steady_clock::now());
        const std::uint64_t now = monotonicNs();
        cpuPause();
        const std::uint64_t after = toNs(std::chrono::steady_clock::now());
        REQUIRE(now >= last);
        REQUIRE(before <= now);
        REQUIRE(now <= after);
        last = now;
    }
}

TEST_CASE("clock: threadCpuNs never goes back and is this thread's CPU clock") {
    const auto cpuNow = [] {
        timespec t{};
        clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
        return static_cast<std::uint64_t>(t.tv_sec) * 1'000'000'000ull +
               static_cast<std::uint64_t>(t.tv_nsec);
    };
    std::uint64_t last = threadCpuNs();
    for (int i = 0; i < 1000; ++i) {
        const std::uint64_t before = cpuNow();
        const std::uint64_t now = threadCpuNs();
        const std::uint64_t after = cpuNow();
        REQUIRE(now >= last);
        REQUIRE(before <= now);
        REQUIRE(now <= after);
        last = now;
    }
}

TEST_CASE("finite: false when any component is NaN or infinite") {
    CHECK(finite(Vec3(0.0, -1.5, 1e300)));
    const double bad[] = {std::numeric_limits<double>::quiet_NaN(),
                          std::numeric_limits<double>::infinity(),
                          -std::numeric_limits<double>::infinity()};
    for (const double b : bad) {
        for (int axis = 0; axis < 3; ++axis) {
            Vec3 v(1.0);
            v[axis] = b;
            CHECK_FALSE(finite(v));
        }
    }
}
