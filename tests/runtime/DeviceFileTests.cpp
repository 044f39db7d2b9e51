// Device files as the runtime reads them: each entry's force effects (`effects`) and renderer
// settings (`renderer`), with every bad value named by the file and its JSON path, beside the
// device's own fields (tests/devices/DeviceConfigTests.cpp).

#include "hapto/io/InputError.h"
#include "hapto/runtime/DeviceFile.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <string>

using namespace hapto;

namespace {

std::string errorOf(const std::string& text) {
    try {
        parseDeviceFile(text, "bad.json");
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

} // namespace

TEST_CASE("the user guide's effects example loads: springs to a plane and a line, a damper in a "
          "sphere, a constant force that is off, and the contact damping") {
    const DeviceFile file = parseDeviceFile(
        test::guideJsonBlock("devices.md", "## Device configuration files", 2), "effects.json");
    REQUIRE(file.devices.size() == 1);
    REQUIRE(file.rendering.size() == 1);
    const DeviceRendering& c = file.rendering[0];
    REQUIRE(c.renderer.contactDampingNsPerM.has_value());
    CHECK(*c.renderer.contactDampingNsPerM == 2.0);
    REQUIRE(c.effects.size() == 4);
    const ForceEffect& plane = c.effects[0];
    CHECK(plane.type == EffectType::Spring);
    CHECK(plane.target == SpringTarget::Plane);
    CHECK(plane.anchorM == Vec3(0, 0.05, 0));
    CHECK(plane.axis == Vec3(0, 1, 0));
    CHECK(plane.stiffnessNPerM == 200.0);
    CHECK(plane.enabled);
    CHECK(plane.region.shape == RegionShape::Everywhere);
    const ForceEffect& line = c.effects[1];
    CHECK(line.target == SpringTarget::Line);
    CHECK(line.axis == Vec3(1, 0, 0));
    CHECK(line.stiffnessNPerM == 50.0);
    const ForceEffect& damper = c.effects[2];
    CHECK(damper.type == EffectType::Damper);
    CHECK(damper.dampingNsPerM == 5.0);
    CHECK(damper.region.shape == RegionShape::Sphere);
    CHECK(damper.region.centerM == Vec3(0, 0, 0));
    CHECK(damper.region.radiusM == 0.02);
    const ForceEffect& constant = c.effects[3];
    CHECK(constant.type == EffectType::Constant);
    CHECK(constant.forceN == Vec3(0, -0.5, 0));
    CHECK_FALSE(constant.enabled);
}

TEST_CASE("effects: a spring to a point, a box region, a normalised axis, and none by default") {
    const DeviceFile file = parseDeviceFile(test::deviceFileWith(R"("effects": [
        {"type": "spring", "anchor": [0.1, 0.2, 0.3], "stiffness_n_per_m": 0},
        {"type": "spring", "anchor": [0, 0, 0], "stiffness_n_per_m": 10000, "direction": [0, 3, 4]},
        {"type": "damper", "damping_n_s_per_m": 100, "enabled": true,
         "region": {"box": {"center": [1, 2, 3], "half_extents": [0.1, 0.2, 0.3]}}},
        {"type": "constant", "force_n": [0, 0, 100], "region": {"sphere": {"center": [0, 0, 0],
         "radius_m": 1e6}}}])"),
                                            "e.json");
    const std::vector<ForceEffect>& e = file.renderingOf(0).effects;
    REQUIRE(e.size() == 4);
    CHECK(e[0].target == SpringTarget::Point);
    CHECK(e[0].anchorM == Vec3(0.1, 0.2, 0.3));
    CHECK(e[0].stiffnessNPerM == 0.0); // the limits are inclusive
    CHECK(e[1].axis == Vec3(0, 0.6, 0.8));
    CHECK(e[1].stiffnessNPerM == kMaxEffectStiffnessNPerM);
    CHECK(e[2].region.shape == RegionShape::Box);
    CHECK(e[2].region.centerM == Vec3(1, 2, 3));
    CHECK(e[2].region.halfExtentsM == Vec3(0.1, 0.2, 0.3));
    CHECK(e[2].dampingNsPerM == kMaxDampingNsPerM);
    CHECK(e[3].forceN == Vec3(0, 0, kMaxEffectForceN));
    CHECK(e[3].region.radiusM == kMaxEffectLengthM);
    for (const ForceEffect& effect : e) {
        CHECK_FALSE(checkForceEffect(effect).has_value());
    }

    const DeviceRendering plain =
        parseDeviceFile(test::deviceFileWith(""), "p.json").renderingOf(0);
    CHECK(plain.effects.empty());
    CHECK_FALSE(plain.renderer.contactDampingNsPerM.has_value());
    CHECK(parseDeviceFile(test::deviceFileWith(R"("effects": [])"), "p.json")
              .renderingOf(0)
              .effects.empty());
}

TEST_CASE("every bad effect or renderer setting names the file and its JSON path") {
    struct Case {
        std::string text;
        std::string where;
    };
    const std::string two =
        R"({"format": "hapto-devices", "version": 1, "devices": [{"name": "a", "kind": "sim"}, )";
    std::string nineEffects = R"({"type": "constant", "force_n": [0, 0, 1]})";
    for (int i = 1; i < 9; ++i) {
        nineEffects += R"(, {"type": "constant", "force_n": [0, 0, 1]})";
    }
    const std::vector<Case> cases = {
        {two + R"({"name": "b", "kind": "sim", "effects": {"type": "spring"}}]})",
         "bad.json: devices[1].effects: expected an array of effects, got an object"},
        {two + R"({"name": "b", "kind": "sim", "effects": [3]}]})",
         "bad.json: devices[1].effects[0]: expected an object"},
        {two + R"({"name": "b", "kind": "sim", "effects": [{"anchor": [0, 0, 0]}]}]})",
         "bad.json: devices[1].effects[0]: missing required field 'type'"},
        {two + R"({"name": "b", "kind": "sim", "effects": [{"type": "magnet"}]}]})",
         "bad.json: devices[1].effects[0].type: unknown effect type 'magnet' (expected spring, "
         "damper or constant)"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "constant", "force_n": [0, 1, 0]},
            {"type": "spring", "anchor": [0, 0, 0], "stiffness_n_per_m": 1e9}]}]})",
         "bad.json: devices[1].effects[1].stiffness_n_per_m: the stiffness (N/m) must be in "
         "0..10000 (got 1e+09); a stiffer spring only oscillates"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "spring", "anchor": [0, 0, 0], "stiffness_n_per_m": -5}]}]})",
         "bad.json: devices[1].effects[0].stiffness_n_per_m: the stiffness (N/m) must be in "
         "0..10000 (got -5)"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "spring", "stiffness_n_per_m": 100}]}]})",
         "bad.json: devices[1].effects[0]: missing required field 'anchor'"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "spring", "anchor": [0, 0, 0], "stiffness_n_per_m": "stiff"}]}]})",
         "bad.json: devices[1].effects[0].stiffness_n_per_m: expected a number, got a string"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "spring", "anchor": [0, 2e6, 0], "stiffness_n_per_m": 100}]}]})",
         "bad.json: devices[1].effects[0].anchor: the anchor (m) must have each coordinate"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "spring", "anchor": [0, 0, 0], "stiffness_n_per_m": 100,
             "direction": [0, 0, 0]}]}]})",
         "bad.json: devices[1].effects[0].direction: the direction must not be zero"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "spring", "anchor": [0, 0, 0], "stiffness_n_per_m": 100,
             "direction": [0, 0, 1], "normal": [0, 1, 0]}]}]})",
         "bad.json: devices[1].effects[0].normal: a spring pulls to a line"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "damper", "damping_n_s_per_m": 2, "stiffness_n_per_m": 100}]}]})",
         "bad.json: devices[1].effects[0]: unknown field 'stiffness_n_per_m'"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "damper", "damping_n_s_per_m": 500}]}]})",
         "bad.json: devices[1].effects[0].damping_n_s_per_m: the damping (N·s/m) must be in "
         "0..100 (got 500)"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "damper", "damping_n_s_per_m": 2, "region": {}}]}]})",
         "bad.json: devices[1].effects[0].region: a region is one of"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "damper", "damping_n_s_per_m": 2,
             "region": {"sphere": {"center": [0, 0, 0], "radius_m": 0}}}]}]})",
         "bad.json: devices[1].effects[0].region.sphere.radius_m: the radius (m) must be > 0"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "damper", "damping_n_s_per_m": 2,
             "region": {"box": {"center": [0, 0, 0], "half_extents": [0.1, -0.1, 0.1]}}}]}]})",
         "bad.json: devices[1].effects[0].region.box.half_extents: each half extent (m) must be "
         "> 0"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "damper", "damping_n_s_per_m": 2,
             "region": {"box": {"center": [0, 0, 0]}}}]}]})",
         "bad.json: devices[1].effects[0].region.box: missing required field 'half_extents'"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "constant", "force_n": [0, 0, 1000]}]}]})",
         "bad.json: devices[1].effects[0].force_n: the force's magnitude (N) must be in 0..100 "
         "(got 1000)"},
        {two + R"({"name": "b", "kind": "sim", "effects": [
            {"type": "constant", "force_n": [0, 0, 1], "enabled": "yes"}]}]})",
         "bad.json: devices[1].effects[0].enabled: expected true or false"},
        {two + R"({"name": "b", "kind": "sim", "effects": [)" + nineEffects + "]}]}",
         "bad.json: devices[1].effects: at most 8 effects per device (got 9)"},
        {two + R"({"name": "b", "kind": "sim", "renderer": {"damping_n_s_per_m": -1}}]})",
         "bad.json: devices[1].renderer.damping_n_s_per_m: the contact damping (N·s/m) must be "
         ">= 0 (got -1)"},
        {two + R"({"name": "b", "kind": "sim", "renderer": {"damping_n_s_per_m": 1000}}]})",
         "bad.json: devices[1].renderer.damping_n_s_per_m: the contact damping (N·s/m) must be "
         "<= 100 (got 1000)"},
        {two + R"({"name": "b", "kind": "sim", "renderer": {"damping": 1}}]})",
         "bad.json: devices[1].renderer: unknown field 'damping'"},
    };
    for (const Case& c : cases) {
        INFO(c.text);
        const std::string e = errorOf(c.text);
        CHECK_THAT(e, Catch::Contains(c.where));
    }
}

