// `hapto run` with dynamic bodies: --no-devices (and its refusal without a dynamic body),
// --stepped (byte-identical reports; Falcon and PHANToM refused), the dynamics in the report,
// --record's bodies.trace and `hapto trace export` of it. Stepped sessions only: counts are
// exact on the step clock.

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>

using namespace hapto::test;
using nlohmann::json;

namespace {

// A 2 cm, 50 g box falling from 10 cm, stepped at 500 Hz, beside a static floor.
const char* kDropScene =
    R"({"format": "hapto-scene", "version": 3, "dynamics": {"rate_hz": 500}, "objects": [)"
    R"({"id": 1, "shape": "box", "center": [0, -0.1, 0], "half_extents": [0.1, 0.01, 0.1]},)"
    R"({"id": 5, "shape": "box", "center": [0, 0.1, 0], "half_extents": [0.01, 0.01, 0.01],)"
    R"( "dynamic": true, "mass_kg": 0.05}]})";

const char* kStaticScene =
    R"({"format": "hapto-scene", "version": 1, "objects": [)"
    R"({"id": 1, "shape": "box", "center": [0, 0, 0], "half_extents": [0.02, 0.02, 0.02]}]})";

/// Runs `hapto run --scene DIR/drop.json ARGS --report DIR/rK.json` twice (k = 0, 1), each
/// to exit code 0 with the dynamics in its table; returns both reports.
std::array<std::string, 2> twoRuns(const TempDir& dir, const std::string& args) {
    writeFile(dir / "drop.json", kDropScene);
    std::array<std::string, 2> reports;
    for (int k = 0; k < 2; ++k) {
        const auto report = dir / ("r" + std::to_string(k) + ".json");
        const CommandResult r = runHapto("run --scene " + (dir / "drop.json").string() + " " +
                                         args + " --report " + report.string());
        INFO(r.output);
        REQUIRE(r.exitCode == 0);
        CHECK_THAT(r.output, Catch::Contains("dynamics") && Catch::Contains("body 5"));
        reports[static_cast<std::size_t>(k)] = readFile(report);
    }
    return reports;
}

} // namespace

TEST_CASE("hapto run --no-devices --stepped runs the bodies alone, the same every run",
          "[threads]") {
    TempDir dir;
    const auto reports = twoRuns(dir, "--no-devices --stepped --quiet --duration 0.2");
    CHECK(reports[0] == reports[1]);
    const json j = json::parse(reports[0]);
    CHECK(j["devices"].empty());
    CHECK(j["dynamics"]["rate_hz"] == 500.0);
    CHECK(j["dynamics"]["steps"] == 100);
    CHECK(j["dynamics"]["missed_deadlines"] == 0);
    CHECK(j["dynamics"]["stable"] == true);
    CHECK(j["dynamics"]["bodies"][0]["id"] == 5);
    CHECK(j["total"]["stable"] == true);
}

TEST_CASE("hapto run --no-devices is refused when the scene has no dynamic body", "[threads]") {
    TempDir dir;
    writeFile(dir / "static.json", kStaticScene);
    const CommandResult r = runHapto("run --scene " + (dir / "static.json").string() +
                                     " --no-devices --stepped --duration 0.1");
    INFO(r.output);
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("--no-devices") &&
                             Catch::Contains("has no dynamic body") &&
                             Catch::Contains("nothing would run"));
    const CommandResult byDefault = runHapto("run --no-devices --stepped --duration 0.1");
    CHECK(byDefault.exitCode == 2);
    CHECK_THAT(byDefault.output, Catch::Contains("the default scene has no dynamic body"));
    const CommandResult both =
        runHapto("run --scene " + (dir / "static.json").string() + " --no-devices --devices " +
                 (dir / "static.json").string() + " --duration 0.1");
    CHECK(both.exitCode == 2);
    CHECK_THAT(both.output, Catch::Contains("not both"));
}

TEST_CASE("hapto run --stepped drives simulated hands byte-identically, and refuses hardware",
          "[threads]") {
    TempDir dir;
    const auto reports = twoRuns(dir, "--stepped --quiet --duration 0.1");
    CHECK(reports[0] == reports[1]);
    const json j = json::parse(reports[0]);
    REQUIRE(j["devices"].size() == 2);
    CHECK(j["devices"][0]["ticks"] == 100);
    CHECK(j["dynamics"]["steps"] == 50);

    for (const char* kind : {"falcon", "phantom"}) {
        writeFile(dir / "hw.json",
                  std::string(R"({"format": "hapto-devices", "version": 1, "devices": [)") +
                      R"({"name": "hw", "kind": ")" + kind + R"("}]})");
        const CommandResult r =
            runHapto("run --devices " + (dir / "hw.json").string() + " --stepped --duration 0.1");
        INFO(r.output);
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("--stepped: device 'hw' is a " + std::string(kind)));
    }
}

TEST_CASE("hapto run --record writes bodies.trace, and trace export gives its columns",
          "[threads]") {
    TempDir dir;
    writeFile(dir / "drop.json", kDropScene);
    const CommandResult r = runHapto("run --scene " + (dir / "drop.json").string() +
                                     " --no-devices --stepped --quiet --duration 0.1 --record " +
                                     (dir / "runs").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    REQUIRE(std::filesystem::exists(dir / "runs/bodies.trace"));
    const CommandResult csv = runHapto("trace export " + (dir / "runs/bodies.trace").string() +
                                       " -o " + (dir / "bodies.csv").string());
    INFO(csv.output);
    REQUIRE(csv.exitCode == 0);
    const std::vector<std::string> lines = linesOf(readFile(dir / "bodies.csv"));
    REQUIRE(lines.size() == 1 + 51); // the header, step 0 and 50 steps of one body
    CHECK(lines[0].rfind("time_s,id,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz", 0) == 0);
    CHECK(lines[1].rfind("0,5,0,0.1,0,1,0,0,0,0,0,0,0,0,0", 0) == 0); // at rest where it starts
    CHECK(lines.back().rfind("0.1,5,", 0) == 0);
    // The body falls: its height at the end is below where it started.
    const std::string& last = lines.back();
    std::vector<double> v;
    std::size_t at = 0;
    while (at <= last.size()) {
        const std::size_t comma = std::min(last.find(',', at), last.size());
        v.push_back(std::stod(last.substr(at, comma - at)));
        at = comma + 1;
    }
    REQUIRE(v.size() == 15);
    CHECK(v[3] < 0.1);
    CHECK(v[10] < 0.0); // vy
}
