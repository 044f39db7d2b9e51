#include "IndexTestScenes.h"

#include "hapto/index/Cursor.h"

#include <catch2/catch.hpp>

#include <thread>

using namespace hapto;
using namespace hapto::test;

TEST_CASE("several threads querying one index at once get what one thread gets", "[threads]") {
    ClusterOptions c;
    c.count = 3000;
    c.rotate = true;
    const Scene scene = makeClusterScene(c);
    for (const IndexSpec& spec :
         {IndexSpec::octree(2, 0.002), IndexSpec::grid(8), IndexSpec::brute()}) {
        INFO(spec.toString());
        const auto index = buildIndex(scene, spec);
        const std::vector<Vec3> points = queryPoints(scene, 21, 3000);
        struct Answer {
            std::uint32_t leaf;
            const std::uint32_t* data;
            std::size_t size;
            bool operator==(const Answer&) const = default;
        };
        std::vector<Answer> expected;
        for (const Vec3& p : points) {
            const LocateResult r = index->locate(p);
            expected.push_back({r.leaf, r.candidates.data(), r.candidates.size()});
        }
        constexpr int kThreads = 4;
        std::vector<std::size_t> mismatches(kThreads, 0);
        std::vector<std::thread> threads;
        for (int t = 0; t < kThreads; ++t) {
            threads.emplace_back([&, t] {
                Cursor cursor(*index, static_cast<CursorStrategy>(t % 3));
                for (int round = 0; round < 3; ++round) {
                    for (std::size_t k = 0; k < points.size(); ++k) {
                        // Each thread walks the points in its own order.
                        const std::size_t i = (k * (2 * t + 1) + round) % points.size();
                        const LocateResult a = cursor.locate(points[i]);
                        const LocateResult b = index->locate(points[i]);
                        const Answer got{a.leaf, a.candidates.data(), a.candidates.size()};
                        const Answer fresh{b.leaf, b.candidates.data(), b.candidates.size()};
                        mismatches[t] += !(got == expected[i]) || !(fresh == expected[i]);
                    }
                }
            });
        }
        for (std::thread& th : threads) {
            th.join();
        }
        for (int t = 0; t < kThreads; ++t) {
            CHECK(mismatches[t] == 0);
        }
    }
}
