#pragma once
/// The device configuration file (`--devices D.json`): which devices, where, how fast, how hard.

#include "hapto/core/Geometry.h"
#include "hapto/devices/DeviceKind.h"
#include "hapto/devices/FalconKinematics.h"
#include "hapto/devices/HandScript.h"

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

/// What a force effect does (JSON `"type"`).
enum class EffectType : std::uint8_t {
    Spring,   ///< Pulls the device point to a point, a line or a plane (`spring`).
    Damper,   ///< Viscosity, F = -b v (`damper`).
    Constant, ///< A constant force (`constant`).
};

/// What a spring pulls to.
enum class SpringTarget : std::uint8_t {
    Point, ///< The anchor: F = -k (x - anchor).
    Line,  ///< The line through the anchor along `axis`: only the offset across it pulls.
    Plane, ///< The plane through the anchor with normal `axis`: only the offset along the
           ///< normal pulls (both sides; a spring, not a wall).
};

/// The shape of the place where an effect acts.
enum class RegionShape : std::uint8_t {
    Everywhere, ///< No region (the default).
    Box,        ///< An axis-aligned box, world frame.
    Sphere,     ///< A ball.
};

/// Where an effect acts (m, world frame): everywhere, inside an axis-aligned box or inside a
/// sphere, the boundary included. JSON `"region": {"box": {"center": [x, y, z],
/// "half_extents": [hx, hy, hz]}}` or `{"sphere": {"center": [x, y, z], "radius_m": r}}`.
struct EffectRegion {
    RegionShape shape = RegionShape::Everywhere;
    Vec3 centerM{0.0};      ///< Box or sphere centre (m).
    Vec3 halfExtentsM{0.0}; ///< Box: half its size along x, y, z (m), each > 0.
    double radiusM = 0.0;   ///< Sphere: its radius (m), > 0.

    /// A box around `center` (m) with half sizes `halfExtents` (m). [any thread]
    static EffectRegion box(const Vec3& center, const Vec3& halfExtents) noexcept {
        return {RegionShape::Box, center, halfExtents, 0.0};
    }
    /// A ball around `center` (m) of radius `radius` (m). [any thread]
    static EffectRegion sphere(const Vec3& center, double radius) noexcept {
        return {RegionShape::Sphere, center, Vec3(0.0), radius};
    }
    /// True when the world point `p` (m) is inside (boundary included). [servo]
    bool contains(const Vec3& p) const noexcept {
        switch (shape) {
        case RegionShape::Box: {
            const Vec3 d = glm::abs(p - centerM);
            return d.x <= halfExtentsM.x && d.y <= halfExtentsM.y && d.z <= halfExtentsM.z;
        }
        case RegionShape::Sphere: {
            const Vec3 d = p - centerM;
            return glm::dot(d, d) <= radiusM * radiusM;
        }
        case RegionShape::Everywhere:
            break;
        }
        return true;
    }
};

/// Effects one device may have at once (a fixed capacity: the servo thread's copy never
/// allocates).
inline constexpr std::size_t kMaxEffectsPerDevice = 8;
/// Largest spring stiffness (N/m). A chosen bound, not a device fact: several times what
/// desktop devices render stably at 1 kHz; a stiffer spring only oscillates. The force is
/// clamped to the device's maximum besides.
inline constexpr double kMaxEffectStiffnessNPerM = 10'000.0;
/// Largest damping (N·s/m), for damper effects and the renderer's contact damping alike. A
/// chosen bound: 100 N·s/m resists a 0.1 m/s hand motion with 10 N, more than a desktop
/// device's peak force.
inline constexpr double kMaxDampingNsPerM = 100.0;
/// Largest constant force (N), per effect. A chosen bound, ten times a PHANToM Premium's
/// 8.5 N peak; the device's own clamp applies as well.
inline constexpr double kMaxEffectForceN = 100.0;
/// Largest |coordinate| of an anchor or region centre, and largest region size (m): the bound
/// on lengths every hapto input has.
inline constexpr double kMaxEffectLengthM = 1e6;

