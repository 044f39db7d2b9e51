#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/FalconDevice.h"
#include "hapto/devices/PhantomDevice.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"
#include "hapto/scenes/Generators.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

using namespace hapto;

namespace {

std::string errorOf(const std::string& text) {
    try {
        parseDeviceConfig(text, "bad.json");
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

} // namespace

TEST_CASE("the README dual-device example loads with its values") {
    const auto configs = parseDeviceConfig(
        test::guideJsonBlock("devices.md", "## Device configuration files", 0), "example.json");
    REQUIRE(configs.size() == 2);
    CHECK(configs[0].name == "left");
    CHECK(configs[1].name == "right");
    for (const DeviceConfig& c : configs) {
        CHECK(c.kind == DeviceKind::Sim);
        CHECK(c.rateHz == 1000.0);
        CHECK(c.maxForceN == 8.5);
        CHECK(c.transform.scale == 1.0);
        CHECK(c.transform.rotation == Quat(1, 0, 0, 0));
    }
    CHECK(configs[0].transform.translation == Vec3(-0.02, 0, 0));
    CHECK(configs[1].transform.translation == Vec3(0.02, 0, 0));
    CHECK(std::get<SimConfig>(configs[0].params).script == HandScript::GraspLeft);
    CHECK(std::get<SimConfig>(configs[1].params).script == HandScript::GraspRight);
    CHECK(std::get<SimConfig>(configs[1].params).seed == 2);
}

TEST_CASE("the README hardware example loads, relative traces resolve against the file") {
    test::TempDir dir;
    test::writeFile(dir / "d.json",
                    test::guideJsonBlock("devices.md", "## Device configuration files", 1));
    const auto configs = loadDeviceConfigFile(dir / "d.json");
    REQUIRE(configs.size() == 3);
    const auto& falcon = std::get<FalconConfig>(configs[0].params);
    CHECK(falcon.serial == "FHS0A1B2");
    CHECK(falcon.home);
    CHECK(falcon.bus == -1);
    CHECK(std::get<PhantomConfig>(configs[1].params).deviceName == "Right PHANToM");
    CHECK(std::get<PhantomConfig>(configs[1].params).library == "libHD.so");
    const auto& replay = std::get<ReplayConfig>(configs[2].params);
    CHECK(replay.loop);
    CHECK(replay.trace == dir.path() / "runs/left.trace");
    CHECK(configs[2].rateHz == 1000.0);
}

TEST_CASE("a device entry's effects and renderer go to the reader given, unread without one") {
    const std::string text =
        test::deviceFileWith(R"("effects": [{"type": "magnet"}], "renderer": 7)");
    // They are the runtime's to read (hapto/runtime/DeviceFile.h): without a reader a program
    // that only places devices passes over them.
    CHECK(parseDeviceConfig(text, "r.json").size() == 1);
    std::vector<std::string> seen;
    parseDeviceConfig(text, "r.json",
                      [&seen](std::size_t device, const nlohmann::json& entry,
                              const json::Source& source, const json::Path& path) {
                          seen.push_back(std::to_string(device) + " " + std::string(source.name()) +
                                         " " + path.str() + " " + entry.at("effects").dump() + " " +
                                         entry.at("renderer").dump());
                      });
    CHECK(seen == std::vector<std::string>{R"(0 r.json devices[0] [{"type":"magnet"}] 7)"});
    // A reader's refusal is the file's, with its path.
    CHECK_THROWS_WITH(parseDeviceConfig(text, "r.json",
                                        [](std::size_t, const nlohmann::json&,
                                           const json::Source& source, const json::Path& path) {
                                            source.fail(path / "renderer", "not a setting");
                                        }),
                      "r.json: devices[0].renderer: not a setting");
}

TEST_CASE("defaults apply to a minimal device") {
    const auto configs = parseDeviceConfig(test::deviceFileWith(""), "min.json");
    REQUIRE(configs.size() == 1);
    const DeviceConfig& c = configs[0];
    CHECK(c.rateHz == 1000.0);
    CHECK(c.maxForceN == 0.0);
    CHECK(c.transform.translation == Vec3(0.0));
    const SimConfig& s = std::get<SimConfig>(c.params);
    CHECK(s.script == HandScript::Walk);
    CHECK(s.seed == 1);
    CHECK(s.handStiffness == 300.0);
    CHECK_FALSE(s.object.has_value());
}

TEST_CASE("every sim field parses") {
    const auto configs = parseDeviceConfig(
        test::deviceFileWith(
            R"("sim": {"script": "slide", "seed": 18446744073709551615, "start": [0.01, 0, 0],
          "object": 7, "near": [0, 0.1, 0], "press_n": 2, "max_speed_m_per_s": 0.3,
          "lift": [0, 0.04, 0], "carry": [0, 0, 0.1], "hand_mass_kg": 0.2,
          "hand_stiffness_n_per_m": 400, "hand_damping_ratio": 0.8, "resolution_m": 0,
          "noise_m": 0})"),
        "all.json");
    const SimConfig& s = std::get<SimConfig>(configs[0].params);
    CHECK(s.script == HandScript::Slide);
    CHECK(s.seed == 18446744073709551615ull);
    CHECK(s.start == Vec3(0.01, 0, 0));
    CHECK(s.object == 7u);
    CHECK(s.near == Vec3(0, 0.1, 0));
    CHECK(s.pressForceN == 2.0);
    CHECK(s.maxSpeedMPerS == 0.3);
    CHECK(s.lift == Vec3(0, 0.04, 0));
    CHECK(s.carry == Vec3(0, 0, 0.1));
    CHECK(s.handMassKg == 0.2);
    CHECK(s.handStiffness == 400.0);
    CHECK(s.handDampingRatio == 0.8);
    CHECK(s.resolutionM == 0.0);
    CHECK(s.noiseM == 0.0);
}

TEST_CASE("falcon and phantom command timeouts default to two servo periods, at most 10 ms") {
    const auto one = [](const std::string& device) {
        return parseDeviceConfig(R"({"format": "hapto-devices", "version": 1, "devices": [)" +
                                     device + "]}",
                                 "t.json")[0];
    };
    // 1 kHz: 2 ms; 4 kHz: 0.5 ms; 100 Hz: 20 ms would be two periods, capped at 10 ms.
    CHECK(
        std::get<FalconConfig>(one(R"({"name": "f", "kind": "falcon"})").params).commandTimeoutMs ==
        Approx(2.0));
    CHECK(std::get<FalconConfig>(one(R"({"name": "f", "kind": "falcon", "rate_hz": 4000})").params)
              .commandTimeoutMs == Approx(0.5));
    CHECK(std::get<PhantomConfig>(one(R"({"name": "p", "kind": "phantom", "rate_hz": 500,
                                          "phantom": {"device": "x"}})")
                                      .params)
              .commandTimeoutMs == Approx(4.0));
    CHECK(std::get<PhantomConfig>(one(R"({"name": "p", "kind": "phantom", "rate_hz": 100})").params)
              .commandTimeoutMs == Approx(10.0));
    CHECK(defaultCommandTimeoutMs(100.0) == kMaxCommandTimeoutMs);
    // Given values are kept, from one servo period up to 10 ms.
    const auto f = std::get<FalconConfig>(one(R"({"name": "f", "kind": "falcon",
                "falcon": {"command_timeout_ms": 1, "motor_word_limit": 4095}})")
                                              .params);
    CHECK(f.commandTimeoutMs == 1.0);
    CHECK(f.motorWordLimit == 4095);
    CHECK(std::get<PhantomConfig>(one(R"({"name": "p", "kind": "phantom",
                                          "phantom": {"command_timeout_ms": 10}})")
                                      .params)
              .commandTimeoutMs == 10.0);
    // The motor word limit defaults to the public headers' 4096.
    CHECK(std::get<FalconConfig>(one(R"({"name": "f", "kind": "falcon"})").params).motorWordLimit ==
          4096);
}

