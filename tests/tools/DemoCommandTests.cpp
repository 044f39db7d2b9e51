// `hapto demo grasp --kinematic` end to end on a mesh: two simulated hands lift, carry and put
// down a closed, static mesh object read from a scene file (the kinematic GraspController; the
// physical grasp, the default, is PhysicalGraspCommandTests.cpp) (a cube from an OBJ file beside
// it), and the command says the rebuilt index finds it at its new place. What the grasp does is
// checked on the step mode's clock (--stepped: the same every run, however busy the machine); the
// wall-clock session (about 9 s) is checked only for ending with every device at zero force.

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <string>

using namespace hapto::test;

namespace {

/// A 5 cm cube as an OBJ (8 vertices, 6 quads, CCW seen from outside; 1-based indices).
const char* kCubeObj = R"(# a 5 cm cube about the origin
v -0.025 -0.025 -0.025
v 0.025 -0.025 -0.025
v 0.025 0.025 -0.025
v -0.025 0.025 -0.025
v -0.025 -0.025 0.025
v 0.025 -0.025 0.025
v 0.025 0.025 0.025
v -0.025 0.025 0.025
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 4 8 7 3
f 1 5 8 4
f 2 3 7 6
)";

/// The built-in grasp scene (y up, floor at y = -0.1) with its cube, id 0, replaced by the given
/// mesh fields, centred at height `y` (the cube's: -0.075).
std::string graspScene(const std::string& meshFields, double y = -0.075) {
    return R"({"format": "hapto-scene", "version": 2,
  "bounds": {"min": [-0.15, -0.10, -0.15], "max": [0.15, 0.15, 0.15]},
  "objects": [
  {"id": 0, "shape": "mesh", "center": [-0.05, )" +
           std::to_string(y) + R"(, 0], "friction": [0.6, 0.5], )" + meshFields + R"(},
  {"id": 1, "shape": "box", "center": [0, -0.09, 0], "half_extents": [0.005, 0.01, 0.04], "friction": [0.3, 0.2]},
  {"id": 2, "shape": "box", "center": [-0.05, -0.075, 0.08], "half_extents": [0.025, 0.025, 0.025], "friction": [0.3, 0.2]},
  {"id": 3, "shape": "box", "center": [-0.05, -0.075, -0.08], "half_extents": [0.025, 0.025, 0.025], "friction": [0.3, 0.2]},
  {"id": 4, "shape": "sphere", "center": [0.10, -0.08, -0.08], "radius": 0.02, "friction": [0.3, 0.2]},
  {"id": 5, "shape": "box", "center": [0.12, -0.05, 0.06], "half_extents": [0.02, 0.05, 0.02], "friction": [0.3, 0.2]}]}
)";
}

/// Runs the grasp demo with --stepped on the scene in `dir`, checks it grasped once and the
/// index found the object at its new place, and returns the JSON report.
nlohmann::json runGraspDemo(const TempDir& dir) {
    const CommandResult r =
        runHapto("demo grasp --kinematic --stepped --scene " + (dir / "scene.json").string() +
                 " --object 0 --report " + (dir / "report.json").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK(r.output.find("force at the end: left 0.000 N, right 0.000 N") != std::string::npos);
    CHECK(r.output.find("grasped 1 time(s)") != std::string::npos);
    CHECK(r.output.find("the index finds it at its new place: yes, at its old place: no") !=
          std::string::npos);
    const nlohmann::json report = nlohmann::json::parse(readFile(dir / "report.json"));
    // The script lifts 5 cm and carries 10 cm along +x.
    const auto& start = report["start_position"];
    double top = -1;
    for (const auto& p : report["path"]) {
        top = std::max(top, p["position"][1].get<double>());
    }
    CHECK(top == Approx(start[1].get<double>() + 0.05).margin(0.008));
    CHECK(report["end_position"][0].get<double>() ==
          Approx(start[0].get<double>() + 0.10).margin(0.008));
    CHECK(report["back_in_index"] == true);
    CHECK(report["index_finds_it_at_end"] == true);
    CHECK(report["clock"] == "stepped");
    // Each hand squeezes with press_n (2 N) while it holds the object: the mean from the
    // grasp's start (the squeeze still rising then) through the lift and carry is within 10 %
    // (issue 35 item 2: the hand's spring in series with the surface gave 1.4 N).
    for (const auto& d : report["devices"]) {
        INFO(d["name"]);
        CHECK(d["squeeze_mean_n"].get<double>() == Approx(2.0).margin(0.2));
        CHECK(d["end_force_n"] == 0.0);
    }
    return report;
}

} // namespace

