// `hapto bench query` and `hapto bench tick` (their hand walk:
// tests/experiments/HandWalkTests.cpp). Behaviour only: nothing here depends on how fast anything
// runs.

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iterator>
#include <string>
#include <unistd.h>

using namespace hapto;
using nlohmann::json;

namespace {

/// Writes a small random scene (60 cubes of 2 cm) with the generator command.
std::string makeScene(const test::TempDir& dir) {
    const std::string path = (dir / "scene.json").string();
    const auto r = test::runHapto("scene random --count 60 --seed 5 --size 0.02 -o " + path);
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    return path;
}

json runJson(const std::string& args) {
    const auto r = test::runHapto("bench query " + args + " --json");
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    return json::parse(r.output);
}

} // namespace

TEST_CASE("hapto bench query --json reports every index over the same walk", "[threads]") {
    test::TempDir dir;
    const std::string scene = makeScene(dir);
    const json j = runJson("--scene " + scene +
                           " --steps 2000 --index brute --index grid:4 --index octree:2:0.005");
    REQUIRE(j.is_array());
    REQUIRE(j.size() == 3);
    CHECK(j[0]["index"] == "brute");
    CHECK(j[1]["index"] == "grid:4");
    CHECK(j[2]["index"] == "octree:2:0.005");
    for (const json& e : j) {
        INFO(e.dump());
        for (const char* key : {"index", "objects", "steps", "ns_p50", "ns_p999", "ns_mean",
                                "locate_steps_mean", "candidates_mean"}) {
            CHECK(e.contains(key));
        }
        CHECK(e.size() == 8);
        CHECK(e["objects"] == 60);
        CHECK(e["steps"] == 2000);
        CHECK(e["ns_p50"].get<double>() >= 0.0);
        CHECK(e["ns_p50"].get<double>() <= e["ns_p999"].get<double>());
        CHECK(e["ns_mean"].get<double>() >= 0.0);
        CHECK(e["locate_steps_mean"].get<double>() >= 0.0);
        CHECK(e["candidates_mean"].get<double>() >= 0.0);
        CHECK(e["candidates_mean"].get<double>() <= 60.0);
    }
    // The walk stays inside the bounds, so brute force hands over every object every time.
    CHECK(j[0]["candidates_mean"].get<double>() == 60.0);
    CHECK(j[0]["locate_steps_mean"].get<double>() == 0.0);
    // A partition hands over fewer.
    CHECK(j[1]["candidates_mean"].get<double>() < 60.0);
    CHECK(j[2]["candidates_mean"].get<double>() < 60.0);
}

TEST_CASE("hapto bench query: every cursor strategy finds the same leaves along the walk",
          "[threads]") {
    test::TempDir dir;
    const std::string scene = makeScene(dir);
    const json j = runJson("--scene " + scene +
                           " --steps 3000 --seed 9 --index octree:2:0.005@root"
                           " --index octree:2:0.005@climb --index octree:2:0.005@links"
                           " --index octree:2:0.005");
    REQUIRE(j.size() == 4);
    CHECK(j[0]["index"] == "octree:2:0.005@root");
    CHECK(j[1]["index"] == "octree:2:0.005@climb");
    CHECK(j[2]["index"] == "octree:2:0.005@links");
    CHECK(j[3]["index"] == "octree:2:0.005");
    // Same walk, same leaves: the candidate counts agree exactly, whatever the strategy.
    for (std::size_t i = 1; i < j.size(); ++i) {
        CHECK(j[i]["candidates_mean"] == j[0]["candidates_mean"]);
    }
    // Plain spec means neighbour links: the same path, the same steps.
    CHECK(j[3]["locate_steps_mean"] == j[2]["locate_steps_mean"]);
    // From the root, every query walks down at least one level in a tree that split.
    CHECK(j[0]["locate_steps_mean"].get<double>() >= 1.0);
}

TEST_CASE("hapto bench query: the same seed walks the same path", "[threads]") {
    test::TempDir dir;
    const std::string scene = makeScene(dir);
    const std::string args = "--scene " + scene + " --steps 2500 --seed 4 --index grid:3";
    const json a = runJson(args);
    const json b = runJson(args);
    CHECK(a[0]["candidates_mean"] == b[0]["candidates_mean"]);
    const json c = runJson("--scene " + scene + " --steps 2500 --seed 5 --index grid:3");
    CHECK(c[0]["steps"] == 2500);
}

