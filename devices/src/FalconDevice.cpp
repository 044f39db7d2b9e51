#include "hapto/devices/FalconDevice.h"

#include "falcon/FalconFirmwareUpload.h"
#include "falcon/FalconHoming.h"
#include "falcon/FalconIoThread.h"
#include "falcon/FalconTransport.h"

#include "hapto/core/Finite.h"
#include "hapto/devices/FalconKinematics.h"

#include <algorithm>
#include <atomic>
#include <cmath>

// FalconDevice composes four parts, each in devices/src/falcon/: the USB/FTDI link
// (FalconTransport), firmware probe and upload (FalconFirmwareUpload), the I/O thread that owns
// the USB traffic once the Falcon runs (FalconIoThread), and homing (FalconHoming). See the
// design note in FalconDevice.h.

namespace hapto {
namespace {

constexpr double kFalconRatedForceN = 8.9; // the Falcon's rated peak force

} // namespace

struct FalconDevice::Impl {
    std::string name;                      ///< From the configuration.
    FalconConfig config;                   ///< Which Falcon, firmware, homing, word limit.
    double maxForceN = kFalconRatedForceN; ///< Force clamp (N).
    falcon::IoSettings io;                 ///< Timeouts, command timeout and clock, word limit.
    std::string error;                     ///< What went wrong last, for people.
    falcon::FalconTransport usb{error};    ///< The USB link (declared before the I/O thread,
                                           ///< so it outlives it).
    falcon::FalconIoThread ioThread;       ///< USB traffic while open.
    std::atomic<bool> open{false};         ///< read()/write() work only while true.
    bool firmwareWasLoaded = false;        ///< open() found firmware running.

    /// Stops the I/O thread (zero force last) and releases the USB link. [control]
    void release() {
        ioThread.stop();
        usb.close();
        open = false;
    }

