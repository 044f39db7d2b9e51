// `hapto scene import`, `info` and `convert`, end to end: the scene written refers
// to the model relative to itself and places it as asked; info reports the triangles; bad
// models and options exit 2 naming the place, and nothing is written.

#include "hapto/scenes/SceneFile.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <string>

using namespace hapto;
using namespace hapto::test;

namespace {

// A unit cube in quads, and the same cube with one quad left out (open).
const char* kUnitCubeObj =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
const char* kOpenCubeObj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\n"
                           "v 0 1 1\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\n";

std::string q(const std::filesystem::path& p) {
    return "'" + p.string() + "'";
}

} // namespace

TEST_CASE("scene import wraps a model in a scene that refers to it relative to itself") {
    TempDir dir;
    std::filesystem::create_directories(dir / "models");
    std::filesystem::create_directories(dir / "scenes");
    writeFile(dir / "models/cube.obj", kUnitCubeObj);
    const auto r = runHapto("scene import " + q(dir / "models/cube.obj") +
                            " --scale 0.05 --center 0.1,0,-0.1 --rotation 0,0,0,1 "
                            "--stiffness 1200 --friction 0.5,0.25 -o " +
                            q(dir / "scenes/cube.json"));
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK_THAT(r.output, Catch::Contains("12 triangles") && Catch::Contains("closed"));
    const std::string written = readFile(dir / "scenes/cube.json");
    CHECK_THAT(written, Catch::Contains("\"file\": \"../models/cube.obj\"") &&
                            Catch::Contains("\"version\": 2"));
    const Scene s = loadSceneFile(dir / "scenes/cube.json");
    REQUIRE(s.size() == 1);
    const SceneObject& o = s.object(0);
    REQUIRE(o.shape == Shape::Mesh);
    CHECK(o.mesh->triangleCount() == 12);
    CHECK(o.mesh->vertices().size() == 8);
    CHECK(o.mesh->closed());
    CHECK(o.material == Material{1200, 0.5, 0.25});
    // A half turn about z: the local corner (0.05, 0.05, 0.05) goes to (-0.05, -0.05, 0.05),
    // then to the centre.
    const Vec3 corner = o.center + o.rotation * Vec3(0.05, 0.05, 0.05);
    CHECK(std::abs(corner.x - 0.05) < 1e-12);
    CHECK(std::abs(corner.y + 0.05) < 1e-12);
    CHECK(std::abs(corner.z + 0.05) < 1e-12);
    for (const Vec3& v : o.mesh->vertices()) {
        CHECK(s.bounds().contains(o.center + o.rotation * v));
    }
}

TEST_CASE("scene info reports the triangles: total, per mesh, degenerate and duplicate dropped, "
          "closed or not") {
    TempDir dir;
    writeFile(dir / "cube.obj", kUnitCubeObj);
    writeFile(dir / "open.obj", kOpenCubeObj);
    writeFile(dir / "s.json", R"({"format": "hapto-scene", "version": 2, "objects": [
        {"id": 4, "shape": "mesh", "center": [0, 0, 0], "file": "cube.obj"},
        {"id": 8, "shape": "mesh", "center": [2, 0, 0], "file": "open.obj"},
        {"id": 9, "shape": "mesh", "center": [0, 2, 0],
         "vertices": [[0,0,0],[1,0,0],[0,1,0],[2,0,0]], "triangles": [[0,1,2],[0,1,3],[2,1,0]]},
        {"id": 1, "shape": "box", "center": [0, 0, 3], "half_extents": [1, 1, 1]}]})");
    const auto r = runHapto("scene info --scene " + q(dir / "s.json"));
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK_THAT(r.output,
               Catch::Contains("objects:  4 (1 boxes, 0 of them rotated; 0 spheres; 3 meshes)"));
    CHECK_THAT(r.output, Catch::Contains("triangles: 23 in 3 meshes (1 closed, 2 open), 1 "
                                         "degenerate and 1 duplicate dropped"));
    CHECK_THAT(r.output, Catch::Contains("mesh 4: 12 triangles, 0 degenerate and 0 duplicate "
                                         "dropped, closed, file cube.obj"));
    CHECK_THAT(r.output, Catch::Contains("mesh 8: 10 triangles, 0 degenerate and 0 duplicate "
                                         "dropped, open, file open.obj"));
    CHECK_THAT(r.output, Catch::Contains("mesh 9: 1 triangles, 1 degenerate and 1 duplicate "
                                         "dropped, open, inline"));
}