TEST_CASE("hapto bench query runs on the default scene and prints a table", "[threads]") {
    const auto r = test::runHapto("bench query --steps 1500 --batch 1");
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK_THAT(r.output, Catch::Contains("200 objects"));
    CHECK_THAT(r.output, Catch::Contains("p99.9 ns"));
    CHECK_THAT(r.output, Catch::Contains("brute"));
    CHECK_THAT(r.output, Catch::Contains("grid:5"));
    CHECK_THAT(r.output, Catch::Contains("octree:2:0.005"));
}

TEST_CASE("hapto bench query refuses bad index specs and options with exit code 2") {
    SECTION("unknown index") {
        const auto r = test::runHapto("bench query --steps 100 --index kdtree:3");
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("kdtree:3"));
    }
    SECTION("bad grid size") {
        const auto r = test::runHapto("bench query --steps 100 --index brute --index grid:0");
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("grid:0"));
    }
    SECTION("unknown cursor strategy") {
        const auto r = test::runHapto("bench query --steps 100 --index octree:2:0.005@sideways");
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("sideways"));
        CHECK_THAT(r.output, Catch::Contains("@climb"));
    }
    SECTION("no steps") {
        const auto r = test::runHapto("bench query --steps 0");
        CHECK(r.exitCode == 2);
    }
    SECTION("missing scene file") {
        const auto r = test::runHapto("bench query --steps 100 --scene /nonexistent/s.json");
        CHECK(r.exitCode == 2);
    }
}

namespace {

constexpr const char* kTickStages[] = {"read",    "snapshot", "locate", "candidates", "render",
                                       "effects", "safety",   "write",  "metrics"};

/// Runs `hapto bench tick ARGS --json OUT` and returns the file's JSON.
json runTickJson(const test::TempDir& dir, const std::string& args) {
    const std::string out = (dir / "tick.json").string();
    const auto r = test::runHapto("bench tick " + args + " --json " + out);
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    return json::parse(test::readFile(out));
}

/// The structure and the invariants of one bench tick entry: every stage, ordered quantiles,
/// each stage no slower than the whole tick at the same quantile (every tick's stages lie
/// inside it), and the stage means adding up to the tick's mean (the stages tile the tick).
void checkTickEntry(const json& e, std::size_t ticks) {
    INFO(e.dump());
    for (const char* key : {"index", "mode", "objects", "ticks", "sleep_us", "warm_us",
                            "wake_latency_us", "device", "stages", "tick", "locate_steps_mean",
                            "candidates_mean", "contact_fraction", "warm_overruns", "start_late"}) {
        CHECK(e.contains(key));
    }
    CHECK(e["ticks"] == ticks);
    // Only a warmed mode has a warm-up to overrun; at most every tick's.
    if (e["warm_us"].get<double>() == 0.0) {
        CHECK(e["warm_overruns"] == 0);
    }
    CHECK(e["warm_overruns"].get<std::uint64_t>() <= ticks);
    // How late each tick after a sleep started: none for back-to-back ticks.
    const json& late = e["start_late"];
    CHECK(late["ns_p50"].get<double>() >= 0.0);
    CHECK(late["ns_p50"].get<double>() <= late["ns_p99"].get<double>());
    CHECK(late["ns_p99"].get<double>() <= late["ns_p999"].get<double>());
    if (e["mode"] == "hot") {
        CHECK(late["ns_p999"].get<double>() == 0.0);
    }
    const json& tick = e["tick"];
    CHECK(tick["ns_p50"].get<double>() >= 0.0);
    CHECK(tick["ns_p50"].get<double>() <= tick["ns_p99"].get<double>());
    CHECK(tick["ns_p99"].get<double>() <= tick["ns_p999"].get<double>());
    REQUIRE(e["stages"].size() == std::size(kTickStages));
    double meanSum = 0.0, medianSum = 0.0;
    for (const char* name : kTickStages) {
        INFO(name);
        REQUIRE(e["stages"].contains(name));
        const json& s = e["stages"][name];
        CHECK(s["ns_p50"].get<double>() >= 0.0);
        CHECK(s["ns_p50"].get<double>() <= s["ns_p99"].get<double>());
        CHECK(s["ns_p99"].get<double>() <= s["ns_p999"].get<double>());
        for (const char* q : {"ns_p50", "ns_p99", "ns_p999", "ns_mean"}) {
            CHECK(s[q].get<double>() <= tick[q].get<double>());
        }
        meanSum += s["ns_mean"].get<double>();
        medianSum += s["ns_p50"].get<double>();
    }
    CHECK(meanSum == Approx(tick["ns_mean"].get<double>()).epsilon(1e-9));
    // Each stage's median is at most the tick's, so nine of them are at most nine ticks'.
    CHECK(medianSum <= std::size(kTickStages) * tick["ns_p50"].get<double>());
    CHECK(e["candidates_mean"].get<double>() >= 0.0);
    CHECK(e["contact_fraction"].get<double>() >= 0.0);
    CHECK(e["contact_fraction"].get<double>() <= 1.0);
}

} // namespace

