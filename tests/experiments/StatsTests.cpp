// The median interval across repeats, against values worked out by hand from its definition,
// and the sweep-list parser (every form, every refusal).

#include "hapto/experiments/Stats.h"

#include "hapto/io/InputError.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

using namespace hapto::experiments;
using Catch::Matchers::Contains;

TEST_CASE("median interval coverage is the Binomial(n, 1/2) mass between the ranks") {
    // n = 5, j = 1: 1 - 2 / 32. n = 6, j = 1: 1 - 2 / 64. n = 9, j = 2: 1 - 2 (1 + 9) / 512.
    CHECK(medianIntervalCoverage(5, 1) == Approx(30.0 / 32.0));
    CHECK(medianIntervalCoverage(6, 1) == Approx(62.0 / 64.0));
    CHECK(medianIntervalCoverage(9, 2) == Approx(492.0 / 512.0));
    CHECK(medianIntervalCoverage(9, 3) == Approx(1.0 - 2.0 * (1 + 9 + 36) / 512.0));
    CHECK(medianIntervalCoverage(1, 1) == 0.0); // [x1, x1] holds the median with probability 0
    CHECK(medianIntervalCoverage(4, 3) == 0.0); // no such interval
}

TEST_CASE("median interval of five runs is min..max at 93.75 percent") {
    const MedianInterval m = medianInterval({5.0, 1.0, 4.0, 2.0, 3.0});
    CHECK(m.n == 5);
    CHECK(m.median == 3.0);
    CHECK(m.lo == 1.0);
    CHECK(m.hi == 5.0);
    CHECK(m.rank == 1);
    CHECK(m.coverage == Approx(0.9375));
}

TEST_CASE("median interval of nine runs is the second smallest to the second largest") {
    // Coverage of j = 2 is 96.1 % >= 95 %, j = 3 only 82.0 %: so x(2) .. x(8).
    const MedianInterval m = medianInterval({9, 8, 7, 6, 5, 4, 3, 2, 1});
    CHECK(m.median == 5.0);
    CHECK(m.lo == 2.0);
    CHECK(m.hi == 8.0);
    CHECK(m.rank == 2);
    CHECK(m.coverage >= 0.95);
}

TEST_CASE("median interval of an even count averages the middle pair and holds the median") {
    const MedianInterval m = medianInterval({10.0, 1.0, 7.0, 3.0, 2.0, 8.0});
    CHECK(m.median == 5.0); // (3 + 7) / 2
    CHECK(m.lo == 1.0);
    CHECK(m.hi == 10.0);
    CHECK(m.coverage == Approx(62.0 / 64.0));
    CHECK(m.lo <= m.median);
    CHECK(m.median <= m.hi);
}

TEST_CASE("median interval drops non-finite values and is empty without any") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const MedianInterval m = medianInterval({nan, 2.0, std::numeric_limits<double>::infinity()});
    CHECK(m.n == 1);
    CHECK(m.median == 2.0);
    CHECK(m.lo == 2.0);
    CHECK(m.hi == 2.0);
    CHECK(m.coverage == 0.0);
    const MedianInterval none = medianInterval({});
    CHECK(none.n == 0);
    CHECK(intervalText(none, 2) == "-");
}

TEST_CASE("interval text and note say the method and the coverage") {
    CHECK(intervalText(medianInterval({1.0, 2.0, 4.0}), 1) == "2.0 [1.0, 4.0]");
    CHECK_THAT(intervalNote(5), Contains("93.75 %"));
    CHECK_THAT(intervalNote(5), Contains("order statistics"));
    CHECK_THAT(intervalNote(9), Contains("96.09 %"));
    CHECK_THAT(intervalNote(1), Contains("no interval"));
}

TEST_CASE("sweep lists: single values, ranges with dash or colon, steps, repeats dropped") {
    CHECK(parseCountList("1,2,3", "--counts", 1, 60) == std::vector<std::int64_t>{1, 2, 3});
    CHECK(parseCountList("1-4", "--counts", 1, 60) == std::vector<std::int64_t>{1, 2, 3, 4});
    CHECK(parseCountList("1:4", "--counts", 1, 60) == std::vector<std::int64_t>{1, 2, 3, 4});
    CHECK(parseCountList("2:8:3", "--counts", 1, 60) == std::vector<std::int64_t>{2, 5, 8});
    CHECK(parseCountList(" 8, 1-3 ,2", "--counts", 1, 60) == std::vector<std::int64_t>{8, 1, 2, 3});
    CHECK(parseCountList("1e3,1e4", "--counts", 1, 1e8) == std::vector<std::int64_t>{1000, 10000});
    CHECK(parseSweepList("1000,2500.5", "--rates", {100, 1e5, false}) ==
          std::vector<double>{1000, 2500.5});
    CHECK(parseSweepList("1000:4000:1000", "--rates", {100, 1e5, false}) ==
          std::vector<double>{1000, 2000, 3000, 4000});
}

TEST_CASE("sweep lists: bad items are refused naming the option and the item") {
    const auto refused = [](const std::string& text, const std::string& why) {
        try {
            (void)parseCountList(text, "--counts", 1, 60);
            FAIL("accepted '" + text + "'");
        } catch (const hapto::InputError& e) {
            CHECK_THAT(e.what(), Contains("--counts '" + text + "'"));
            CHECK_THAT(e.what(), Contains(why));
        }
    };
    refused("", "empty list");
    refused("1,,2", "empty item");
    refused("1,x", "'x' in 'x' is not a number");
    refused("1.5", "not a whole number");
    refused("0", "out of range");
    refused("61", "out of range");
    refused("8-1", "runs backwards");
    refused("1:8:0", "must be above 0");
    refused("1:2:3:4", "not A:B or A:B:STEP");
    refused("nan", "not a number");
    refused("1-", "'' in '1-' is not a number");
    CHECK_THROWS_WITH(parseSweepList("1000:4000", "--rates", {100, 1e5, false}),
                      Contains("needs a step"));
    CHECK_THROWS_WITH(parseCountList("1:100000", "--counts", 1, 1e9),
                      Contains("more than 10000 values"));
}
