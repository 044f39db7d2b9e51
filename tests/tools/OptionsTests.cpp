// The finite-range check every numeric option goes through (tools/src/Options.h), in process.

#include "Options.h"

#include <catch2/catch.hpp>

#include <cstdint>
#include <string>
#include <vector>

using namespace hapto::cli;

namespace {

/// Parses `--x VALUE` into a double option checked by finiteRange(lo, hi); the error or "".
template <class T> std::string parse(const std::string& value, double lo, double hi) {
    CLI::App app;
    T x{};
    app.add_option("--x", x)->check(finiteRange(lo, hi));
    std::vector<std::string> args{value, "--x"}; // CLI11 takes them in reverse
    try {
        app.parse(args);
    } catch (const CLI::ParseError& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST_CASE("finiteRange refuses NaN, infinities, text and values out of range, naming them") {
    for (const char* bad : {"nan", "NaN", "-nan", "inf", "-inf", "infinity", "1e400"}) {
        INFO(bad);
        const std::string error = parse<double>(bad, 0, 10);
        CHECK_THAT(error, Catch::Contains("--x") && Catch::Contains(bad) &&
                              Catch::Contains("from 0 to 10"));
    }
    CHECK_THAT(parse<double>("ten", 0, 10), Catch::Contains("not a number"));
    CHECK_THAT(parse<double>("10.5", 0, 10), Catch::Contains("out of range"));
    CHECK_THAT(parse<double>("-0.1", 0, 10), Catch::Contains("out of range"));
    CHECK(parse<double>("0", 0, 10).empty());
    CHECK(parse<double>("10", 0, 10).empty());
    CHECK(parse<double>("2.5e0", 0, 10).empty());
}

TEST_CASE("finiteRange on integer options also catches negatives an unsigned option would wrap") {
    CHECK_THAT(parse<std::uint64_t>("-1", 0, kMaxSeed), Catch::Contains("out of range"));
    CHECK(parse<std::uint64_t>("18446744073709551615", 0, kMaxSeed).empty());
    CHECK_THAT(parse<int>("nan", 1, 32), Catch::Contains("--x"));
    CHECK_THAT(parse<int>("33", 1, 32), Catch::Contains("from 1 to 32"));
    CHECK(parse<int>("32", 1, 32).empty());
}
