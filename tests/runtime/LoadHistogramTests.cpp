#include "hapto/runtime/LoadHistogram.h"

#include <catch2/catch.hpp>

#include <memory>
#include <thread>

using namespace hapto;

TEST_CASE("every value falls in a bucket whose upper bound is within 3.2 % above it") {
    for (std::uint64_t v : {0ull, 1ull, 31ull, 32ull, 33ull, 1000ull, 999'999ull, 1'000'000ull,
                            123'456'789ull, (1ull << 40) + 12345}) {
        const int b = LoadHistogram::bucketOf(v);
        const std::uint64_t upper = LoadHistogram::bucketUpper(b);
        CHECK(upper >= v);
        CHECK(static_cast<double>(upper) <= static_cast<double>(v) * 1.0325 + 1);
        if (b > 0) {
            CHECK(LoadHistogram::bucketUpper(b - 1) < v);
        }
    }
}

TEST_CASE("quantiles of a known distribution") {
    auto h = std::make_unique<LoadHistogram>();
    for (std::uint64_t i = 1; i <= 100000; ++i) {
        h->record(i * 10); // uniform 10 .. 1e6 ns
    }
    const HistogramSummary s = h->summary();
    CHECK(s.count == 100000);
    CHECK(s.mean == Approx(500005.0));
    CHECK(s.max == 1e6);
    CHECK(s.p50 == Approx(500000).epsilon(0.033));
    CHECK(s.p99 == Approx(990000).epsilon(0.033));
    CHECK(s.p999 == Approx(999000).epsilon(0.033));
    CHECK(s.p50 <= s.p99);
    CHECK(s.p99 <= s.p999);
    CHECK(s.p999 <= s.max);
}

TEST_CASE("a reader summarising while the writer records sees counts that only grow", "[threads]") {
    auto h = std::make_unique<LoadHistogram>();
    std::atomic<bool> done{false};
    std::thread writer([&] {
        for (std::uint64_t i = 0; i < 200000; ++i) {
            h->record(i % 5000);
        }
        done = true;
    });
    std::uint64_t last = 0;
    while (!done) {
        const std::uint64_t c = h->summary().count;
        CHECK(c >= last);
        last = c;
    }
    writer.join();
    CHECK(h->summary().count == 200000);
}