TEST_CASE("every bad input names the file and its JSON path") {
    struct Case {
        std::string text;
        std::string where;
    };
    const std::string two =
        R"({"format": "hapto-devices", "version": 1, "devices": [{"name": "a", "kind": "sim"}, )";
    const std::vector<Case> cases = {
        {"[1, 2]", "bad.json: (top level): expected a JSON object"},
        {"{\"format\": \"hapto-devices\",", "bad.json:1:"},
        {R"({"format": "hapto-scene", "version": 1, "devices": []})", "bad.json: format:"},
        {R"({"format": "hapto-devices", "version": 2, "devices": []})", "bad.json: version:"},
        {R"({"format": "hapto-devices", "version": 1})", "missing required field 'devices'"},
        {R"({"format": "hapto-devices", "version": 1, "devices": []})",
         "bad.json: devices: list at least one device"},
        {R"({"format": "hapto-devices", "version": 1, "devices": [], "extra": 1})",
         "bad.json: (top level): unknown field 'extra'"},
        {R"({"format": "hapto-devices", "version": 1, "devices": [3]})",
         "bad.json: devices[0]: expected an object"},
        {two + R"({"name": "a", "kind": "sim"}]})",
         "bad.json: devices[1].name: duplicate name 'a' (also at devices[0])"},
        {two + R"({"name": "", "kind": "sim"}]})", "bad.json: devices[1].name:"},
        {two + R"({"name": "b c", "kind": "sim"}]})", "bad.json: devices[1].name:"},
        {two + R"({"kind": "sim"}]})", "bad.json: devices[1]: missing required field 'name'"},
        {two + R"({"name": "b", "kind": "robot"}]})", "bad.json: devices[1].kind: unknown kind"},
        {two + R"({"name": "b", "kind": "sim", "rate_hz": 50}]})",
         "bad.json: devices[1].rate_hz: the rate (Hz) must be >= 100"},
        {two + R"({"name": "b", "kind": "sim", "rate_hz": 200000}]})",
         "bad.json: devices[1].rate_hz: the rate (Hz) must be <= 100000"},
        {two + R"({"name": "b", "kind": "sim", "rate_hz": "fast"}]})",
         "bad.json: devices[1].rate_hz: expected a number, got a string"},
        {two + R"({"name": "b", "kind": "sim", "max_force_n": -1}]})",
         "bad.json: devices[1].max_force_n: the max force (N) must be >= 0"},
        {two + R"({"name": "b", "kind": "sim", "transform": {"scale": 0}}]})",
         "bad.json: devices[1].transform.scale: the scale must be > 0 (got 0)"},
        {two + R"({"name": "b", "kind": "sim", "transform": {"rotation": [1, 1, 0, 0]}}]})",
         "bad.json: devices[1].transform.rotation: must be a unit quaternion"},
        {two + R"({"name": "b", "kind": "sim", "transform": {"translation": [0, 0]}}]})",
         "bad.json: devices[1].transform.translation: expected an array of 3 numbers"},
        {two + R"({"name": "b", "kind": "sim", "transform": {"translation": [0, "x", 0]}}]})",
         "bad.json: devices[1].transform.translation[1]: expected a number"},
        {two + R"({"name": "b", "kind": "sim", "transform": {"shear": 1}}]})",
         "bad.json: devices[1].transform: unknown field 'shear'"},
        {two + R"({"name": "b", "kind": "sim", "colour": "red"}]})",
         "bad.json: devices[1]: unknown field 'colour'"},
        {two + R"({"name": "b", "kind": "sim", "sim": {"script": "dance"}}]})",
         "bad.json: devices[1].sim.script: unknown script 'dance'"},
        {two + R"({"name": "b", "kind": "sim", "sim": {"seed": -1}}]})",
         "bad.json: devices[1].sim.seed: expected a non-negative integer"},
        {two + R"({"name": "b", "kind": "sim", "sim": {"speed": 1}}]})",
         "bad.json: devices[1].sim: unknown field 'speed'"},
        {two + R"({"name": "b", "kind": "sim", "sim": {"hand_mass_kg": 0}}]})",
         "bad.json: devices[1].sim.hand_mass_kg:"},
        {two + R"({"name": "b", "kind": "sim", "sim": {"noise_m": -0.001}}]})",
         "bad.json: devices[1].sim.noise_m:"},
        {two + R"({"name": "b", "kind": "sim", "sim": {"object": -3}}]})",
         "bad.json: devices[1].sim.object: must be in 0.."},
        {two + R"({"name": "b", "kind": "sim", "replay": {"trace": "x"}}]})",
         "bad.json: devices[1].replay: settings for kind 'replay' on a device of kind 'sim'"},
        {two + R"({"name": "b", "kind": "replay"}]})",
         "bad.json: devices[1]: a replay device needs"},
        {two + R"({"name": "b", "kind": "replay", "replay": {"trace": 3}}]})",
         "bad.json: devices[1].replay.trace: expected a string"},
        {two + R"({"name": "b", "kind": "replay", "replay": {"trace": "t", "loop": 1}}]})",
         "bad.json: devices[1].replay.loop: expected true or false"},
        {two + R"({"name": "b", "kind": "falcon", "falcon": {"bus": 999}}]})",
         "bad.json: devices[1].falcon.bus: must be in -1..255"},
        {two + R"({"name": "b", "kind": "falcon", "falcon": {"home": "yes"}}]})",
         "bad.json: devices[1].falcon.home: expected true or false"},
        {two + R"({"name": "b", "kind": "phantom", "phantom": {"library": ""}}]})",
         "bad.json: devices[1].phantom.library:"},
        {two + R"({"name": "b", "kind": "phantom", "phantom": {"serial": "x"}}]})",
         "bad.json: devices[1].phantom: unknown field 'serial'"},
        {two + R"({"name": "b", "kind": "falcon", "falcon": {"motor_word_limit": 0}}]})",
         "bad.json: devices[1].falcon.motor_word_limit: the motor word limit must be a whole "
         "number of motor counts in 1..32767 (got 0)"},
        {two + R"({"name": "b", "kind": "falcon", "falcon": {"motor_word_limit": 40000}}]})",
         "bad.json: devices[1].falcon.motor_word_limit: the motor word limit must be a whole "
         "number of motor counts in 1..32767 (got 40000)"},
        {two + R"({"name": "b", "kind": "falcon", "falcon": {"motor_word_limit": 4095.5}}]})",
         "bad.json: devices[1].falcon.motor_word_limit: the motor word limit must be a whole"},
        {two + R"({"name": "b", "kind": "falcon", "falcon": {"motor_word_limit": "4096"}}]})",
         "bad.json: devices[1].falcon.motor_word_limit:"},
        {two + R"({"name": "b", "kind": "falcon", "falcon": {"command_timeout_ms": 0}}]})",
         "bad.json: devices[1].falcon.command_timeout_ms: the command timeout (ms; how long a "
         "stalled servo's last force may still be applied) must be > 0 (got 0)"},
        {two + R"({"name": "b", "kind": "falcon", "falcon": {"command_timeout_ms": 100}}]})",
         "bad.json: devices[1].falcon.command_timeout_ms: the command timeout (ms; how long a "
         "stalled servo's last force may still be applied) must be <= 10 (got 100)"},
        {two + R"({"name": "b", "kind": "phantom", "phantom": {"command_timeout_ms": -1}}]})",
         "bad.json: devices[1].phantom.command_timeout_ms: the command timeout"},
        {two + R"({"name": "b", "kind": "phantom", "phantom": {"command_timeout_ms": "2"}}]})",
         "bad.json: devices[1].phantom.command_timeout_ms: expected a number, got a string"},
        {two + R"({"name": "b", "kind": "phantom", "rate_hz": 200,
                   "phantom": {"command_timeout_ms": 4}}]})",
         "bad.json: devices[1].phantom.command_timeout_ms: the command timeout (4 ms) is shorter "
         "than one servo period (5 ms at rate_hz 200)"},
        {two + R"({"name": "b", "kind": "sim", "sim": {"command_timeout_ms": 2}}]})",
         "bad.json: devices[1].sim: unknown field 'command_timeout_ms'"},
    };
    for (const Case& c : cases) {
        INFO(c.text);
        const std::string e = errorOf(c.text);
        CHECK_THAT(e, Catch::Contains(c.where));
    }
}

