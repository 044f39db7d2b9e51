#pragma once
/// A Novint Falcon over libusb-1.0: set-up, firmware upload, homing and asynchronous 1 kHz I/O.
//
// Design note. open() runs on the control thread: it finds the Falcon (0403:cb48, by serial or
// bus/address), sets up the FTDI bridge, probes for running firmware (one I/O packet, a short
// wait) and uploads the user's firmware file if none answers, then starts the device's own I/O
// thread and homes. The I/O thread owns all USB traffic after that: it runs the libusb event
// loop with one bulk IN transfer always in flight and one OUT command per cycle (~1 kHz),
// reassembles frames, runs forward kinematics and turns the servo's force into motor words
// with the Jacobian at the newest pose. The servo thread never touches libusb: read() and
// write() only copy the newest sample out of, and the newest force into, two lock-free seqlock
// mailboxes, then compare a timestamp. So a slow bus can make samples stale (Stalled) but
// never blocks the servo. close() tells the I/O thread to send a zero-force packet, waits for
// it, cancels the IN transfer, joins the thread, and releases the device.
// Invariants: one writer per mailbox at a time (the I/O thread for samples; the control
// thread, then the servo thread, for commands); the servo path does no allocation, lock,
// syscall (clock reads go through the vDSO) or throw. If the servo stops writing, the I/O thread
// sends zero force once the newest command is older than FalconConfig::commandTimeoutMs (two
// servo periods by default, at most 10 ms). Every packet, the firmware probe and the last zero
// packet included, carries the homing bit: the public firmware notes say it must stay set for
// the motors to stay homed (libnifalcon include/falcon/core/FalconFirmware.h, "Homing Mode").
// Motor words are scaled together so the largest fits FalconConfig::motorWordLimit.

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hapto {

/// One Falcon found on the USB bus.
struct FalconInfo {
    int bus = 0;        ///< USB bus number.
    int address = 0;    ///< USB device address on that bus.
    std::string serial; ///< USB serial number; empty when it could not be read.
};

/// Lists the Falcons (USB 0403:cb48) on the bus. When the list is empty, `whyNone` says why
/// ("no 0403:cb48 device on the USB bus", "libusb could not be initialised: ...", or a
/// permission problem with what to do). [control]
std::vector<FalconInfo> listFalcons(std::string& whyNone);

/// Timeouts of a FalconDevice; the defaults suit real hardware, tests shorten them.
struct FalconTimeouts {
    std::chrono::milliseconds usb{500};      ///< One synchronous set-up transfer.
    std::chrono::milliseconds probe{100};    ///< Wait for a reply when probing for firmware.
    std::chrono::milliseconds homing{30000}; ///< Wait for all three homed flags.
    std::chrono::milliseconds stale{50};     ///< A sample older than this is Stalled.
    std::chrono::microseconds period{1000};  ///< I/O cycle: one command packet per period.
};

/// Counters of the I/O thread, for diagnostics (monotonic).
struct FalconIoStats {
    std::uint64_t commandsSent = 0;       ///< OUT packets completed.
    std::uint64_t framesDecoded = 0;      ///< Valid frames received.
    std::uint64_t samplesPublished = 0;   ///< Frames that gave a finite position.
    std::uint64_t badFrames = 0;          ///< Frames started with '<' but invalid.
    std::uint64_t garbageBytes = 0;       ///< Bytes not part of any valid frame.
    std::uint64_t shortTransfers = 0;     ///< IN transfers shorter than the FTDI status bytes.
    std::uint64_t kinematicsFailures = 0; ///< Valid frames whose encoders gave no position.
    std::uint64_t transferErrors = 0;     ///< OUT/IN transfers that failed (other than unplug).
};

/// A Novint Falcon (`"kind": "falcon"`). Positions are reported in the device frame with the
/// origin at the workspace centre (m); forces are taken in newtons in the same frame.
class FalconDevice final : public Device {
public:
    /// A Falcon picked by `config` (serial or bus/address), forces clamped to maxForceN (N;
    /// <= 0 means the Falcon's own ~9 N). A command timeout outside (0, 10] ms is clamped into
    /// it (the file parser refuses such values). Does not touch USB until open(). [control]
    FalconDevice(std::string name, const FalconConfig& config, double maxForceN);
    /// Closes the device if open. [control]
    ~FalconDevice() override;
    FalconDevice(const FalconDevice&) = delete;
    FalconDevice& operator=(const FalconDevice&) = delete;

    /// The configured name. [any thread]
    std::string_view name() const override;
    /// "falcon". [any thread]
    DeviceKind kind() const override { return DeviceKind::Falcon; }
    /// Model, workspace (m, centred), max force (N), 1 kHz, 4 buttons. [control]
    DeviceCapabilities capabilities() const override;

    /// Finds, sets up, loads firmware if needed, starts I/O and homes (if configured). [control]
    DeviceStatus open() override;
    /// Sends zero force, stops the I/O thread and releases the device. Safe twice. [control]
    void close() override;

    /// Copies the newest sample: Ok, Stalled (older than the stale timeout), BadData (only
    /// undecodable data lately), Disconnected or NotOpen. Never blocks. [servo]
    DeviceStatus read(DeviceState& state) noexcept override;
    /// Publishes the force (N, device frame) for the next packet; clamped to the max force,
    /// non-finite -> zero. Never blocks. [servo]
    DeviceStatus write(const Vec3& forceN) noexcept override;

    /// What went wrong last, for people. [control]
    std::string errorMessage() const override;

    /// Sets the LEDs sent with every packet. [control]
    void setLeds(bool green, bool blue, bool red);
    /// Replaces the timeouts; call before open(). [control]
    void setTimeouts(const FalconTimeouts& timeouts);
    /// The monotonic clock (ns) that stamps each write() and judges its age on the I/O thread;
    /// default std::chrono::steady_clock. Tests pass a clock they step. Must be callable from
    /// the servo and I/O threads without blocking. Call before open(). [control]
    void setCommandClock(std::int64_t (*nowNs)());
    /// True when open() found firmware running, false when it uploaded the file. [control]
    bool firmwareWasLoaded() const;
    /// I/O counters so far. [any thread]
    FalconIoStats ioStats() const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace hapto
