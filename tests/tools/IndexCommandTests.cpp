#include "TestSupport.h"

#include "hapto/index/DefaultIndex.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/SceneFile.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <sstream>

using namespace hapto;
using namespace hapto::test;

namespace {

// A small scene: two overlapping boxes, a sphere, and a box with a non-dense id.
Scene smallScene() {
    std::vector<SceneObject> o;
    o.push_back(makeBox(7, {0.0, 0.0, 0.0}, Vec3(0.02)));
    o.push_back(makeBox(3, {0.03, 0.0, 0.0}, Vec3(0.02), glm::angleAxis(0.5, Vec3(0, 0, 1))));
    o.push_back(makeSphere(42, {-0.08, 0.08, 0.0}, 0.01));
    o.push_back(makeBox(1000000, {0.1, -0.1, 0.1}, Vec3(0.005)));
    return Scene({Vec3(-0.125), Vec3(0.125)}, std::move(o));
}

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        out.push_back(line);
    }
    return out;
}

} // namespace

TEST_CASE("hapto query lists candidate ids per point, the same set for every index", "[threads]") {
    TempDir dir;
    saveSceneFile(smallScene(), dir / "s.json");
    writeFile(dir / "p.csv", "x,y,z\n0,0,0\n0.01, 0.0, 0.0\n-0.08,0.08,0\n0.5,0,0\n"
                             "0.1,-0.1,0.1\r\n\n0.12,0.12,-0.12\n");
    for (const char* spec :
         {"brute", "grid:5", "grid:1:aabb", "octree:1:0.005", "octree:2:0.005:aabb"}) {
        INFO(spec);
        const CommandResult r =
            runHapto("query --scene " + (dir / "s.json").string() + " --index " + spec +
                     " --points " + (dir / "p.csv").string());
        REQUIRE(r.exitCode == 0);
        const auto out = lines(r.output);
        REQUIRE(out.size() == 7);
        CHECK(out[0] == "point,candidates");
        // Objects holding the point are always there (ids, ascending, space separated).
        CHECK_THAT(out[1], Catch::StartsWith("0,"));
        CHECK_THAT(out[1], Catch::Contains("3 7") || Catch::Equals("0,3 7 42 1000000"));
        CHECK_THAT(out[2], Catch::Contains("7"));
        CHECK_THAT(out[3], Catch::Contains("42"));
        // Outside the bounds: partitioned indices give nothing, brute force gives everything.
        CHECK(out[4] == (std::string(spec) == "brute" ? "3,3 7 42 1000000" : "3,"));
        CHECK_THAT(out[5], Catch::Contains("1000000"));
        CHECK_THAT(out[6], Catch::StartsWith("5,"));
    }
    // Brute force lists every id everywhere in the bounds.
    const CommandResult brute = runHapto("query --scene " + (dir / "s.json").string() +
                                         " --index brute --points " + (dir / "p.csv").string());
    CHECK(lines(brute.output)[1] == "0,3 7 42 1000000");
    // A fine octree separates the far corner from everything.
    const CommandResult fine =
        runHapto("query --scene " + (dir / "s.json").string() + " --index octree:1:0.001 " +
                 "--points " + (dir / "p.csv").string() + " -o " + (dir / "out.csv").string());
    REQUIRE(fine.exitCode == 0);
    const auto out = lines(readFile(dir / "out.csv"));
    REQUIRE(out.size() == 7);
    CHECK(out[6] == "5,");
    CHECK(out[3] == "2,42");
}

TEST_CASE("hapto query refuses a bad spec or points file with exit code 2 and a clear message") {
    TempDir dir;
    saveSceneFile(smallScene(), dir / "s.json");
    writeFile(dir / "good.csv", "0,0,0\n");
    writeFile(dir / "bad.csv", "x,y,z\n0,0,0\n0.1,zero,0\n");
    writeFile(dir / "short.csv", "0,0\n");
    writeFile(dir / "nan.csv", "0,0,nan\n");
    const std::string scene = " --scene " + (dir / "s.json").string();
    CommandResult r =
        runHapto("query" + scene + " --index grid:0 --points " + (dir / "good.csv").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("grid:0") && Catch::Contains("1 to 256"));
    r = runHapto("query" + scene + " --index kdtree --points " + (dir / "good.csv").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("octree:M:MIN"));
    r = runHapto("query" + scene + " --index brute --points " + (dir / "bad.csv").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("bad.csv:3") && Catch::Contains("0.1,zero,0"));
    r = runHapto("query" + scene + " --index brute --points " + (dir / "short.csv").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("short.csv:1"));
    r = runHapto("query" + scene + " --index brute --points " + (dir / "nan.csv").string());
    CHECK(r.exitCode == 2);
    r = runHapto("query" + scene + " --index brute --points " + (dir / "none.csv").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("none.csv"));
}

TEST_CASE("hapto index-stats prints the statistics, as text or JSON", "[threads]") {
    CommandResult r = runHapto("index-stats --index octree:2:0.005");
    REQUIRE(r.exitCode == 0);
    CHECK_THAT(r.output, Catch::Contains("octree:2:0.005") && Catch::Contains("leaves:") &&
                             Catch::Contains("object-cell pairs:") && Catch::Contains("depth:"));
    r = runHapto("index-stats --index grid:5:aabb --json");
    REQUIRE(r.exitCode == 0);
    const auto j = nlohmann::json::parse(r.output);
    CHECK(j.at("index") == "grid:5:aabb");
    CHECK(j.at("objects") == 200);
    CHECK(j.at("leaves") == 125);
    CHECK(j.at("object_cell_pairs").get<int>() >= 200);
    CHECK(j.at("objects_per_leaf").is_array());
    TempDir dir;
    saveSceneFile(smallScene(), dir / "s.json");
    r = runHapto("index-stats --scene " + (dir / "s.json").string() + " --index brute --json");
    REQUIRE(r.exitCode == 0);
    CHECK(nlohmann::json::parse(r.output).at("object_cell_pairs") == 4);
    r = runHapto("index-stats --index octree:2");
    CHECK(r.exitCode == 2);
}

TEST_CASE("without --index, query and index-stats build the index every session builds") {
    TempDir dir;
    saveSceneFile(smallScene(), dir / "s.json");
    writeFile(dir / "p.csv", "0,0,0\n-0.08,0.08,0\n0.12,0.12,-0.12\n");
    const std::string args =
        "query --scene " + (dir / "s.json").string() + " --points " + (dir / "p.csv").string();
    // Boxes and spheres: the default, the paper's octree, as run and demo grasp choose.
    const CommandResult chosen = runHapto(args);
    INFO(chosen.output);
    REQUIRE(chosen.exitCode == 0);
    CHECK(chosen.output == runHapto(args + " --index " + std::string(kDefaultIndexSpec)).output);
    const CommandResult stats =
        runHapto("index-stats --scene " + (dir / "s.json").string() + " --json");
    INFO(stats.output);
    REQUIRE(stats.exitCode == 0);
    CHECK(nlohmann::json::parse(stats.output).at("index") == std::string(kDefaultIndexSpec));
    // A bad --index is still refused before the points are read.
    const CommandResult bad = runHapto("query --scene " + (dir / "s.json").string() +
                                       " --index kdtree --points " + (dir / "none.csv").string());
    CHECK(bad.exitCode == 2);
    CHECK_THAT(bad.output, Catch::Contains("kdtree") && !Catch::Contains("none.csv"));
}
