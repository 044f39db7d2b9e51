// `hapto bench query` (its hand walk: tests/experiments/HandWalkTests.cpp). Behaviour only:
// nothing here depends on how fast anything runs.

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <string>

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

TEST_CASE("hapto bench query --json reports every index over the same walk") {
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

TEST_CASE("hapto bench query: every cursor strategy finds the same leaves along the walk") {
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

TEST_CASE("hapto bench query: the same seed walks the same path") {
    test::TempDir dir;
    const std::string scene = makeScene(dir);
    const std::string args = "--scene " + scene + " --steps 2500 --seed 4 --index grid:3";
    const json a = runJson(args);
    const json b = runJson(args);
    CHECK(a[0]["candidates_mean"] == b[0]["candidates_mean"]);
    const json c = runJson("--scene " + scene + " --steps 2500 --seed 5 --index grid:3");
    CHECK(c[0]["steps"] == 2500);
}

TEST_CASE("hapto bench query runs on the default scene and prints a table") {
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