/// One force effect of a device: a plain value (world frame, SI units), checked by
/// checkForceEffect() and evaluated every servo tick by the runtime (hapto/runtime/Effects.h),
/// its force added to the proxy's before the safety filter. JSON: one object of a device's
/// `"effects"` list (README.md "Force effects").
struct ForceEffect {
    EffectType type = EffectType::Constant;    ///< JSON `type`.
    bool enabled = true;                       ///< Off: no force. JSON `enabled`.
    SpringTarget target = SpringTarget::Point; ///< Spring: point, line (JSON `direction`) or
                                               ///< plane (JSON `normal`).
    Vec3 anchorM{0.0}; ///< Spring: the point, or a point of the line or plane (m). `anchor`.
    Vec3 axis{0.0};    ///< Spring: the line's direction or the plane's normal, unit length.
    double stiffnessNPerM = 0.0; ///< Spring: k (N/m), 0..kMaxEffectStiffnessNPerM.
                                 ///< `stiffness_n_per_m`.
    double dampingNsPerM = 0.0;  ///< Damper: b (N·s/m), 0..kMaxDampingNsPerM.
                                 ///< `damping_n_s_per_m`.
    Vec3 forceN{0.0};            ///< Constant: the force (N), |F| <= kMaxEffectForceN. `force_n`.
    EffectRegion region;         ///< Where the effect acts; everywhere by default. `region`.

    /// A spring of stiffness `k` (N/m) to the point `anchor` (m). [any thread]
    static ForceEffect springToPoint(const Vec3& anchor, double k) noexcept;
    /// A spring of stiffness `k` (N/m) to the line through `anchor` (m) along `direction`
    /// (any non-zero length; normalised). [any thread]
    static ForceEffect springToLine(const Vec3& anchor, const Vec3& direction, double k) noexcept;
    /// A spring of stiffness `k` (N/m) to the plane through `anchor` (m) with `normal` (any
    /// non-zero length; normalised). [any thread]
    static ForceEffect springToPlane(const Vec3& anchor, const Vec3& normal, double k) noexcept;
    /// A damper of `b` (N·s/m) inside `region` (everywhere by default). [any thread]
    static ForceEffect damper(double b, const EffectRegion& region = {}) noexcept;
    /// A constant force (N, world). [any thread]
    static ForceEffect constant(const Vec3& forceN) noexcept;
};

/// What is wrong with an effect: the JSON field (as in a device file, e.g.
/// `stiffness_n_per_m`, `region.sphere.radius_m`) and what to do.
struct EffectProblem {
    std::string field;
    std::string message;
};
/// The first problem of `effect` (a gain, force or length out of its documented range, a
/// non-finite value, an axis that is not of unit length), or none. The one home of the
/// effect rules: device files and Runtime::setEffects() both apply it. [any thread]
std::optional<EffectProblem> checkForceEffect(const ForceEffect& effect);
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
    /// Force effects from the first tick on, at most kMaxEffectsPerDevice, each passing
    /// checkForceEffect(). JSON `effects`.
    std::vector<ForceEffect> effects;
    /// The renderer's contact damping b (N·s/m), 0..kMaxDampingNsPerM; none = the runtime's
    /// RuntimeOptions::renderer.damping. JSON `"renderer": {"damping_n_s_per_m": b}`.
    std::optional<double> contactDampingNsPerM;
};

/// Loads a device configuration file (format "hapto-devices", README.md "Device configuration
/// files"); relative trace and firmware paths are resolved against the file's folder. Throws
/// InputError naming the file and the JSON path (e.g. `devices[1].transform.scale`). [control]
std::vector<DeviceConfig> loadDeviceConfigFile(const std::filesystem::path& path);
/// Parses device configuration JSON; `sourceName` names it in messages; paths are kept as
/// written. Throws InputError. [control]
std::vector<DeviceConfig> parseDeviceConfig(std::string_view text, std::string_view sourceName);
/// Two simulated hands side by side at 1 kHz in the clear 4 cm around the origin of the default
/// scene: "left" at x = -0.02 m sliding on its nearest surface (seed 1), "right" at x = +0.02 m
/// touching its nearest surface (seed 2): the paper's "sliding" and "touch" cases. [control]
std::vector<DeviceConfig> defaultDeviceConfigs();

} // namespace hapto