TEST_CASE("an effect value just past a limit is shown with the digits that put it past") {
    CHECK_THAT(errorOf(test::deviceFileWith(R"("effects": [{"type": "damper",
                                                  "damping_n_s_per_m": 100.0000001}])")),
               Catch::Contains("effects[0].damping_n_s_per_m: the damping (N·s/m) must be in "
                               "0..100 (got 100.0000001)"));
}

TEST_CASE("a spring's direction may have any length but zero, and a zero one is shown") {
    const auto spring = [](const std::string& axis) {
        return test::deviceFileWith(R"("effects": [{"type": "spring", "anchor": [0, 0, 0],
                                          "stiffness_n_per_m": 100, "direction": )" +
                                    axis + "}]");
    };
    // Its squares overflow (or underflow), yet it is a direction.
    const ForceEffect huge =
        parseDeviceFile(spring("[1e308, 1e308, 0]"), "a.json").rendering.at(0).effects.at(0);
    CHECK(huge.axis.x == Approx(std::sqrt(0.5)));
    CHECK(huge.axis.y == Approx(std::sqrt(0.5)));
    CHECK(huge.axis.z == 0.0);
    const ForceEffect tiny =
        parseDeviceFile(spring("[0, -1e-200, 1e-200]"), "a.json").rendering.at(0).effects.at(0);
    CHECK(tiny.axis.y == Approx(-std::sqrt(0.5)));
    CHECK(tiny.axis.z == Approx(std::sqrt(0.5)));
    CHECK(errorOf(spring("[0, 0, -0.0]")) ==
          "bad.json: devices[0].effects[0].direction: the direction must not be zero (got [0, 0, "
          "-0])");
}

