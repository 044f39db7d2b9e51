// `hapto demo grasp`, physical (the default): two simulated hands lift a body with mass by
// friction alone, carry it, set it down on the plinth, grasp it again, lift it 4 cm and open;
// it falls and comes to rest. Checked on the step mode's clock (--stepped: the same every run)
// over the three built-in objects (--shape box, sphere, mesh); --record writes the hands' and
// the bodies' traces; --kinematic keeps the kinematic controller; the command's refusals.

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

using namespace hapto::test;

namespace {

constexpr int kPlinthId = 7; // the built-in physical scene's plinth (top at y = -0.08 m)
constexpr double kPlinthTop = -0.08;

/// Runs `hapto demo grasp --stepped <extra> --report` in `dir` and returns the report.
nlohmann::json runPhysical(const TempDir& dir, const std::string& extra) {
    const CommandResult r =
        runHapto("demo grasp --stepped " + extra + " --report " + (dir / "report.json").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK(r.output.find("force at the end: left 0.000 N, right 0.000 N") != std::string::npos);
    return nlohmann::json::parse(readFile(dir / "report.json"));
}

/// Checks a body placed on the plinth: on object 7, its lowest point within `boundMm` of the
/// plinth's top, over the plinth's 6 cm square centred at x = 0.05.
void checkOnPlinth(const nlohmann::json& place, double boundMm) {
    INFO(place.dump());
    CHECK(place["support_id"] == kPlinthId);
    CHECK(std::abs(place["gap_mm"].get<double>()) < boundMm);
    CHECK(std::abs(place["lowest_y"].get<double>() - kPlinthTop) < boundMm * 1e-3);
    CHECK(std::abs(place["center_of_mass"][0].get<double>() - 0.05) < 0.03);
    CHECK(std::abs(place["center_of_mass"][2].get<double>()) < 0.03);
}

} // namespace

TEST_CASE("hapto demo grasp --stepped lifts a box, a sphere and a mesh by friction, sets each down "
          "on the plinth, drops it and it comes to rest there at zero force",
          "[threads]") {
    for (const char* shape : {"box", "sphere", "mesh"}) {
        DYNAMIC_SECTION(shape) {
            TempDir dir;
            const nlohmann::json r = runPhysical(dir, std::string("--shape ") + shape);
            INFO(r.dump(1));
            CHECK(r["mode"] == "physical");
            CHECK(r["clock"] == "stepped");
            CHECK(r["mass_kg"].get<double>() == Approx(0.1));
            // Held: lifted 5 cm by the hands less their springs' sag under the weight (each
            // hand's 300 N/m spring carries m g / 2: 1.6 mm), sliding under 1 mm against them.
            CHECK(r["held"] == true);
            CHECK(r["lift_mm"].get<double>() > 45.0);
            CHECK(r["slip_max_mm"].get<double>() < 1.0);
            // Carried sideways, so with no vertical acceleration: the hands hold up m g. The
            // mean over 1.3 s of control steps, each one tick's force, within 1 % (a 20 Hz ring
            // of the body on the hands' contact springs averages out over 26 periods).
            CHECK(r["carry_support_mean_n"].get<double>() ==
                  Approx(r["weight_n"].get<double>()).epsilon(0.01));
            // Set down on the plinth 2 cm above the floor, not into it: its lowest point within
            // 0.5 mm of the plinth's top (the solver's penetration slop is 0.1 mm).
            checkOnPlinth(r["set_down"], 0.5);
            // Dropped: lifted again by 4 cm less the sag and slip (3-5 cm above the plinth).
            CHECK(r["drop_from"]["gap_mm"].get<double>() > 30.0);
            CHECK(r["drop_from"]["gap_mm"].get<double>() < 50.0);
            // At rest on the plinth, not hovering and not sunk: within 0.2 mm (slop + g dt^2).
            CHECK(r["at_rest"] == true);
            checkOnPlinth(r["rest"], 0.2);
            CHECK(r["dynamics"]["stable"] == true);
            CHECK(r["dynamics"]["deepest_penetration_mm"].get<double>() < 1.0);
            for (const auto& d : r["devices"]) {
                CHECK(d["end_force_n"] == 0.0);
                CHECK(d["squeeze_mean_n"].get<double>() == Approx(2.0).epsilon(0.05));
            }
        }
    }
}

TEST_CASE("hapto demo grasp --stepped gives the same report every run, and --record writes the "
          "hands' and the bodies' traces",
          "[threads]") {
    TempDir dir;
    const nlohmann::json first = runPhysical(dir, "--record " + (dir / "a").string());
    const nlohmann::json second = runPhysical(dir, "--record " + (dir / "b").string());
    CHECK(second == first);
    for (const char* name : {"left.trace", "right.trace", "bodies.trace"}) {
        CHECK(std::filesystem::is_regular_file(dir / "a" / name));
    }
    // The bodies' trace exports the same rows both times; its last row is where the report
    // says the body came to rest.
    std::string csv[2];
    for (int i = 0; i < 2; ++i) {
        const std::string run = i == 0 ? "a" : "b";
        const CommandResult e = runHapto("trace export " + (dir / run / "bodies.trace").string() +
                                         " -o " + (dir / (run + ".csv")).string());
        REQUIRE(e.exitCode == 0);
        csv[i] = readFile(dir / (run + ".csv"));
    }
    CHECK(csv[0] == csv[1]);
    REQUIRE(csv[0].rfind("time_s,id,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz", 0) == 0);
    const std::vector<std::string> rows = linesOf(csv[0]);
    REQUIRE(rows.size() > 10000); // 1 kHz for over 10 s
    const std::string& last = rows.back();
    double t = 0, y = 0;
    int id = -1;
    double x = 0;
    REQUIRE(std::sscanf(last.c_str(), "%lf,%d,%lf,%lf", &t, &id, &x, &y) == 4);
    CHECK(id == 0);
    // The box's centre, its centre of mass too.
    CHECK(x == Approx(first["rest"]["center_of_mass"][0].get<double>()).margin(1e-6));
    CHECK(y == Approx(first["rest"]["center_of_mass"][1].get<double>()).margin(1e-6));
}

TEST_CASE("hapto demo grasp --kinematic --stepped still carries the built-in static cube with "
          "the kinematic controller",
          "[threads]") {
    TempDir dir;
    const CommandResult r =
        runHapto("demo grasp --kinematic --stepped --report " + (dir / "report.json").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK(r.output.find("grasped 1 time(s)") != std::string::npos);
    CHECK(r.output.find("force at the end: left 0.000 N, right 0.000 N") != std::string::npos);
    const nlohmann::json report = nlohmann::json::parse(readFile(dir / "report.json"));
    CHECK(report["end_position"][0].get<double>() ==
          Approx(report["start_position"][0].get<double>() + 0.10).margin(0.008));
}

TEST_CASE("hapto demo grasp refuses what cannot work, with exit code 2 and the options named",
          "[threads]") {
    TempDir dir;
    // A version-2 scene: its object 0 is static.
    writeFile(dir / "static.json",
              R"({"format": "hapto-scene", "version": 2,
  "bounds": {"min": [-0.15, -0.10, -0.15], "max": [0.15, 0.15, 0.15]},
  "objects": [{"id": 0, "shape": "box", "center": [-0.05, -0.075, 0], "half_extents": [0.025, 0.025, 0.025]}]})");
    writeFile(dir / "dynamic.json",
              R"({"format": "hapto-scene", "version": 3,
  "bounds": {"min": [-0.15, -0.11, -0.15], "max": [0.15, 0.15, 0.15]},
  "objects": [{"id": 0, "shape": "box", "center": [-0.05, -0.075, 0], "half_extents": [0.025, 0.025, 0.025],
               "dynamic": true, "mass_kg": 0.1},
              {"id": 1, "shape": "box", "center": [0, -0.105, 0], "half_extents": [0.15, 0.005, 0.15]}]})");
    const struct {
        std::string args;
        std::string says;
    } cases[] = {
        {"--stepped --view", "--stepped --view"},
        {"--shape cone", "--shape 'cone'"},
        {"--shape sphere --kinematic", "--shape"},
        {"--shape sphere --scene " + (dir / "dynamic.json").string(), "--shape"},
        {"--stepped --scene " + (dir / "static.json").string(), "is static"},
        {"--stepped --kinematic --scene " + (dir / "dynamic.json").string(), "is dynamic"},
    };
    for (const auto& c : cases) {
        const CommandResult r = runHapto("demo grasp " + c.args);
        INFO(c.args << "\n" << r.output);
        CHECK(r.exitCode == 2);
        CHECK(r.output.find(c.says) != std::string::npos);
    }
}