TEST_CASE("hapto demo grasp --kinematic --stepped --object on a closed mesh lifts, carries and "
          "puts it down, "
          "and the index finds it at its new place",
          "[threads]") {
    TempDir dir;
    writeFile(dir / "cube.obj", kCubeObj);
    writeFile(dir / "scene.json", graspScene(R"("file": "cube.obj")"));
    const nlohmann::json report = runGraspDemo(dir);
    // Put back on the floor where it was, 10 cm along +x.
    const auto& start = report["start_position"];
    const auto& end = report["end_position"];
    CHECK(end[1].get<double>() == Approx(start[1].get<double>()).margin(0.008));
    CHECK(end[2].get<double>() == Approx(start[2].get<double>()).margin(0.008));
    CHECK(report["index_finds_it_at_start"] == false);
    CHECK(report["mass_kg"].get<double>() > 0);
}

TEST_CASE("hapto demo grasp --kinematic --stepped --object on a generated torus lying flat on the "
          "floor, 1.5 cm "
          "from a ridge, lifts, carries and puts it down",
          "[threads]") {
    TempDir dir;
    // A 6 cm torus, axis along y (lying flat), 2016 triangles, written beside its own scene.
    const CommandResult made =
        runHapto("scene mesh --shape torus --triangles 2000 --size 0.06 -o " +
                 (dir / "torus.json").string());
    REQUIRE(made.exitCode == 0);
    // 1.5 cm tall, resting on the floor (y = -0.1): its +x side is 1.5 cm from the scene's
    // ridge (object 1), nearer than the hands' usual 2 cm stand-off.
    writeFile(dir / "scene.json", graspScene(R"("file": "torus.ply")", -0.0925));
    const nlohmann::json report = runGraspDemo(dir);
    // Put back on the floor, 10 cm along +x.
    CHECK(report["end_position"][1].get<double>() ==
          Approx(report["start_position"][1].get<double>()).margin(0.003));
}

TEST_CASE("hapto demo grasp --kinematic --stepped: the same session gives the same report, path "
          "and forces",
          "[threads]") {
    TempDir dir;
    writeFile(dir / "cube.obj", kCubeObj);
    writeFile(dir / "scene.json", graspScene(R"("file": "cube.obj")"));
    const nlohmann::json first = runGraspDemo(dir);
    const nlohmann::json second = runGraspDemo(dir);
    CHECK(second == first);
}

TEST_CASE("hapto demo grasp on the wall clock ends with every device at zero force", "[realtime]") {
    // What the grasp does on the wall clock depends on the control loop keeping pace with the
    // servo threads (a busy machine can leave the cube where it was): only the session's end is
    // checked here; the grasp itself, on the step clock, above.
    TempDir dir;
    const CommandResult r = runHapto("demo grasp --report " + (dir / "report.json").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK(r.output.find("force at the end: left 0.000 N, right 0.000 N") != std::string::npos);
    const nlohmann::json report = nlohmann::json::parse(readFile(dir / "report.json"));
    CHECK(report["clock"] == "wall");
    REQUIRE(report["devices"].size() == 2);
    for (const auto& d : report["devices"]) {
        CHECK(d["end_force_n"] == 0.0);
    }
}