TEST_CASE("hapto bench tick --json reports every stage of every mode for every index",
          "[threads]") {
    test::TempDir dir;
    const std::string scene = makeScene(dir);
    const json j = runTickJson(dir, "--scene " + scene +
                                        " --ticks 300 --sleep-us 200 --warm-us 20 --index grid:4 "
                                        "--index octree:2:0.005");
    REQUIRE(j.is_array());
    REQUIRE(j.size() == 6);
    const char* modes[] = {"hot", "sleep", "sleep+warm"};
    for (std::size_t i = 0; i < j.size(); ++i) {
        const json& e = j[i];
        CHECK(e["index"] == (i < 3 ? "grid:4" : "octree:2:0.005"));
        CHECK(e["mode"] == modes[i % 3]);
        CHECK(e["objects"] == 60);
        CHECK(e["device"] == "walk");
        CHECK(e["sleep_us"].get<double>() == (i % 3 == 0 ? 0.0 : 200.0));
        CHECK(e["warm_us"].get<double>() == (i % 3 == 2 ? 20.0 : 0.0));
        checkTickEntry(e, 300);
    }
    // The same walk in every mode: the same candidates, the same contacts.
    for (std::size_t i = 1; i < 3; ++i) {
        CHECK(j[i]["candidates_mean"] == j[0]["candidates_mean"]);
        CHECK(j[i]["contact_fraction"] == j[0]["contact_fraction"]);
        CHECK(j[3 + i]["candidates_mean"] == j[3]["candidates_mean"]);
    }
}

TEST_CASE("hapto bench tick --wake-latency-us adds the sleep modes with the request held",
          "[threads]") {
    test::TempDir dir;
    const std::string out = (dir / "tick.json").string();
    const auto r = test::runHapto("bench tick --ticks 100 --sleep-us 100 --warm-us 10 "
                                  "--wake-latency-us 0 --json " +
                                  out);
    INFO(r.output);
    if (::access("/dev/cpu_dma_latency", W_OK) != 0) {
        // Not root, or no PM QoS here: the run stops and says what it could not hold.
        CHECK(r.exitCode != 0);
        CHECK_THAT(r.output, Catch::Contains("/dev/cpu_dma_latency"));
        CHECK_FALSE(std::filesystem::exists(out));
        return;
    }
    REQUIRE(r.exitCode == 0);
    const json j = json::parse(test::readFile(out));
    REQUIRE(j.size() == 5);
    const char* modes[] = {"hot", "sleep", "sleep+warm", "sleep+lat", "sleep+warm+lat"};
    for (std::size_t i = 0; i < j.size(); ++i) {
        CHECK(j[i]["mode"] == modes[i]);
        CHECK(j[i]["wake_latency_us"] == (i < 3 ? -1 : 0));
        CHECK(j[i]["sleep_us"].get<double>() == (i == 0 ? 0.0 : 100.0));
        CHECK(j[i]["warm_us"].get<double>() == (i == 2 || i == 4 ? 10.0 : 0.0));
        checkTickEntry(j[i], 100);
        CHECK(j[i]["candidates_mean"] == j[0]["candidates_mean"]); // the same walk
    }
    CHECK_THAT(r.output, Catch::Contains("sleep+warm+lat"));
}

TEST_CASE("hapto bench tick drives a simulated hand's reads and writes, and prints a table",
          "[threads]") {
    test::TempDir dir;
    const json j = runTickJson(dir, "--device sim --ticks 200 --sleep-us 100 --warm-us 10");
    REQUIRE(j.size() == 3);
    for (const json& e : j) {
        CHECK(e["device"] == "sim");
        CHECK(e["objects"] == 200);
        checkTickEntry(e, 200);
    }
    const auto r = test::runHapto("bench tick --ticks 100 --sleep-us 50 --warm-us 5");
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK_THAT(r.output, Catch::Contains("200 objects"));
    CHECK_THAT(r.output, Catch::Contains("octree:2:0.005"));
    CHECK_THAT(r.output, Catch::Contains("sleep+warm"));
    CHECK_THAT(r.output, Catch::Contains("p99.9 ns"));
    for (const char* name : kTickStages) {
        CHECK_THAT(r.output, Catch::Contains(name));
    }
}

