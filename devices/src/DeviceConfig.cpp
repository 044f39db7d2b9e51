// Device configuration files ("hapto-devices", version 1). Same habits as scene files: every
// field is checked, unknown fields are refused, and every message names the file and the JSON
// path of the bad value (e.g. `devices[1].transform.scale`).

#include "hapto/devices/DeviceConfig.h"

#include "hapto/io/InputError.h"

#include "hapto/io/JsonInput.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace hapto {
namespace {

using namespace hapto::json;

/// The kinds a file may name, each also the name of its settings field.
constexpr std::array<DeviceKind, 4> kFileKinds = {DeviceKind::Sim, DeviceKind::Replay,
                                                  DeviceKind::Falcon, DeviceKind::Phantom};

WorkspaceTransform parseTransform(const Source& w, const Json& j, const Path& path) {
    object(w, j, path);
    checkKeys(w, j, path, {"translation", "rotation", "scale"});
    WorkspaceTransform t;
    if (const Json* v = optional(j, "translation")) {
        t.translation = vec3(w, *v, path / "translation");
    }
    if (const Json* v = optional(j, "rotation")) {
        t.rotation = quaternion(w, *v, path / "rotation");
    }
    if (const Json* v = optional(j, "scale")) {
        t.scale = ranged(w, *v, path / "scale", 0.0, 1e6, true, "the scale");
    }
    return t;
}

SimConfig parseSim(const Source& w, const Json& j, const Path& path) {
    object(w, j, path);
    checkKeys(w, j, path,
              {"script", "seed", "start", "object", "near", "press_n", "max_speed_m_per_s", "lift",
               "carry", "hand_mass_kg", "hand_stiffness_n_per_m", "hand_damping_ratio",
               "resolution_m", "noise_m", "orientation", "spin_rad_per_s"});
    SimConfig c;
    if (const Json* v = optional(j, "script")) {
        const std::string script = string(w, *v, path / "script");
        const std::optional<HandScript> parsed = parseHandScript(script);
        if (!parsed) {
            w.fail(path / "script", "unknown script '" + printable(script) +
                                        "' (expected free, touch, slide, walk, grasp-left or "
                                        "grasp-right)");
        }
        c.script = *parsed;
    }
    if (const Json* v = optional(j, "seed")) {
        if (!v->is_number_integer() || (!v->is_number_unsigned() && v->get<std::int64_t>() < 0)) {
            w.fail(path / "seed", "expected a non-negative integer, got " +
                                      (v->is_number_integer() ? v->dump() : typeName(*v)));
        }
        c.seed = v->get<std::uint64_t>();
    }
    if (const Json* v = optional(j, "start")) {
        c.start = vec3(w, *v, path / "start");
    }
    if (const Json* v = optional(j, "object")) {
        c.object = static_cast<std::uint32_t>(integer(w, *v, path / "object", 0, 0xFFFFFFFEll));
    }
    if (const Json* v = optional(j, "near")) {
        c.near = vec3(w, *v, path / "near");
    }
    if (const Json* v = optional(j, "press_n")) {
        c.pressForceN = ranged(w, *v, path / "press_n", 0.0, 100.0, false, "the press force (N)");
    }
    if (const Json* v = optional(j, "max_speed_m_per_s")) {
        c.maxSpeedMPerS =
            ranged(w, *v, path / "max_speed_m_per_s", 0.0, 10.0, true, "the speed cap (m/s)");
    }
    if (const Json* v = optional(j, "lift")) {
        c.lift = vec3(w, *v, path / "lift");
    }
    if (const Json* v = optional(j, "carry")) {
        c.carry = vec3(w, *v, path / "carry");
    }
    if (const Json* v = optional(j, "hand_mass_kg")) {
        c.handMassKg = ranged(w, *v, path / "hand_mass_kg", 0.0, 100.0, true, "the hand mass (kg)");
    }
    if (const Json* v = optional(j, "hand_stiffness_n_per_m")) {
        c.handStiffness = ranged(w, *v, path / "hand_stiffness_n_per_m", 0.0, 1e6, true,
                                 "the hand stiffness (N/m)");
    }
    if (const Json* v = optional(j, "hand_damping_ratio")) {
        c.handDampingRatio =
            ranged(w, *v, path / "hand_damping_ratio", 0.0, 100.0, false, "the damping ratio");
    }
    if (const Json* v = optional(j, "resolution_m")) {
        c.resolutionM =
            ranged(w, *v, path / "resolution_m", 0.0, 0.01, false, "the resolution (m)");
    }
    if (const Json* v = optional(j, "noise_m")) {
        c.noiseM = ranged(w, *v, path / "noise_m", 0.0, 0.01, false, "the noise (m)");
    }
    if (const Json* v = optional(j, "orientation")) {
        c.orientation = quaternion(w, *v, path / "orientation");
    }
    if (const Json* v = optional(j, "spin_rad_per_s")) {
        c.spinRadPerS = vec3(w, *v, path / "spin_rad_per_s");
        for (int i = 0; i < 3; ++i) {
            checkRange(w, c.spinRadPerS[i], (path / "spin_rad_per_s")[static_cast<std::size_t>(i)],
                       -100.0, 100.0, false, "a spin component (rad/s)");
        }
    }
    return c;
}

ReplayConfig parseReplay(const Source& w, const Json& j, const Path& path) {
    object(w, j, path);
    checkKeys(w, j, path, {"trace", "loop"});
    ReplayConfig c;
    c.trace = string(w, required(w, j, path, "trace"), path / "trace");
    if (c.trace.empty()) {
        w.fail(path / "trace", "the trace path must not be empty");
    }
    if (const Json* v = optional(j, "loop")) {
        c.loop = boolean(w, *v, path / "loop");
    }
    return c;
}

/// `command_timeout_ms` of a device with its own I/O thread, or the default for `rateHz`.
double parseCommandTimeout(const Source& w, const Json& j, const Path& path, double rateHz) {
    const Json* v = optional(j, "command_timeout_ms");
    if (!v) {
        return defaultCommandTimeoutMs(rateHz);
    }
    const Path at = path / "command_timeout_ms";
    const double ms = ranged(w, *v, at, 0.0, kMaxCommandTimeoutMs, true,
                             "the command timeout (ms; how long a stalled servo's last force "
                             "may still be applied)");
    const double periodMs = 1000.0 / rateHz;
    if (ms < periodMs) {
        w.fail(at, "the command timeout (" + show(ms) + " ms) is shorter than one servo period (" +
                       show(periodMs) + " ms at rate_hz " + show(rateHz) +
                       "), so every force would be zeroed before the next one arrives; use at "
                       "least one period (default: two)");
    }
    return ms;
}

FalconConfig parseFalcon(const Source& w, const Json& j, const Path& path, double rateHz) {
    object(w, j, path);
    checkKeys(
        w, j, path,
        {"serial", "bus", "address", "firmware", "home", "motor_word_limit", "command_timeout_ms"});
    FalconConfig c;
    if (const Json* v = optional(j, "serial")) {
        c.serial = string(w, *v, path / "serial");
    }
    if (const Json* v = optional(j, "bus")) {
        c.bus = static_cast<int>(integer(w, *v, path / "bus", -1, 255));
    }
    if (const Json* v = optional(j, "address")) {
        c.address = static_cast<int>(integer(w, *v, path / "address", -1, 255));
    }
    if (const Json* v = optional(j, "firmware")) {
        c.firmware = string(w, *v, path / "firmware");
    }
    if (const Json* v = optional(j, "home")) {
        c.home = boolean(w, *v, path / "home");
    }
    if (const Json* v = optional(j, "motor_word_limit")) {
        const bool whole = v->is_number_integer();
        const bool inRange =
            whole &&
            !(v->is_number_unsigned() &&
              v->get<std::uint64_t>() > std::uint64_t{falcon::kMaxMotorWordLimit}) &&
            v->get<std::int64_t>() >= 1 && v->get<std::int64_t>() <= falcon::kMaxMotorWordLimit;
        if (!inRange) {
            w.fail(path / "motor_word_limit",
                   "the motor word limit must be a whole number of motor counts in 1.." +
                       std::to_string(falcon::kMaxMotorWordLimit) + " (got " + describe(*v) +
                       "); the public headers cap motor values at " +
                       std::to_string(falcon::kDefaultMotorWordLimit) + ", the default");
        }
        c.motorWordLimit = static_cast<int>(v->get<std::int64_t>());
    }
    c.commandTimeoutMs = parseCommandTimeout(w, j, path, rateHz);
    return c;
}

PhantomConfig parsePhantom(const Source& w, const Json& j, const Path& path, double rateHz) {
    object(w, j, path);
    checkKeys(w, j, path, {"device", "library", "command_timeout_ms"});
    PhantomConfig c;
    if (const Json* v = optional(j, "device")) {
        c.deviceName = string(w, *v, path / "device");
    }
    if (const Json* v = optional(j, "library")) {
        c.library = string(w, *v, path / "library");
        if (c.library.empty()) {
            w.fail(path / "library", "the library name must not be empty");
        }
    }
    c.commandTimeoutMs = parseCommandTimeout(w, j, path, rateHz);
    return c;
}

bool validName(const std::string& name) {
    if (name.empty() || name.size() > 63) {
        return false;
    }
    return std::all_of(name.begin(), name.end(), [](char ch) {
        return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') ||
               ch == '-' || ch == '_';
    });
}

DeviceConfig parseDevice(const Source& w, const Json& j, const Path& path, std::size_t index,
                         const DeviceEntryReader& reader) {
    object(w, j, path);
    checkKeys(w, j, path,
              {"name", "kind", "rate_hz", "max_force_n", "transform", "tool_tip", "effects",
               "renderer", "sim", "replay", "falcon", "phantom"});
    DeviceConfig d;
    d.name = string(w, required(w, j, path, "name"), path / "name");
    if (!validName(d.name)) {
        w.fail(path / "name", "a device name is 1 to 63 letters, digits, '-' or '_' (got " +
                                  describe(required(w, j, path, "name")) +
                                  "); it also names trace files");
    }
    const std::string kind = string(w, required(w, j, path, "kind"), path / "kind");
    const std::optional<DeviceKind> parsedKind = parseDeviceKind(kind);
    if (!parsedKind) {
        w.fail(path / "kind",
               "unknown kind '" + printable(kind) + "' (expected sim, replay, falcon or phantom)");
    }
    d.kind = *parsedKind;
    for (const DeviceKind otherKind : kFileKinds) {
        const std::string other(name(otherKind));
        if (otherKind != d.kind && j.contains(other)) {
            w.fail(path / other.c_str(), "settings for kind '" + other + "' on a device of kind '" +
                                             kind + "' (rename the field to '" + kind +
                                             "' or change the kind)");
        }
    }
    if (const Json* v = optional(j, "rate_hz")) {
        d.rateHz = ranged(w, *v, path / "rate_hz", 100.0, 100000.0, false, "the rate (Hz)");
    }
    if (const Json* v = optional(j, "max_force_n")) {
        d.maxForceN =
            ranged(w, *v, path / "max_force_n", 0.0, kUnbounded, false, "the max force (N)");
    }
    if (const Json* v = optional(j, "transform")) {
        d.transform = parseTransform(w, *v, path / "transform");
    }
    if (reader) { // `effects` and `renderer`: here, so a file's first bad value is the one named
        reader(index, j, w, path);
    }
    if (const Json* v = optional(j, "tool_tip")) {
        d.toolTipM = vec3(w, *v, path / "tool_tip");
        for (int i = 0; i < 3; ++i) {
            if (std::abs(d.toolTipM[i]) > kMaxToolTipM) {
                w.fail((path / "tool_tip")[static_cast<std::size_t>(i)],
                       "a tool tip component is at most " + show(kMaxToolTipM) + " m (got " +
                           show(d.toolTipM[i]) + ")");
            }
        }
    }
    const Json* params = optional(j, kind.c_str());
    const Path ppath = path / kind.c_str();
    switch (d.kind) {
    case DeviceKind::Sim:
        d.params = params ? parseSim(w, *params, ppath) : SimConfig{};
        break;
    case DeviceKind::Replay:
        if (!params) {
            w.fail(path, "a replay device needs \"replay\": {\"trace\": \"FILE\"}");
        }
        {
            ReplayConfig r = parseReplay(w, *params, ppath);
            r.ownRate = j.contains("rate_hz");
            r.ownTransform = j.contains("transform");
            r.ownToolTip = j.contains("tool_tip");
            r.ownMaxForce = j.contains("max_force_n");
            d.params = std::move(r);
        }
        break;
    case DeviceKind::Falcon:
        d.params = parseFalcon(w, params ? *params : Json::object(), ppath, d.rateHz);
        break;
    case DeviceKind::Phantom:
    case DeviceKind::Scripted: // parseDeviceKind never gives it
        d.params = parsePhantom(w, params ? *params : Json::object(), ppath, d.rateHz);
        break;
    }
    return d;
}

} // namespace

