#pragma once
/// The device configuration file (`--devices D.json`): which devices, where, how fast, how hard.

#include "hapto/scenes/Geometry.h"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace hapto {

/// Maps a device's own frame into the world: world = translation + scale * rotation * device.
/// Forces go the other way, rotated only: a newton is a newton in both frames.
struct WorkspaceTransform {
    Vec3 translation{0.0};     ///< Where the device origin sits in the world (m).
    Quat rotation{1, 0, 0, 0}; ///< Device axes in the world, unit quaternion (w, x, y, z).
    double scale = 1.0;        ///< World metres per device metre (> 0).

    /// A device-frame position (m) in the world. [servo]
    Vec3 positionToWorld(const Vec3& p) const { return translation + scale * (rotation * p); }
    /// A world position (m) in the device frame. [servo]
    Vec3 positionToDevice(const Vec3& p) const {
        return glm::conjugate(rotation) * ((p - translation) / scale);
    }
    /// A device-frame velocity (m/s) in the world. [servo]
    Vec3 velocityToWorld(const Vec3& v) const { return scale * (rotation * v); }
    /// A world force (N) in the device frame. [servo]
    Vec3 forceToDevice(const Vec3& f) const { return glm::conjugate(rotation) * f; }
};

/// Simulated hand (`"kind": "sim"`).
struct SimConfig {
    std::string script = "walk"; ///< free, touch, slide, walk, grasp-left, grasp-right.
    std::uint64_t seed = 1;      ///< Same seed and scene, same motion.
};

/// Playback of a recorded trace (`"kind": "replay"`).
struct ReplayConfig {
    std::filesystem::path trace; ///< A trace file written by `hapto run --record`.
    bool loop = false;           ///< Start over at the end instead of stalling.
};

/// A Novint Falcon over libusb (`"kind": "falcon"`).
struct FalconConfig {
    std::string serial;            ///< Pick by USB serial number; empty = any.
    int bus = -1;                  ///< Pick by USB bus number; -1 = any.
    int address = -1;              ///< Pick by USB device address; -1 = any.
    std::filesystem::path firmware; ///< Firmware image to upload when none is loaded.
    bool home = true;              ///< Run the homing procedure at open.
};

/// A PHANToM or Touch through OpenHaptics (`"kind": "phantom"`).
struct PhantomConfig {
    std::string deviceName;            ///< OpenHaptics device name; empty = the default device.
    std::string library = "libHD.so";  ///< The HD library to dlopen.
};

/// One configured device.
struct DeviceConfig {
    std::string name;             ///< Unique name ("left", "right").
    std::string kind;             ///< "sim", "replay", "falcon" or "phantom".
    WorkspaceTransform transform; ///< Device frame into the world.
    double maxForceN = 0.0;       ///< Force clamp (N); 0 = the device's own maximum.
    double rateHz = 1000.0;       ///< Servo rate (Hz).
    std::variant<SimConfig, ReplayConfig, FalconConfig, PhantomConfig> params; ///< Per kind.
};

/// Loads a device configuration file; throws InputError naming the file and JSON path. [control]
std::vector<DeviceConfig> loadDeviceConfigFile(const std::filesystem::path& path);
/// Parses device configuration JSON; `sourceName` names it in messages. [control]
std::vector<DeviceConfig> parseDeviceConfig(std::string_view text, std::string_view sourceName);
/// Two simulated hands, "left" and "right", 1 kHz, side by side. [control]
std::vector<DeviceConfig> defaultDeviceConfigs();

} // namespace hapto