TEST_CASE("an effect type with control characters is shown escaped in its message") {
    CHECK_THAT(errorOf(test::deviceFileWith(R"("effects": [{"type": "\r"}])")),
               Catch::Contains(R"(devices[0].effects[0].type: unknown effect type '\r')"));
}

TEST_CASE("a device file's first bad value is the one named, whichever module reads it") {
    const std::string head = R"({"format": "hapto-devices", "version": 1, "devices": [)";
    // Device 0's effects come before device 1's fields...
    CHECK_THAT(errorOf(head + R"({"name": "a", "kind": "sim", "effects": [{"type": "magnet"}]},
                                 {"name": "", "kind": "sim"}]})"),
               Catch::StartsWith("bad.json: devices[0].effects[0].type: unknown effect type"));
    // ...and within a device they come after its transform, before its tool tip and settings.
    CHECK_THAT(errorOf(test::deviceFileWith(R"("transform": {"scale": 0}, "effects": [3])")),
               Catch::StartsWith("bad.json: devices[0].transform.scale:"));
    CHECK_THAT(errorOf(test::deviceFileWith(
                   R"("effects": [3], "tool_tip": [1, 0, 0], "sim": {"script": "dance"})")),
               Catch::StartsWith("bad.json: devices[0].effects[0]: expected an object"));
    CHECK_THAT(
        errorOf(test::deviceFileWith(R"("renderer": {"damping": 1}, "tool_tip": [1, 0, 0])")),
        Catch::StartsWith("bad.json: devices[0].renderer: unknown field 'damping'"));
}

