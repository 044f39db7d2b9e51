#pragma once
/// The device configuration file (`--devices D.json`): which devices, where, how fast, how hard.

#include "hapto/core/Geometry.h"
#include "hapto/devices/DeviceKind.h"
#include "hapto/devices/FalconKinematics.h"
#include "hapto/devices/HandScript.h"

#include <nlohmann/json_fwd.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace hapto {

namespace json {
struct Path;
class Source;
} // namespace json

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
    /// A device-frame force (N) in the world. [servo]
    Vec3 forceToWorld(const Vec3& f) const { return rotation * f; }
    /// A device-frame velocity (m/s) in the world. [servo]
    Vec3 velocityToWorld(const Vec3& v) const { return scale * (rotation * v); }
    /// A world force (N) in the device frame. [servo]
    Vec3 forceToDevice(const Vec3& f) const { return glm::conjugate(rotation) * f; }
};

/// Simulated hand (`"kind": "sim"`): a scripted target pulls a mass-spring-damper hand that
/// holds the device; see SimDevice. Scripts work in the world frame (m); the hand lives in the
/// device frame. Every default below is what a missing JSON field gives.
struct SimConfig {
    HandScript script = HandScript::Walk; ///< What the hand does. JSON `script`.
    std::uint64_t seed = 1; ///< Same seed, scene and configuration, same motion, bit for bit.
    Vec3 start{0.0};        ///< Where the hand starts, device frame (m). JSON `start`.
    std::optional<std::uint32_t> object; ///< Object id to touch, slide on or grasp; none = the
                                         ///< nearest (touch, slide) or the one nearest `near`
                                         ///< (grasp). JSON `object`.
    Vec3 near{0.0};               ///< Grasp scripts pick the object nearest this world point (m)
                                  ///< when `object` is not given, so two hands agree. JSON `near`.
    double pressForceN = 1.5;     ///< The force touch, slide and grasp press with (N), >= 0:
                                  ///< felt once a press settles, whatever the surface's
                                  ///< stiffness (SimDevice). `press_n`.
    double maxSpeedMPerS = 0.5;   ///< Speed cap of scripted motion (m/s), > 0. `max_speed_m_per_s`.
    Vec3 lift{0.0, 0.05, 0.0};    ///< Grasp: lift of the object, world (m); +y is up. `lift`.
    Vec3 carry{0.10, 0.0, 0.0};   ///< Grasp: sideways carry after the lift, world (m). `carry`.
    double handMassKg = 0.15;     ///< Moving mass of hand and handle (kg), > 0. `hand_mass_kg`.
    double handStiffness = 300.0; ///< Hand stiffness (N/m), > 0: a force F moves the hand's
                                  ///< equilibrium by F / handStiffness. `hand_stiffness_n_per_m`.
    double handDampingRatio = 1.0; ///< Damping as a fraction of critical (unitless), >= 0.
                                   ///< `hand_damping_ratio`.
    double resolutionM = 1.0e-5;   ///< Encoder quantum (m), >= 0; 0 = continuous. `resolution_m`.
    double noiseM = 2.0e-6;        ///< Uniform position noise per axis, |noise| <= noiseM (m),
                                   ///< >= 0. `noise_m`.
    /// The stylus orientation at the start, device frame, unit quaternion [w, x, y, z]. With
    /// it (or a spin) the hand reports an orientation and angular velocity; without either it
    /// reports none, like a 3-DOF device. `orientation`.
    std::optional<Quat> orientation;
    Vec3 spinRadPerS{0.0}; ///< The stylus turns at this constant angular velocity (rad/s, device
                           ///< frame) from `orientation`; each component within +-100.
                           ///< `spin_rad_per_s`.
};

/// Playback of a recorded trace (`"kind": "replay"`).
struct ReplayConfig {
    std::filesystem::path trace; ///< A trace file written by `hapto run --record`; a relative
                                 ///< path in a file is relative to that file's folder.
    bool loop = false;           ///< Start over at the end instead of stalling.
    // Set by the parser when the device's own fields give them; otherwise a version 2 trace's
    // recorded rate, transform and tool tip are used (useTraceSettings).
    bool ownRate = false;      ///< The device gave `rate_hz`.
    bool ownTransform = false; ///< The device gave `transform`.
    bool ownToolTip = false;   ///< The device gave `tool_tip`.
    bool ownMaxForce = false;  ///< The device gave `max_force_n`.
};

/// The longest a device's own I/O thread may keep applying the servo's last force (ms): a
/// command older than its `command_timeout_ms` is replaced by zero force, and longer timeouts
/// are refused. A hand on the handle feels at most this much of a stalled servo's force.
inline constexpr double kMaxCommandTimeoutMs = 10.0;
/// The command timeout when a file gives none: two servo periods (ms) at `rateHz` (Hz), capped
/// at kMaxCommandTimeoutMs. [any thread]
double defaultCommandTimeoutMs(double rateHz);