TEST_CASE("a deeply nested wrong value is named by its type, not printed") {
    // The message used to dump() the value, which recurses once per level: 12000 levels
    // overflowed the stack under ASan (corpus crash-deep-version-dump.json).
    const std::string deep = std::string(12000, '[') + std::string(12000, ']');
    CHECK(errorOf(R"({"format": "hapto-devices", "version": )" + deep + R"(, "devices": []})") ==
          "bad.json: version: this build reads version 1, got an array");
    CHECK(errorOf(R"({"format": {"a": )" + deep + R"(}, "version": 1, "devices": []})") ==
          "bad.json: format: expected \"hapto-devices\", got an object");
    // A long wrong string is cut short.
    const std::string e =
        errorOf(R"({"format": ")" + std::string(5000, 'x') + R"(", "version": 1, "devices": []})");
    CHECK_THAT(e, Catch::StartsWith("bad.json: format: expected \"hapto-devices\", got \"xxx"));
    CHECK_THAT(e, Catch::EndsWith("xxx..."));
    CHECK(e.size() < 200);
}

TEST_CASE("a missing file is refused with its name") {
    CHECK_THROWS_WITH(loadDeviceConfigFile("/nonexistent/d.json"),
                      Catch::Contains("/nonexistent/d.json: cannot open"));
}

