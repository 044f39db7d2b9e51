#pragma once
/// A PHANToM or Touch device through 3D Systems' OpenHaptics HD library, loaded at run time.
///
/// Design note: the scheduler exchange.
/// OpenHaptics runs ONE scheduler thread for all its devices; hapto runs one servo thread per
/// device. They never call each other. Each open PhantomDevice puts one asynchronous callback
/// (highest priority) on the HD scheduler. Every HD tick that callback, between hdBeginFrame and
/// hdEndFrame of its own device, reads position (mm -> m), velocity (mm/s -> m/s) and buttons,
/// publishes them into a lock-free seqlock mailbox, and applies the newest force (N) the hapto
/// servo thread left in a second seqlock mailbox. read() and write() touch only those
/// mailboxes and a few atomics: no allocation, lock, syscall (the clock read is vDSO) or throw.
///
/// Latency: a sample waits up to one HD period for hapto's servo to read it, and the force
/// computed from it waits up to one HD period to be applied. At 1 kHz each, a force reaches the
/// motors 1-2 ms after the position it was computed from (one HD-to-hapto hop is inherent to
/// any two-thread design). To keep it near 1 ms, run hapto's servo at the HD scheduler rate
/// (setSchedulerRateHz = DeviceConfig::rateHz) and watch staleSampleCount(): it counts reads
/// that found no new HD sample, i.e. hapto ticks that rendered old data. A sample older than the
/// stale timeout (default 50 ms) makes read() report Stalled.
///
/// The HD scheduler is started when the first PhantomDevice of a library opens and stopped when
/// the last one closes (a process-wide registry, control threads only, one mutex). OpenHaptics'
/// examples initialise every device before hdStartScheduler, so opening a device while another
/// runs briefly stops the scheduler around hdInitDevice: open all phantoms before servo threads
/// start. close() commands zero force, waits until one HD tick has applied it (bounded), then
/// unschedules its callback, disables force output and calls hdDisableDevice.
///
/// Stale commands: the callback applies the servo's newest force only while it is younger than
/// PhantomConfig::commandTimeoutMs (two servo periods by default, at most 10 ms) on the command
/// clock; a servo thread that stops writing leaves zero force on the handle, not its last force.
///
/// HD errors seen by the callback (drained with hdGetError after hdEndFrame) make the device
/// faulted: from then on it applies zero force, read()/write() return Disconnected
/// (HD_COMM_ERROR, HD_COMM_CONFIG_ERROR) or Error (any other code), and errorMessage() gives the
/// HD code, its name and hdGetErrorString's text. A fault lasts until close() and open().

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hapto {

namespace detail {
struct PhantomLink;
}
namespace hd {
struct HdApi;
struct HdRuntime;
} // namespace hd

/// What probePhantoms found about one device.
struct PhantomInfo {
    std::string deviceName;    ///< OpenHaptics configuration name; empty = the default device.
    std::string model;         ///< HD_DEVICE_MODEL_TYPE ("Touch", "PHANToM Premium 1.5").
    std::string vendor;        ///< HD_DEVICE_VENDOR.
    std::string serial;        ///< HD_DEVICE_SERIAL_NUMBER.
    double maxForceN = 0.0;    ///< HD_NOMINAL_MAX_FORCE (N).
    double maxStiffness = 0.0; ///< HD_NOMINAL_MAX_STIFFNESS, converted to N/m.
    Aabb workspace;            ///< HD_USABLE_WORKSPACE_DIMENSIONS, converted to m, device frame.
};

/// Lists the OpenHaptics default device, if the HD library at `library` loads and a device
/// answers. Never throws: with nothing to list, returns empty and `whyNone` says why in plain
/// words ("OpenHaptics libHD.so not found: install OpenHaptics from 3D Systems; ..."). Named
/// devices cannot be enumerated through the HD API; open them by name instead. Refuses (empty,
/// with a reason) while a PhantomDevice of that library is open in this process. [control]
std::vector<PhantomInfo> probePhantoms(const std::string& library, std::string& whyNone);

/// A PHANToM / Touch (`"kind": "phantom"`): position, velocity and buttons in, force out, through
/// the HD scheduler (see the design note above). Device frame = OpenHaptics' frame, in metres.
class PhantomDevice final : public Device {
public:
    /// A closed device named `name` ("left") for OpenHaptics device `config.deviceName` (empty =
    /// HD_DEFAULT_DEVICE) from `config.library`; forces are clamped to `maxForceN` (N), or to
    /// the device's HD_NOMINAL_MAX_FORCE when that is smaller or `maxForceN` is 0. A command
    /// timeout outside (0, 10] ms is clamped into it (the file parser refuses such values).
    /// [control]
    PhantomDevice(std::string name, const PhantomConfig& config, double maxForceN);
    /// Closes the device (zero force first). [control]
    ~PhantomDevice() override;
    PhantomDevice(const PhantomDevice&) = delete;
    PhantomDevice& operator=(const PhantomDevice&) = delete;

    /// The configured name. [any thread]
    std::string_view name() const override { return mName; }
    /// "phantom". [any thread]
    DeviceKind kind() const override { return DeviceKind::Phantom; }
    /// Model, usable workspace (m), force limit (N), nominal stiffness (N/m), rate (Hz), 2
    /// buttons; the HD values are known after open(). [control]
    DeviceCapabilities capabilities() const override;

    /// Loads the HD library, initialises the device by name, enables force output with zero
    /// force, schedules its HD callback, starts the HD scheduler if needed and waits (up to 2 s)
    /// for the first sample. Error (library or device missing, HD error) or Stalled (no sample);
    /// errorMessage() says what and what to do. [control]
    DeviceStatus open() override;
    /// Zero force, applied by one HD tick (waits up to 200 ms), then unschedules, disables force
    /// output and calls hdDisableDevice; stops the HD scheduler after the last phantom. Safe to
    /// call twice. [control]
    void close() override;

    /// The newest HD sample (m, m/s, buttons). Stalled when it is older than the stale timeout;
    /// Disconnected / Error after an HD error; BadData when not finite. [servo]
    DeviceStatus read(DeviceState& state) noexcept override;
    /// Leaves a force (N, clamped to the limit), stamped with the command clock, for the next HD
    /// ticks; they apply it until it is older than the command timeout, then zero. A non-finite
    /// force leaves zero and returns BadData. [servo]
    DeviceStatus write(const Vec3& forceN) noexcept override;

    /// What went wrong last, with the HD error code, name and text for HD errors. [control]
    std::string errorMessage() const override;

    /// How old the newest sample may be before read() reports Stalled (default 50 ms). Call
    /// before open(). [control]
    void setStaleTimeout(std::chrono::nanoseconds timeout) { mStaleTimeout = timeout; }
    /// Asks the HD scheduler for `rateHz` ticks per second (hdSetSchedulerRate) when this device
    /// starts it; 0 (default) keeps OpenHaptics' default (1000 Hz). Match hapto's servo rate to
    /// avoid stale samples. Call before open(). [control]
    void setSchedulerRateHz(unsigned long rateHz) { mSchedulerRateHz = rateHz; }
    /// The monotonic clock (ns) that stamps each write() and judges its age in the HD callback;
    /// default std::chrono::steady_clock. Tests pass a clock they step. Must be callable from
    /// the servo and HD threads without blocking. Call before open(). [control]
    void setCommandClock(std::int64_t (*nowNs)());

    /// Stale reads: read() calls since open() that found no HD sample newer than the previous
    /// read() had. [any thread]
    std::uint64_t staleSampleCount() const;
    /// HD scheduler ticks this device's callback has run since open(). [any thread]
    std::uint64_t hdTickCount() const;

private:
    std::string hdDeviceLabel() const;
    /// open()'s parts, under the HD registry lock: initialise the device, read its properties
    /// and prepare the link; schedule the callback and start the scheduler; wait (bounded) for
    /// the first sample. Each sets mError and cleans up on failure. [control]
    bool initHdDevice(const hd::HdApi& api, const std::string& who);
    DeviceStatus startServo(hd::HdRuntime& rt, bool wasRunning, const std::string& who);
    DeviceStatus awaitFirstSample(const std::string& who);
    void releaseLocked();
    /// NotOpen, Disconnected or Error after an HD error, else Ok: what read() and write()
    /// check first. [servo]
    DeviceStatus linkStatus() const noexcept;

    std::string mName;
    PhantomConfig mConfig;
    double mMaxForceN;
    std::chrono::nanoseconds mStaleTimeout{std::chrono::milliseconds(50)};
    unsigned long mSchedulerRateHz = 0;
    std::int64_t mCommandTimeoutNs = 2'000'000; ///< Max age of an applied force (ns).
    std::int64_t (*mCommandClock)() = nullptr;  ///< Set by the constructor: steady_clock (ns).

    // Control-thread state.
    hd::HdRuntime* mRuntime = nullptr; ///< Non-null while open.
    unsigned long mScheduled = 0;      ///< The HDSchedulerHandle of this device's callback.
    DeviceCapabilities mCaps;
    std::string mError;

    // Shared with the HD callback and the servo thread; allocated once, never moves.
    std::unique_ptr<detail::PhantomLink> mLink;
    std::atomic<bool> mOpen{false};
    double mForceLimitN = 0.0; ///< Written before mOpen is released; read by write().
};

} // namespace hapto
