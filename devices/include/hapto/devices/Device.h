#pragma once
/// The Device interface: what a servo thread reads from and writes to a force-feedback device.

#include "hapto/core/Geometry.h"
#include "hapto/devices/DeviceKind.h"

#include <cstdint>
#include <string>
#include <string_view>

namespace hapto {

/// The outcome of a device call, as a value: the servo path never sees an exception.
enum class DeviceStatus : std::uint8_t {
    Ok,           ///< The call did what it says.
    NotOpen,      ///< open() has not succeeded (or close() was called).
    Stalled,      ///< No fresh data within the device's timeout.
    Disconnected, ///< The device went away (unplugged, library shut down).
    BadData,      ///< The device answered with data that cannot be decoded or is not finite.
    Error,        ///< Any other failure; errorMessage() says more on the control thread.
};

/// A short lower-case name for a status ("ok", "stalled", ...). [any thread]
std::string_view statusName(DeviceStatus status);

/// One reading of a device, in the device's own frame. Position is the gimbal centre (the end
/// of the arm, where the device's force acts); the stylus frame turns with `orientation`. Each
/// `has...` flag says whether the field beside it is real: a device that does not measure a
/// quantity leaves the flag false and the field at its default.
struct DeviceState {
    Vec3 position{0.0};              ///< End-effector (gimbal centre) position (m), device frame.
    Vec3 velocity{0.0};              ///< End-effector velocity (m/s), device frame, if hasVelocity.
    Quat orientation{1, 0, 0, 0};    ///< Stylus frame in the device frame, unit quaternion
                                     ///< (w, x, y, z), if hasOrientation; identity otherwise.
    Vec3 angularVelocity{0.0};       ///< Stylus angular velocity (rad/s), device frame, if
                                     ///< hasAngularVelocity.
    Vec3 gimbalAnglesRad{0.0};       ///< The gimbal's three joint angles (rad), as the device
                                     ///< reports them, if hasGimbalAngles.
    double gripper = 0.0;            ///< Gripper opening as the device reports it (device units:
                                     ///< rad for an angle, 0..1 for a fraction), if hasGripper.
    bool hasVelocity = false;        ///< True when the device measured or estimated velocity.
    bool hasOrientation = false;     ///< True when the device measures the stylus orientation.
    bool hasAngularVelocity = false; ///< True when the device measures angular velocity.
    bool hasGimbalAngles = false;    ///< True when gimbalAnglesRad holds the joint angles.
    bool hasGripper = false;         ///< True when the device has a gripper and read it.
    std::uint32_t buttons = 0;       ///< Bit i set while button i is pressed.
    std::uint64_t sequence = 0;      ///< Increases with every fresh sample from the device.
};

/// What a device can do, each with its unit.
struct DeviceCapabilities {
    std::string model;             ///< Human-readable model ("simulated hand", "Novint Falcon").
    Aabb workspace;                ///< Reachable positions (m), device frame.
    double maxForceN = 0.0;        ///< Largest continuous force it may be sent (N).
    double maxStiffness = 0.0;     ///< Largest stable rendering stiffness (N/m); 0 = unknown.
    double nominalRateHz = 1000.0; ///< The servo rate it is designed for (Hz).
    int buttonCount = 0;           ///< Number of buttons.
};

/// A force-feedback device. open/close and capabilities run on the control thread; read and
/// write run on the device's own servo thread and never allocate, lock (beyond the device's
/// own I/O), log or throw.
class Device {
public:
    virtual ~Device() = default;

    /// The name from the configuration ("left", "right"). [any thread]
    virtual std::string_view name() const = 0;
    /// The configuration kind; name(kind()) prints it. [any thread]
    virtual DeviceKind kind() const = 0;
    /// Workspace, limits, rate. [control]
    virtual DeviceCapabilities capabilities() const = 0;

    /// Opens and prepares the device (homing, firmware) with zero force. On failure returns
    /// the status and errorMessage() says what and what to do. [control]
    virtual DeviceStatus open() = 0;
    /// Commands zero force and releases the device. Safe to call twice. [control]
    virtual void close() = 0;

    /// Reads the newest sample. [servo]
    virtual DeviceStatus read(DeviceState& state) noexcept = 0;
    /// Commands a force (N), device frame. [servo]
    virtual DeviceStatus write(const Vec3& forceN) noexcept = 0;
    /// The servo let `periods` of its deadlines pass without a tick (a late wake-up or a tick
    /// that overran; the next tick's deadline is that many periods further on than the one
    /// after the tick just done). A device that keeps its own time (a simulated hand) lets it run
    /// on through them, under the force last written, as a real hand moves on while nobody reads
    /// it; a real device needs nothing. Bounded work. [servo]
    virtual void periodsSkipped(std::uint64_t periods) noexcept { (void)periods; }

    /// What went wrong last, for people. [control]
    virtual std::string errorMessage() const = 0;
};

} // namespace hapto