TEST_CASE("the default devices are two simulated hands side by side in the clear region") {
    const auto configs = defaultDeviceConfigs();
    REQUIRE(configs.size() == 2);
    CHECK(configs[0].name == "left");
    CHECK(configs[1].name == "right");
    CHECK(configs[0].transform.translation == Vec3(-0.02, 0, 0));
    CHECK(configs[1].transform.translation == Vec3(0.02, 0, 0));
    const Scene scene = makeDefaultScene();
    for (const DeviceConfig& c : configs) {
        CHECK(c.kind == DeviceKind::Sim);
        CHECK(c.rateHz == 1000.0);
        const Vec3 start = c.transform.positionToWorld(std::get<SimConfig>(c.params).start);
        for (const SceneObject& o : scene.objects()) {
            CHECK_FALSE(o.contains(start));
        }
        auto device = makeDevice(c, scene);
        CHECK(device->name() == c.name);
        CHECK(device->open() == DeviceStatus::Ok);
    }
}

TEST_CASE("the factory makes every kind, and hardware kinds fail at open, not before") {
    const Scene scene = makeDefaultScene();
    DeviceConfig c = defaultDeviceConfigs()[0];
    CHECK(dynamic_cast<SimDevice*>(makeDevice(c, scene).get()) != nullptr);
    c.kind = DeviceKind::Falcon;
    c.params = FalconConfig{};
    auto falcon = makeDevice(c, scene);
    CHECK(dynamic_cast<FalconDevice*>(falcon.get()) != nullptr);
    CHECK(falcon->kind() == DeviceKind::Falcon);
    c.kind = DeviceKind::Phantom;
    PhantomConfig phantom;
    phantom.library = "libHD-that-does-not-exist.so";
    c.params = phantom;
    auto ph = makeDevice(c, scene);
    CHECK(dynamic_cast<PhantomDevice*>(ph.get()) != nullptr);
    CHECK(ph->open() != DeviceStatus::Ok); // no OpenHaptics here: a clear error, no throw
    CHECK_THAT(ph->errorMessage(), Catch::Contains("libHD-that-does-not-exist.so"));
    c.kind = DeviceKind::Scripted; // made by the program, never by the factory
    CHECK_THROWS_AS(makeDevice(c, scene), InputError);
    c.kind = DeviceKind::Sim;
    SimConfig sim;
    sim.object = 123456;
    c.params = sim;
    CHECK_THROWS_WITH(makeDevice(c, scene), Catch::Contains("123456"));
}