TEST_CASE("hapto demo grasp --stepped with hands squeezing 0.3 N each (mu_s (F1 + F2) = 0.37 m g) "
          "does not lift the box - not held, and it stays on the floor",
          "[threads]") {
    TempDir dir;
    const auto hand = [](const char* name, const char* script, double x, int seed) {
        return std::string(R"({"name": ")") + name +
               R"(", "kind": "sim", "transform": {"translation": [)" + std::to_string(x) +
               R"(, -0.04, 0]}, "sim": {"script": ")" + script + R"(", "seed": )" +
               std::to_string(seed) + R"(, "object": 0, "press_n": 0.3}})";
    };
    writeFile(dir / "light.json", R"({"format": "hapto-devices", "version": 1, "devices": [)" +
                                      hand("left", "grasp-left", -0.12, 1) + ", " +
                                      hand("right", "grasp-right", 0.04, 2) + "]}");
    const nlohmann::json r = runPhysical(dir, "--devices " + (dir / "light.json").string());
    INFO(r.dump(1));
    CHECK(r["held"] == false);
    CHECK(r["lift_mm"].get<double>() < 1.0);
    CHECK(r["slip_max_mm"].get<double>() > 40.0); // the hands rose 5 cm past it
    CHECK(r["rest"]["support_id"] == 6);          // the floor
    CHECK(r["at_rest"] == true);
}