TEST_CASE("each device's effects and renderer settings are its own, none when it gives none") {
    const DeviceFile file = parseDeviceFile(
        R"({"format": "hapto-devices", "version": 1, "devices": [{"name": "a", "kind": "sim"},
            {"name": "b", "kind": "sim", "effects": [{"type": "damper", "damping_n_s_per_m": 2}],
             "renderer": {"damping_n_s_per_m": 3}}]})",
        "two.json");
    REQUIRE(file.devices.size() == 2);
    CHECK(file.devices[1].name == "b");
    CHECK(file.renderingOf(0).effects.empty());
    CHECK_FALSE(file.renderingOf(0).renderer.contactDampingNsPerM.has_value());
    REQUIRE(file.renderingOf(1).effects.size() == 1);
    CHECK(file.renderingOf(1).effects[0].dampingNsPerM == 2.0);
    CHECK(file.renderingOf(1).renderer.contactDampingNsPerM == 3.0);
    // Made in code from devices alone: nothing to render besides the scene.
    const DeviceFile inCode{defaultDeviceConfigs(), {}};
    CHECK(inCode.renderingOf(1).effects.empty());
    CHECK_FALSE(inCode.renderingOf(1).renderer.contactDampingNsPerM.has_value());
}

TEST_CASE("a device file on disk: its effects are read and its relative traces resolve") {
    test::TempDir dir;
    test::writeFile(dir / "d.json", R"({"format": "hapto-devices", "version": 1, "devices": [
        {"name": "r", "kind": "replay", "replay": {"trace": "runs/r.trace"},
         "effects": [{"type": "constant", "force_n": [0, 1, 0]}]}]})");
    const DeviceFile file = loadDeviceFile(dir / "d.json");
    CHECK(std::get<ReplayConfig>(file.devices.at(0).params).trace == dir.path() / "runs/r.trace");
    REQUIRE(file.renderingOf(0).effects.size() == 1);
    CHECK(file.renderingOf(0).effects[0].forceN == Vec3(0, 1, 0));
    CHECK_THROWS_WITH(loadDeviceFile(dir / "none.json"),
                      Catch::Contains((dir / "none.json").string() + ": cannot open"));
}