TEST_CASE("device kinds and hand scripts: parsed once, printed back the same") {
    for (const DeviceKind k :
         {DeviceKind::Sim, DeviceKind::Replay, DeviceKind::Falcon, DeviceKind::Phantom}) {
        CHECK(parseDeviceKind(name(k)) == k);
    }
    CHECK(name(DeviceKind::Scripted) == "scripted");
    CHECK_FALSE(parseDeviceKind("scripted").has_value()); // never from a file
    CHECK_FALSE(parseDeviceKind("Sim").has_value());
    CHECK_FALSE(parseDeviceKind("").has_value());
    for (const HandScript s : {HandScript::Free, HandScript::Touch, HandScript::Slide,
                               HandScript::Walk, HandScript::GraspLeft, HandScript::GraspRight}) {
        CHECK(parseHandScript(name(s)) == s);
    }
    CHECK(name(HandScript::GraspLeft) == "grasp-left");
    CHECK_FALSE(parseHandScript("dance").has_value());
}

TEST_CASE("tool_tip, a sim stylus and the replay's own settings parse, bad ones name their path") {
    const auto configs = parseDeviceConfig(test::deviceFileWith(R"("tool_tip": [0, 0, -0.04],
                      "sim": {"orientation": [0, 1, 0, 0], "spin_rad_per_s": [0, 0.5, 0]})"),
                                           "tip.json");
    CHECK(configs[0].toolTipM == Vec3(0.0, 0.0, -0.04));
    const SimConfig& s = std::get<SimConfig>(configs[0].params);
    REQUIRE(s.orientation.has_value());
    CHECK(*s.orientation == Quat{0, 1, 0, 0});
    CHECK(s.spinRadPerS == Vec3(0.0, 0.5, 0.0));
    CHECK(parseDeviceConfig(test::deviceFileWith(""), "min.json")[0].toolTipM == Vec3(0.0));

    const std::string replay = R"({"format": "hapto-devices", "version": 1, "devices": [)";
    const auto own = parseDeviceConfig(
        replay + R"({"name": "r", "kind": "replay", "rate_hz": 500, "tool_tip": [0, 0, 0.01],
                     "replay": {"trace": "r.trace"}}]})",
        "own.json");
    const ReplayConfig& r = std::get<ReplayConfig>(own[0].params);
    CHECK(r.ownRate);
    CHECK(r.ownToolTip);
    CHECK_FALSE(r.ownTransform);
    CHECK_FALSE(r.ownMaxForce);

    CHECK_THAT(errorOf(test::deviceFileWith(R"("tool_tip": [0, 0.6, 0])")),
               Catch::Contains("bad.json: devices[0].tool_tip[1]: a tool tip component is at "
                               "most 0.5 m (got 0.6)"));
    CHECK_THAT(errorOf(test::deviceFileWith(R"("tool_tip": [0, 0])")),
               Catch::Contains("bad.json: devices[0].tool_tip"));
    CHECK_THAT(errorOf(test::deviceFileWith(R"("sim": {"orientation": [2, 0, 0, 0]})")),
               Catch::Contains("bad.json: devices[0].sim.orientation"));
    CHECK_THAT(errorOf(test::deviceFileWith(R"("sim": {"spin_rad_per_s": [0, 0, 1000]})")),
               Catch::Contains("bad.json: devices[0].sim.spin_rad_per_s[2]"));
}

