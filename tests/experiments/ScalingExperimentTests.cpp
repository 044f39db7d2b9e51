// `runDevices` (hapto experiment scaling) over a few wall-clock runs: the device counts asked
// are the ones run, and every cell reports its median with an interval that holds it, for the
// load sum, the median device and the worst device, in CSV, JSON and markdown.

#include "hapto/experiments/Experiments.h"
#include "hapto/experiments/Stats.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

using namespace hapto;
using namespace hapto::experiments;

namespace {

std::string slurp(const std::filesystem::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

} // namespace

TEST_CASE("experiment scaling: the counts asked, each cell's median inside its interval",
          "[realtime]") {
    test::TempDir dir;
    DevicesArgs a;
    a.common.out = dir.path().string();
    a.common.quick = true;
    a.common.durationS = 0.05;
    a.common.repeats = 3;
    a.common.realtime = false;
    a.deviceCounts = {1, 3};
    a.ratesHz = {1000.0};
    a.cursor = false;
    REQUIRE(runDevices(a) == 0);

    const auto j = nlohmann::json::parse(slurp(dir / "devices.json"));
    CHECK(j["options"]["device_counts"] == nlohmann::json::array({1, 3}));
    CHECK(j["options"]["interval_coverage"].get<double>() == Approx(0.75)); // [min, max] of 3
    REQUIRE(j["devices"].size() == 2);
    for (std::size_t i = 0; i < 2; ++i) {
        const auto& row = j["devices"][i];
        INFO("row " << i);
        CHECK(row["devices"] == (i == 0 ? 1 : 3));
        CHECK(row["repeats"] == 3);
        CHECK(row["per_device"].size() == 3 * (i == 0 ? 1u : 3u)); // every device of every run
        for (const char* f : {"load_sum", "median_device_p999", "worst_load_p999"}) {
            INFO(f);
            const std::string name(f);
            const double lo = row[name + "_lo_pct"], hi = row[name + "_hi_pct"];
            CHECK(lo <= row[name + "_pct"].get<double>());
            CHECK(row[name + "_pct"].get<double>() <= hi);
        }
        // The median device is never above the worst one, run by run, so neither are medians.
        CHECK(row["median_device_p999_pct"].get<double>() <=
              row["worst_load_p999_pct"].get<double>());
        CHECK(row["interval_coverage"].get<double>() == Approx(0.75));
        // The median over the runs is the middle of the runs' load sums.
        std::vector<double> sums;
        for (int k = 0; k < 3; ++k) {
            double sum = 0;
            for (const auto& d : row["per_device"]) {
                if (d["repeat"] == k) {
                    sum += d["load_mean_pct"].get<double>();
                }
            }
            sums.push_back(sum);
        }
        CHECK(row["load_sum_pct"].get<double>() ==
              Approx(medianInterval(sums).median).margin(1e-6));
    }
    const std::string md = slurp(dir / "devices.md");
    CHECK_THAT(md, Catch::Contains("load sum % (one core), median [interval]"));
    CHECK_THAT(md, Catch::Contains("median device p99.9 % [interval]"));
    CHECK_THAT(md, Catch::Contains("worst device p99.9 % [interval]"));
    CHECK_THAT(md, Catch::Contains("75 %"));
    CHECK_THAT(md, Catch::Contains("**Smoke test (--quick)**"));
    const std::string csv = slurp(dir / "devices.csv");
    for (const char* column : {"load_sum_lo_pct", "median_device_p999_pct", "interval_coverage"}) {
        CHECK_THAT(csv.substr(0, csv.find('\n')), Catch::Contains(column));
    }
}