/// A Novint Falcon over libusb (`"kind": "falcon"`).
struct FalconConfig {
    std::string serial;             ///< Pick by USB serial number; empty = any.
    int bus = -1;                   ///< Pick by USB bus number; -1 = any.
    int address = -1;               ///< Pick by USB device address; -1 = any.
    std::filesystem::path firmware; ///< Firmware image to upload when none is loaded.
    bool home = true;               ///< Wait at open until all three motors report homed.
    int motorWordLimit = falcon::kDefaultMotorWordLimit; ///< Largest |motor word| sent (counts,
                                                         ///< 1..32767); the three words are
                                                         ///< scaled together to fit.
                                                         ///< `motor_word_limit`.
    double commandTimeoutMs = 2.0; ///< The I/O thread sends zero force once the newest write()
                                   ///< is older than this (ms), (0, 10]. A file's default is two
                                   ///< servo periods (2 ms at 1 kHz). `command_timeout_ms`.
};

/// A PHANToM or Touch through OpenHaptics (`"kind": "phantom"`).
struct PhantomConfig {
    std::string deviceName;           ///< OpenHaptics device name; empty = the default device.
    std::string library = "libHD.so"; ///< The HD library to dlopen.
    double commandTimeoutMs = 2.0;    ///< The HD callback applies zero force once the newest
                                   ///< write() is older than this (ms), (0, 10]. A file's default
                                   ///< is two servo periods (2 ms at 1 kHz). `command_timeout_ms`.
};

/// The longest tool tip component a file may give (m).
inline constexpr double kMaxToolTipM = 0.5;

/// The device configuration file format version this build reads.
inline constexpr int kDeviceConfigFormatVersion = 1;

/// One configured device.
struct DeviceConfig {
    std::string name;                  ///< Unique name: 1..63 of [A-Za-z0-9_-] ("left", "right").
    DeviceKind kind = DeviceKind::Sim; ///< What drives it. JSON `kind`.
    WorkspaceTransform transform;      ///< Device frame into the world.
    double maxForceN = 0.0;            ///< Force clamp (N); 0 = the device's own maximum.
    double rateHz = 1000.0;            ///< Servo rate (Hz), 100..100000. A replay uses its trace's.
    Vec3 toolTipM{0.0}; ///< The contact point in the stylus frame (m), JSON `tool_tip`: the
                        ///< renderer touches with position + R * toolTipM (R the stylus
                        ///< orientation; the identity on a device without one) instead of the
                        ///< gimbal centre, and its force acts there. A 3-DOF device applies that
                        ///< force at the gimbal, as it can: the same force, no torque. Each
                        ///< component within +-kMaxToolTipM.
    std::variant<SimConfig, ReplayConfig, FalconConfig, PhantomConfig> params; ///< Per kind.
};

/// Reads the fields of a device entry that are the runtime's, not the device's: `effects` and
/// `renderer` belong to the device file's format, but what they mean (force effects, renderer
/// settings) lives in hapto::runtime, which reads them (parseDeviceFile(), DeviceFile.h). It is
/// called once per device entry with the device's index, its entry (a JSON object whose other
/// fields are already checked up to its transform), the file's Source and the entry's JSON
/// path, so its messages read like the rest of the file's and a file's first bad value is the
/// one named. It throws InputError through Source::fail. [control]
using DeviceEntryReader = std::function<void(std::size_t device, const nlohmann::json& entry,
                                             const json::Source& source, const json::Path& path)>;

/// Loads a device configuration file (format "hapto-devices", README.md "Device configuration
/// files"); relative trace and firmware paths are resolved against the file's folder. Throws
/// InputError naming the file and the JSON path (e.g. `devices[1].transform.scale`). The
/// entries' `effects` and `renderer` go to `reader`; without one they are not read (a program
/// that drives the devices reads the file with parseDeviceFile() or loadDeviceFile() of
/// hapto/runtime/DeviceFile.h). [control]
std::vector<DeviceConfig> loadDeviceConfigFile(const std::filesystem::path& path,
                                               const DeviceEntryReader& reader = {});
/// Parses device configuration JSON; `sourceName` names it in messages; paths are kept as
/// written. Throws InputError. `reader` as for loadDeviceConfigFile(). [control]
std::vector<DeviceConfig> parseDeviceConfig(std::string_view text, std::string_view sourceName,
                                            const DeviceEntryReader& reader = {});
/// Two simulated hands side by side at 1 kHz in the clear 4 cm around the origin of the default
/// scene: "left" at x = -0.02 m sliding on its nearest surface (seed 1), "right" at x = +0.02 m
/// touching its nearest surface (seed 2): the paper's "sliding" and "touch" cases. [control]
std::vector<DeviceConfig> defaultDeviceConfigs();
/// The grasp scene's two simulated hands (makeGraspScene, makeDynamicGraspScene; y up) at 1 kHz:
/// "left" from x = -0.12 m on the grasp-left script (seed 1), "right" from x = +0.04 m on
/// grasp-right (seed 2), both at y = -0.04 m, grasping `object` with `pressForceN` each (N).
/// The hands of `hapto demo grasp` and of the examples. [control]
std::vector<DeviceConfig> graspHandConfigs(std::uint32_t object = 0, double pressForceN = 2.0);

} // namespace hapto