double defaultCommandTimeoutMs(double rateHz) {
    return std::min(2.0 * 1000.0 / rateHz, kMaxCommandTimeoutMs);
}

std::vector<DeviceConfig> parseDeviceConfig(std::string_view text, std::string_view sourceName,
                                            const DeviceEntryReader& reader) {
    const Source w(sourceName);
    const Path top;
    const Json root = parseText(text, w);
    if (!root.is_object()) {
        w.fail(top,
               "expected a JSON object with \"format\": \"hapto-devices\", got " + typeName(root));
    }
    checkKeys(w, root, top, {"format", "version", "devices"});
    const Json& format = required(w, root, top, "format");
    if (!format.is_string() || format.get<std::string>() != "hapto-devices") {
        w.fail(top / "format", "expected \"hapto-devices\", got " + describe(format));
    }
    const Json& version = required(w, root, top, "version");
    if (!version.is_number_integer() || version.get<std::int64_t>() != kDeviceConfigFormatVersion) {
        w.fail(top / "version", "this build reads version " +
                                    std::to_string(kDeviceConfigFormatVersion) + ", got " +
                                    describe(version));
    }
    const Path devicesPath = top / "devices";
    const Json& devices = required(w, root, top, "devices");
    if (!devices.is_array()) {
        w.fail(devicesPath, "expected an array of devices, got " + typeName(devices));
    }
    if (devices.empty()) {
        w.fail(devicesPath, "list at least one device");
    }
    std::vector<DeviceConfig> out;
    out.reserve(devices.size());
    for (std::size_t i = 0; i < devices.size(); ++i) {
        const Path path = devicesPath[i];
        out.push_back(parseDevice(w, devices[i], path, i, reader));
        for (std::size_t k = 0; k < i; ++k) {
            if (out[k].name == out[i].name) {
                w.fail(path / "name", "duplicate name '" + out[i].name + "' (also at devices[" +
                                          std::to_string(k) + "]); names must be unique");
            }
        }
    }
    return out;
}