    /// Opens the link, loads firmware if none runs, starts the I/O thread, homes. [control]
    DeviceStatus openDevice() {
        error.clear();
        usb.setUsbTimeout(io.timeouts.usb);
        if (const DeviceStatus st = usb.open(name, config); st != DeviceStatus::Ok) {
            release();
            return st;
        }
        firmwareWasLoaded = falcon::firmwareAnswers(usb, io.timeouts.probe);
        if (!firmwareWasLoaded) {
            if (usb.lastUsbError() == LIBUSB_ERROR_NO_DEVICE) {
                usb.fail("the Falcon went away during set-up");
                release();
                return DeviceStatus::Disconnected;
            }
            if (!falcon::uploadFirmware(usb, config.firmware, io.timeouts.probe)) {
                release();
                return DeviceStatus::Error;
            }
            if (!falcon::firmwareAnswers(usb, io.timeouts.probe)) {
                usb.fail("the firmware from " + config.firmware.string() +
                         " was uploaded but the Falcon does not answer: is it a Falcon firmware "
                         "image? Power-cycle the Falcon and try again");
                release();
                return DeviceStatus::Error;
            }
        }
        ioThread.resetParser();
        ioThread.configure(io);
        open = true;
        // Set before the I/O thread starts, so no force goes out before the homed flags arrive.
        ioThread.setHoming(config.home);
        ioThread.setLeds(config.home ? 8 : 2); // red while homing, green when ready
        ioThread.start(usb);
        if (config.home && !falcon::homeFalcon(ioThread, name, io.timeouts.homing, error)) {
            release();
            return DeviceStatus::Error;
        }
        return DeviceStatus::Ok;
    }
};

FalconDevice::FalconDevice(std::string name, const FalconConfig& config, double maxForceN)
    : mImpl(std::make_unique<Impl>()) {
    mImpl->name = std::move(name);
    mImpl->config = config;
    mImpl->maxForceN = maxForceN > 0.0 ? maxForceN : kFalconRatedForceN;
    const double timeoutMs = std::isfinite(config.commandTimeoutMs) && config.commandTimeoutMs > 0.0
                                 ? std::min(config.commandTimeoutMs, kMaxCommandTimeoutMs)
                                 : defaultCommandTimeoutMs(1000.0);
    mImpl->io.commandTimeoutNs = static_cast<std::int64_t>(std::llround(timeoutMs * 1.0e6));
    mImpl->config.motorWordLimit = std::clamp(config.motorWordLimit, 1, falcon::kMaxMotorWordLimit);
    mImpl->io.motorWordLimit = mImpl->config.motorWordLimit;
}

FalconDevice::~FalconDevice() {
    close();
}

std::string_view FalconDevice::name() const {
    return mImpl->name;
}

DeviceCapabilities FalconDevice::capabilities() const {
    DeviceCapabilities c;
    c.model = "Novint Falcon";
    // The box the kinematics can reach everywhere (mechanism z 0.075..0.155 m, +-5 cm across),
    // relative to kWorkspaceOriginZ. NOTE: that origin (0.150 m, from the protocol notes) sits
    // near the top of this range; the reachable centre is nearer 0.115 m. To be checked on
    // hardware.
    c.workspace = Aabb{Vec3(-0.05, -0.05, 0.075 - falcon::kWorkspaceOriginZ),
                       Vec3(0.05, 0.05, 0.155 - falcon::kWorkspaceOriginZ)};
    c.maxForceN = mImpl->maxForceN;
    c.maxStiffness = 2000.0;
    c.nominalRateHz = 1.0e6 / static_cast<double>(mImpl->io.timeouts.period.count());
    c.buttonCount = 4;
    return c;
}

DeviceStatus FalconDevice::open() {
    if (mImpl->open) {
        return DeviceStatus::Ok;
    }
    return mImpl->openDevice();
}

void FalconDevice::close() {
    if (mImpl->usb.context()) {
        mImpl->release();
    }
}

DeviceStatus FalconDevice::read(DeviceState& state) noexcept {
    Impl& m = *mImpl;
    if (!m.open.load(std::memory_order_acquire)) {
        return DeviceStatus::NotOpen;
    }
    const falcon::IoState io = m.ioThread.state();
    falcon::IoSample s{};
    const bool have = m.ioThread.newestSample(s);
    if (have) {
        state.position = s.positionM;
        state.hasVelocity = false;
        // The Falcon senses its three arm encoders only: no stylus orientation, gimbal or
        // gripper (libnifalcon: FalconKinematic.h turns the three arm angles into a position only;
        // the grips, FalconGripFourButton, report buttons).
        state.hasOrientation = false;
        state.hasAngularVelocity = false;
        state.hasGimbalAngles = false;
        state.hasGripper = false;
        state.buttons = s.buttons;
        state.sequence = s.sequence;
    }
    if (io == falcon::IoState::Disconnected) {
        return DeviceStatus::Disconnected;
    }
    if (io == falcon::IoState::Error) {
        return DeviceStatus::Error;
    }
    const std::int64_t staleNs =
        std::chrono::duration_cast<std::chrono::nanoseconds>(m.io.timeouts.stale).count();
    if (!have || falcon::ioNowNs() - s.timeNs > staleNs) {
        return m.ioThread.badSinceValid() ? DeviceStatus::BadData : DeviceStatus::Stalled;
    }
    return DeviceStatus::Ok;
}

DeviceStatus FalconDevice::write(const Vec3& forceN) noexcept {
    Impl& m = *mImpl;
    if (!m.open.load(std::memory_order_acquire)) {
        return DeviceStatus::NotOpen;
    }
    Vec3 f = forceN;
    if (!finite(f)) {
        f = Vec3(0.0);
    }
    const double len = glm::length(f);
    if (len > m.maxForceN) {
        f *= m.maxForceN / len;
    }
    m.ioThread.command(f);
    switch (m.ioThread.state()) {
    case falcon::IoState::Running:
        return DeviceStatus::Ok;
    case falcon::IoState::Disconnected:
        return DeviceStatus::Disconnected;
    case falcon::IoState::Error:
        break;
    }
    return DeviceStatus::Error;
}

std::string FalconDevice::errorMessage() const {
    const Impl& m = *mImpl;
    if (!m.error.empty()) {
        return m.error;
    }
    switch (m.ioThread.state()) {
    case falcon::IoState::Disconnected:
        return "device '" + m.name + "': the Falcon was unplugged or powered off";
    case falcon::IoState::Error:
        return "device '" + m.name + "': USB I/O failed repeatedly (" +
               falcon::usbError(m.usb.lastUsbError()) + "); re-plug the Falcon";
    case falcon::IoState::Running:
        break;
    }
    return {};
}

void FalconDevice::setLeds(bool green, bool blue, bool red) {
    mImpl->ioThread.setLeds(
        static_cast<std::uint8_t>((green ? 2 : 0) | (blue ? 4 : 0) | (red ? 8 : 0)));
}

void FalconDevice::setTimeouts(const FalconTimeouts& timeouts) {
    mImpl->io.timeouts = timeouts;
}

void FalconDevice::setCommandClock(std::int64_t (*nowNs)()) {
    mImpl->io.commandClock = nowNs ? nowNs : &falcon::ioNowNs;
}

bool FalconDevice::firmwareWasLoaded() const {
    return mImpl->firmwareWasLoaded;
}

FalconIoStats FalconDevice::ioStats() const {
    return mImpl->ioThread.stats();
}

} // namespace hapto