TEST_CASE("scene import refuses bad models and options with exit code 2 and writes nothing") {
    TempDir dir;
    writeFile(dir / "cube.obj", kUnitCubeObj);
    writeFile(dir / "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    writeFile(dir / "old.json", "an older file\n");
    writeFile(dir / "model.json", "{}\n");
    struct Case {
        std::string args;
        std::string expected;
    };
    const std::vector<Case> cases{
        {q(dir / "bad.obj"), "bad.obj:4: vertex index 4 is out of range"},
        {q(dir / "missing.stl"), "missing.stl: cannot open the model file"},
        {q(dir.path()), "is a directory"},
        {q(dir / "model.json"), "unknown model format '.json'"},
        {q(dir / "cube.obj") + " --scale 0",
         "--scale: 0 is out of range; expected a number above 0"},
        {q(dir / "cube.obj") + " --scale nan", "--scale"},
        {q(dir / "cube.obj") + " --center 1,2", "--center"},
        {q(dir / "cube.obj") + " --center 0,nan,0", "--center"},
        {q(dir / "cube.obj") + " --rotation 1,1,0,0", "--rotation: expected a unit quaternion"},
        {q(dir / "cube.obj") + " --stiffness 0",
         "--stiffness: 0 is out of range; expected a number above 0"},
        {q(dir / "cube.obj") + " --friction 0.1,0.2", "--friction: the dynamic coefficient"},
    };
    for (const Case& c : cases) {
        INFO(c.args);
        const auto r = runHapto("scene import " + c.args + " -o " + q(dir / "old.json"));
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains(c.expected));
        CHECK(readFile(dir / "old.json") == "an older file\n");
    }
    // The model is never the output.
    const auto r = runHapto("scene import " + q(dir / "cube.obj") + " -o " + q(dir / "cube.obj"));
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("the model file"));
    CHECK(readFile(dir / "cube.obj") == kUnitCubeObj);
}

TEST_CASE("scene convert turns JSON into binary and back, and every --scene reads the binary") {
    TempDir dir;
    REQUIRE(runHapto("scene random --count 300 --rotate -o " + q(dir / "a.json")).exitCode == 0);
    auto r = runHapto("scene convert " + q(dir / "a.json") + " -o " + q(dir / "a.hsb"));
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK(readFile(dir / "a.hsb").starts_with("HAPTOSCN"));
    // --format overrides the name; the input is told apart by its magic.
    r = runHapto("scene convert " + q(dir / "a.hsb") + " -o " + q(dir / "b.out") +
                 " --format json");
    REQUIRE(r.exitCode == 0);
    CHECK(readFile(dir / "b.out") == readFile(dir / "a.json"));
    CHECK(loadSceneFile(dir / "a.hsb") == loadSceneFile(dir / "a.json"));
    r = runHapto("scene info --scene " + q(dir / "a.hsb"));
    CHECK(r.exitCode == 0);
    CHECK_THAT(r.output, Catch::Contains("objects:  300 (300 boxes, 300 of them rotated"));
}

TEST_CASE("scene convert refuses its input as output, a damaged input and a model it would "
          "lose, writing nothing") {
    TempDir dir;
    REQUIRE(runHapto("scene random --count 20 -o " + q(dir / "a.json")).exitCode == 0);
    REQUIRE(runHapto("scene convert " + q(dir / "a.json") + " -o " + q(dir / "a.hsb")).exitCode ==
            0);
    const std::string json = readFile(dir / "a.json");
    const std::string binary = readFile(dir / "a.hsb");
    auto r = runHapto("scene convert " + q(dir / "a.hsb") + " -o " + q(dir / "a.hsb"));
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("an input is never overwritten"));
    CHECK(readFile(dir / "a.hsb") == binary);

    writeFile(dir / "cut.hsb", binary.substr(0, binary.size() - 1));
    writeFile(dir / "old.json", "an older file\n");
    r = runHapto("scene convert " + q(dir / "cut.hsb") + " -o " + q(dir / "old.json"));
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("cut.hsb: byte 24: ") &&
                             Catch::Contains("the file is truncated or damaged"));
    CHECK(readFile(dir / "old.json") == "an older file\n");

    // A model named relative to the scene cannot be referenced from another folder.
    writeFile(dir / "cube.obj", kUnitCubeObj);
    REQUIRE(runHapto("scene import " + q(dir / "cube.obj") + " -o " + q(dir / "m.json")).exitCode ==
            0);
    std::filesystem::create_directories(dir / "elsewhere");
    r = runHapto("scene convert " + q(dir / "m.json") + " -o " + q(dir / "elsewhere/m.hsb"));
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("names its model file 'cube.obj' relative to the "
                                         "scene's folder"));
    CHECK(!std::filesystem::exists(dir / "elsewhere/m.hsb"));
    r = runHapto("scene convert " + q(dir / "m.json") + " -o " + q(dir / "m.hsb"));
    CHECK(r.exitCode == 0);
    CHECK(sceneToJson(loadSceneFile(dir / "m.hsb")) == sceneToJson(loadSceneFile(dir / "m.json")));
}
