// The surface a newcomer meets: `hapto --version`, an unknown command named as unknown, and
// the option conventions (--rates with --rate kept, --duration in seconds with soak's
// --minutes kept, --realtime and --no-realtime everywhere, counts as numbers).

#include "TestSupport.h"

#include "hapto/Version.h"

#include <catch2/catch.hpp>

#include <string>

using namespace hapto;

TEST_CASE("hapto --version prints the project's version") {
    const auto r = test::runHapto("--version");
    INFO(r.output);
    CHECK(r.exitCode == 0);
    CHECK(r.output.find(std::string("hapto ") + HAPTO_VERSION_STRING) != std::string::npos);
}

TEST_CASE("an unknown command is named as unknown, exit 2") {
    const auto r = test::runHapto("frobnicate");
    INFO(r.output);
    CHECK(r.exitCode == 2);
    CHECK(r.output.find("hapto: unknown command 'frobnicate'; see hapto --help") !=
          std::string::npos);
    // A known command still runs, and an unknown option is still CLI11's message.
    CHECK(test::runHapto("scene default -o -").exitCode == 0);
    CHECK(test::runHapto("--frobnicate").exitCode == 2);
}

TEST_CASE("options follow one convention, the old spellings still work") {
    test::TempDir dir;
    const std::string out = " --out " + dir.path().string();
    // --rates, and --rate as its old spelling, on every experiment; numbers as numbers.
    for (const std::string args : {
             "experiment devices --quick --no-cursor --max-devices 1 --rates 1000",
             "experiment devices --quick --no-cursor --max-devices 1 --rate 1000 --realtime",
             "experiment devices --quick --max-devices 1 --cursor-objects 1e2 --walk-steps 2e3",
         }) {
        const auto r = test::runHapto(args + out + " --no-realtime");
        INFO(args << "\n" << r.output);
        CHECK(r.exitCode == 0);
    }
    // Counts refused as counts: a fraction, zero where one is needed, a fraction in a list.
    for (const std::string args : {
             "experiment devices --quick --walk-steps 2.5",
             "experiment paper2 --quick --counts 10,2.5",
             "bench query --steps 0",
             "scene random --count 1.5 -o -",
         }) {
        const auto r = test::runHapto(args + (args.rfind("experiment", 0) == 0 ? out : ""));
        INFO(args << "\n" << r.output);
        CHECK(r.exitCode == 2);
    }
    // Soak: --duration in seconds, --minutes kept; not both.
    const auto both = test::runHapto("soak --duration 60 --minutes 1 --no-realtime");
    INFO(both.output);
    CHECK(both.exitCode == 2);
    const auto tooShort = test::runHapto("soak --duration 2 --no-realtime");
    CHECK(tooShort.exitCode == 2);
    CHECK(tooShort.output.find("--duration 2") != std::string::npos);
    const auto tooShortMinutes = test::runHapto("soak --minutes 0.02 --no-realtime");
    CHECK(tooShortMinutes.exitCode == 2);
    CHECK(tooShortMinutes.output.find("--minutes 0.02") != std::string::npos);
}
