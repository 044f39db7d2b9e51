// hapto_bench, hull-contact: what one collide() call costs between a dynamic mesh's convex
// hull and a box, and between two such hulls (the narrow phase's most expensive pairs).
//
// Benchmarks, named hull-contact/box/V and hull-contact/hull/V (V = 12, 24, 48, 96): hulls of
// V random points on a 1 cm sphere (seeded, through convexHullOf, so every point is a corner
// and the faces are triangles: the many-faced case), turned by a fixed rotation; the other
// shape (a 2 cm box, or a second such hull turned another way) above it, its lowest corner
// (the box: its bottom face's centre) 0.5 mm below the hull's highest, so the two overlap and
// collide() runs the separating-axis test to the end and clips. One call per iteration, manual time
// on the steady clock; counters p50_us and points (the manifold's size: the pair was in contact).
//
//   hapto_bench --benchmark_filter='^hull-contact/' --benchmark_min_time=0.5
//               --benchmark_repetitions=5   (one line)

#include "hapto/core/Random.h"
#include "hapto/dynamics/Contact.h"
#include "hapto/experiments/TickBench.h"
#include "hapto/scenes/ConvexHullOf.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

namespace hapto::bench {
namespace {

constexpr double kRadiusM = 0.01;

ConvexHull randomHull(int corners, std::uint64_t seed) {
    Random random(seed);
    std::vector<Vec3> points;
    while (static_cast<int>(points.size()) < corners) {
        const Vec3 p(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1));
        const double len = glm::length(p);
        if (len > 0.1 && len <= 1.0) {
            points.push_back(p * (kRadiusM / len));
        }
    }
    return convexHullOf(points).hull;
}

Mat3 turn(double angle, const Vec3& axis) {
    return glm::mat3_cast(glm::angleAxis(angle, glm::normalize(axis)));
}

void hullContact(benchmark::State& state, bool againstHull, int corners) {
    const ConvexHull a = randomHull(corners, 37);
    const ConvexHull b = randomHull(corners, 38);
    const Mat3 ra = turn(0.4, Vec3(1, 2, 3));
    const Mat3 rb = turn(1.1, Vec3(-2, 1, 1));
    // b's lowest corner 0.5 mm below a's highest, straight above it: they overlap there.
    Vec3 top(0.0, -1.0, 0.0), bottom(0.0, -kRadiusM, 0.0); // the box's bottom face centre
    for (const Vec3& v : a.vertices) {
        top = (ra * v).y > top.y ? ra * v : top;
    }
    if (againstHull) {
        bottom.y = 1.0;
        for (const Vec3& v : b.vertices) {
            bottom = (rb * v).y < bottom.y ? rb * v : bottom;
        }
    }
    const Vec3 above = top - bottom - Vec3(0.0, 5e-4, 0.0);
    const ConvexShape sa = ConvexShape::hullAt(a, Vec3(0.0), ra);
    const ConvexShape sb = againstHull
                               ? ConvexShape::hullAt(b, above, rb)
                               : ConvexShape::box(above, turn(0.3, Vec3(0, 1, 0)), Vec3(kRadiusM));
    ContactManifold m;
    std::vector<double> us;
    us.reserve(1 << 20);
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        collide(sa, sb, 1e-3, m);
        const auto t1 = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(m);
        const double s = std::chrono::duration<double>(t1 - t0).count();
        state.SetIterationTime(s);
        if (us.size() < us.capacity()) {
            us.push_back(1e6 * s);
        }
    }
    state.counters["p50_us"] = experiments::quantilesOf(std::move(us)).p50;
    state.counters["points"] = m.count;
    state.counters["edges"] = static_cast<double>(a.edges.size());
}

const bool gRegistered = [] {
    for (const bool hull : {false, true}) {
        for (const int v : {12, 24, 48, 96}) {
            const std::string name =
                std::string("hull-contact/") + (hull ? "hull/" : "box/") + std::to_string(v);
            benchmark::RegisterBenchmark(name.c_str(), hullContact, hull, v)
                ->UseManualTime()
                ->Unit(benchmark::kMicrosecond);
        }
    }
    return true;
}();

} // namespace
} // namespace hapto::bench