TEST_CASE("a value just past a limit is shown with the digits that put it past the limit") {
    CHECK_THAT(errorOf(test::deviceFileWith(R"("tool_tip": [0, 0.5000001, 0])")),
               Catch::Contains("bad.json: devices[0].tool_tip[1]: a tool tip component is at "
                               "most 0.5 m (got 0.5000001)"));
    CHECK_THAT(
        errorOf(test::deviceFileWith(R"("sim": {"hand_damping_ratio": 100.00000000000001})")),
        Catch::Contains("the damping ratio must be <= 100 (got 100.00000000000001)"));
    // Round values stay short.
    CHECK_THAT(errorOf(test::deviceFileWith(R"("rate_hz": 1e9)")),
               Catch::Contains("the rate (Hz) must be <= 100000 (got 1e+09)"));
}

TEST_CASE("a device file in UTF-16, or with a NUL or a stray byte, is named as such, escaped") {
    const std::string json = test::deviceFileWith("");
    std::string utf16 = "\xFF\xFE";
    for (const char c : json) {
        utf16 += c;
        utf16 += '\0';
    }
    CHECK(errorOf(utf16) == "bad.json: not UTF-8 text: the file starts with a UTF-16 byte order "
                            "mark; save it as UTF-8");
    // Without its mark: the first NUL is named.
    CHECK_THAT(errorOf(utf16.substr(2)),
               Catch::Contains("bad.json:1:2: not valid JSON: a NUL byte (byte 1)"));
    // A byte that is not UTF-8 is written as an escape, never as itself.
    const std::string stray = errorOf("{\"format\": \xFF}");
    CHECK_THAT(stray, Catch::Contains("bad.json:1:12: not valid JSON:"));
    CHECK_THAT(stray, Catch::Contains("\\xFF"));
    CHECK(stray.find('\xFF') == std::string::npos);
}

TEST_CASE("a device name with control characters is shown escaped in its message") {
    const std::string e = errorOf(test::deviceFileWith("").replace(
        test::deviceFileWith("").find("\"a\""), 3, R"("a\nb\u0000c\u001b[2J")"));
    CHECK_THAT(e, Catch::Contains("bad.json: devices[0].name: a device name is 1 to 63 letters"));
    CHECK_THAT(e, Catch::Contains(R"((got "a\nb\u0000c\u001b[2J"))"));
    CHECK(std::none_of(e.begin(), e.end(), [](char c) { return c >= 0 && c < 0x20; }));
    // So are an unknown field, kind and script.
    CHECK_THAT(errorOf(test::deviceFileWith(R"("\u001b[2J": 1)")),
               Catch::Contains(R"(bad.json: devices[0]: unknown field '\x1B[2J')"));
    CHECK_THAT(errorOf(test::deviceFileWith(R"("sim": {"script": "a\nb"})")),
               Catch::Contains(R"(devices[0].sim.script: unknown script 'a\nb')"));
    std::string badKind = test::deviceFileWith("");
    badKind.replace(badKind.find(R"("sim")"), 5, R"("s\u0000m")");
    CHECK_THAT(errorOf(badKind), Catch::Contains(R"(devices[0].kind: unknown kind 's\x00m')"));
}