TEST_CASE("hapto bench tick --walk-edge keeps the walk in a cube about the scene's centre",
          "[threads]") {
    test::TempDir dir;
    const std::string scene = makeScene(dir);
    const json whole = runTickJson(dir, "--scene " + scene + " --ticks 50 --sleep-us 50");
    const json inner =
        runTickJson(dir, "--scene " + scene + " --ticks 50 --sleep-us 50 --walk-edge 0.02");
    REQUIRE(whole.size() == 3);
    REQUIRE(inner.size() == 3);
    for (int a = 0; a < 3; ++a) {
        const double lo = whole[0]["walk_min"][a], hi = whole[0]["walk_max"][a];
        const double ilo = inner[0]["walk_min"][a], ihi = inner[0]["walk_max"][a];
        REQUIRE(hi - lo > 0.02); // the scene is larger than the cube asked for
        CHECK(ihi - ilo == Approx(0.02).epsilon(1e-12));
        CHECK(0.5 * (ilo + ihi) == Approx(0.5 * (lo + hi)).margin(1e-15));
    }
    checkTickEntry(inner[0], 50);
}

TEST_CASE("hapto bench tick --push-mm holds the walking hand back near the proxy", "[threads]") {
    // 10^3 cubes of 2 mm filling half of a 2.5 cm cube: the hand walks into them all the time.
    test::TempDir dir;
    const std::string scene = (dir / "dense.json").string();
    REQUIRE(test::runHapto("scene random --count 1000 --seed 1 --size 0.002 --workspace 0.025 -o " +
                           scene)
                .exitCode == 0);
    const std::string args = "--scene " + scene + " --ticks 300 --sleep-us 50";
    const json held = runTickJson(dir, args); // the default: 2 mm
    const json through = runTickJson(dir, args + " --push-mm 0");
    for (const json* j : {&held, &through}) {
        REQUIRE(j->size() == 3);
        for (const json& e : *j) {
            checkTickEntry(e, 300);
            CHECK(e["solves_mean"].get<double>() >= 1.0);
            CHECK(e["extra_leaves_mean"].get<double>() >= 0.0);
            CHECK(e["pull_backs_mean"].get<double>() >= 0.0);
            CHECK(e["gap_m"]["p50"].get<double>() <= e["gap_m"]["p99"].get<double>());
            CHECK(e["gap_m"]["p99"].get<double>() <= e["gap_m"]["p999"].get<double>());
        }
    }
    // Held back to 2 mm from the proxy after each tick, the hand is at most one walk step
    // (0.5 mm) further at the next; walking through, it leaves the proxy far behind.
    CHECK(held[0]["contact_fraction"].get<double>() > 0.1);
    CHECK(held[0]["gap_m"]["p999"].get<double>() <= 0.0025 + 1e-9);
    CHECK(through[0]["gap_m"]["p99"].get<double>() > 0.005);
}

TEST_CASE("hapto bench tick refuses bad options with exit code 2 and writes nothing") {
    test::TempDir dir;
    const std::string out = (dir / "tick.json").string();
    SECTION("a warm-up not shorter than the sleep") {
        const auto r =
            test::runHapto("bench tick --ticks 10 --sleep-us 10 --warm-us 20 --json " + out);
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("--warm-us"));
    }
    SECTION("an unknown device") {
        const auto r = test::runHapto("bench tick --ticks 10 --device falcon --json " + out);
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("--device"));
    }
    SECTION("a negative wake latency") {
        const auto r = test::runHapto("bench tick --ticks 10 --wake-latency-us -1 --json " + out);
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("--wake-latency-us"));
    }
    SECTION("no ticks") {
        const auto r = test::runHapto("bench tick --ticks 0 --json " + out);
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("--ticks"));
    }
    SECTION("a walk cube of no size") {
        for (const char* edge : {"0", "-1", "nan"}) {
            const auto r = test::runHapto(std::string("bench tick --ticks 10 --walk-edge ") + edge +
                                          " --json " + out);
            CHECK(r.exitCode == 2);
            CHECK_THAT(r.output, Catch::Contains("--walk-edge"));
        }
    }
    SECTION("a negative or non-finite push") {
        for (const char* push : {"-1", "nan", "inf"}) {
            const auto r = test::runHapto(std::string("bench tick --ticks 10 --push-mm ") + push +
                                          " --json " + out);
            CHECK(r.exitCode == 2);
            CHECK_THAT(r.output, Catch::Contains("--push-mm"));
        }
    }
    SECTION("an unknown index") {
        const auto r = test::runHapto("bench tick --ticks 10 --index kdtree:3 --json " + out);
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("kdtree:3"));
    }
    SECTION("an output in a missing folder") {
        const auto r = test::runHapto("bench tick --ticks 10 --json " +
                                      (dir / "missing" / "tick.json").string());
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("--json"));
    }
    CHECK_FALSE(std::filesystem::exists(out));
}