std::vector<DeviceConfig> loadDeviceConfigFile(const std::filesystem::path& path,
                                               const DeviceEntryReader& reader) {
    const std::string text = readFile(path, "device configuration");
    std::vector<DeviceConfig> configs = parseDeviceConfig(text, path.string(), reader);
    const std::filesystem::path base = path.parent_path();
    for (DeviceConfig& c : configs) {
        if (auto* r = std::get_if<ReplayConfig>(&c.params); r && r->trace.is_relative()) {
            r->trace = base / r->trace;
        }
        if (auto* f = std::get_if<FalconConfig>(&c.params);
            f && !f->firmware.empty() && f->firmware.is_relative()) {
            f->firmware = base / f->firmware;
        }
    }
    return configs;
}

std::vector<DeviceConfig> defaultDeviceConfigs() {
    std::vector<DeviceConfig> out(2);
    out[0].name = "left";
    out[0].kind = DeviceKind::Sim;
    out[0].transform.translation = Vec3(-0.02, 0.0, 0.0);
    SimConfig left;
    left.script = HandScript::Slide;
    left.seed = 1;
    out[0].params = left;
    out[1].name = "right";
    out[1].kind = DeviceKind::Sim;
    out[1].transform.translation = Vec3(0.02, 0.0, 0.0);
    SimConfig right;
    right.script = HandScript::Touch;
    right.seed = 2;
    out[1].params = right;
    return out;
}

std::vector<DeviceConfig> graspHandConfigs(std::uint32_t object, double pressForceN) {
    std::vector<DeviceConfig> hands(2);
    for (int i = 0; i < 2; ++i) {
        hands[i].name = i == 0 ? "left" : "right";
        hands[i].kind = DeviceKind::Sim;
        hands[i].transform.translation = i == 0 ? Vec3(-0.12, -0.04, 0.0) : Vec3(0.04, -0.04, 0.0);
        SimConfig sim;
        sim.script = i == 0 ? HandScript::GraspLeft : HandScript::GraspRight;
        sim.seed = static_cast<std::uint64_t>(i + 1);
        sim.object = object;
        sim.pressForceN = pressForceN;
        hands[i].params = sim;
    }
    return hands;
}

} // namespace hapto
