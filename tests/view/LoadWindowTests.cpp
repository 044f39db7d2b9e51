// The load over the last second, from the lifetime histogram.

#include "hapto/view/LoadWindow.h"

#include <catch2/catch.hpp>

using namespace hapto;

namespace {
constexpr std::uint64_t kS = 1'000'000'000;
double upper(std::uint64_t ns) {
    return static_cast<double>(LoadHistogram::bucketUpper(LoadHistogram::bucketOf(ns)));
}
} // namespace

TEST_CASE("the load window holds only the last second's ticks") {
    const double periodNs = 1e6; // 1 kHz
    LoadHistogram h;
    LoadWindow window(periodNs, kS, 32);
    CHECK(window.sample(h, 0).ticks == 0);

    for (int i = 0; i < 1000; ++i) {
        h.record(500'000); // half the period
    }
    WindowLoad w = window.sample(h, kS / 2);
    CHECK(w.ticks == 1000);
    CHECK(w.p50 == Approx(upper(500'000) / periodNs));
    CHECK(w.p50 >= 0.5);
    CHECK(w.p50 <= 0.5 * 1.032);
    CHECK(w.spanS == Approx(0.5));

    // A second and a half later the heavy ticks have left the window.
    for (int i = 0; i < 1000; ++i) {
        h.record(100'000);
    }
    window.sample(h, kS); // a copy inside the next window
    for (int i = 0; i < 1000; ++i) {
        h.record(100'000);
    }
    w = window.sample(h, 2 * kS);
    CHECK(w.ticks == 1000);
    CHECK(w.p50 == Approx(upper(100'000) / periodNs));
    CHECK(w.p999 == Approx(upper(100'000) / periodNs));
    CHECK(w.spanS == Approx(1.0));
}

TEST_CASE("the load window's p99.9 sees one slow tick in a thousand") {
    LoadHistogram h;
    LoadWindow window(1e6, kS, 32);
    window.sample(h, 0);
    for (int i = 0; i < 998; ++i) {
        h.record(100'000);
    }
    h.record(2'000'000);
    h.record(2'000'000); // two in a thousand: above the 99.9th rank
    const WindowLoad w = window.sample(h, kS / 10);
    CHECK(w.ticks == 1000);
    CHECK(w.p50 == Approx(upper(100'000) / 1e6));
    CHECK(w.p999 == Approx(upper(2'000'000) / 1e6));
    CHECK(w.p999 > 1.0); // over the period: the chart's red line crosses 100 %
}

TEST_CASE("the load window refuses a period that is not positive") {
    CHECK_THROWS(LoadWindow(0.0, kS, 4));
    CHECK_THROWS(LoadWindow(std::nan(""), kS, 4));
}
