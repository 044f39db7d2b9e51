// PhantomDevice: OpenHaptics' HD scheduler on one side, a hapto servo thread on the other.
//
// Design note.
// The idea: two real-time threads that never wait for each other. The HD scheduler thread owns
// the device I/O (hdBeginFrame/hdEndFrame must run there); the hapto servo thread owns the force
// computation. Between them sit two single-writer seqlock mailboxes per device:
//   sample  HD thread -> servo   {position m, velocity m/s, stylus orientation, gimbal angles
//                                 rad, buttons, time since open (ns)}
//   force   servo -> HD thread   {force N, time of the write on the command clock (ns)}
// plus atomics for faults (HD thread -> everyone), the zero-force request at close (control ->
// HD thread) and its acknowledgement (HD thread -> control).
// The invariants:
//   - Only the HD callback writes `sample`; only write() (the servo thread) writes `force`.
//     close() never writes `force`: it raises `zeroForce`, which the callback obeys before
//     looking at `force`, so there is never a second writer.
//   - Once `zeroForce` is raised or a fault is recorded, every later HD tick applies exactly zero.
//   - A force older than the command timeout is never applied: if the servo thread stalls, the
//     HD callback (which keeps running) applies zero from the first tick past that age. The age
//     is judged on our own monotonic clock: hdGetSchedulerTimeStamp counts only from the start
//     of the current frame (OpenHaptics hdScheduler.h), not across ticks.
//   - The callback's user data (PhantomLink) outlives its scheduling: it is freed only after
//     hdUnschedule returned (and PhantomDevice cannot move).
//   - HD calls from control threads (init, enable, probe, schedule, start/stop) are serialised
//     by one process-wide mutex; neither the servo nor the HD thread ever takes it.
// The cost per tick: HD thread, 5 HD gets + 1 set + ~12 atomic stores + one clock read;
// servo thread, ~12 atomic loads + one clock read. Latency: see PhantomDevice.h.

#include "hapto/devices/PhantomDevice.h"

#include "hapto/core/Clock.h"
#include "hapto/core/Finite.h"
#include "hapto/core/Mailbox.h"

#include "PhantomHdApi.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <thread>

namespace hapto {

namespace detail {

/// One force command as the servo left it.
struct PhantomForce {
    Vec3 forceN{0.0};        ///< Device frame (N).
    std::int64_t timeNs = 0; ///< When write() published it, on the command clock (ns).
};
static_assert(std::is_trivially_copyable_v<PhantomForce>);

/// One HD tick's reading as the HD callback left it.
struct PhantomSample {
    Vec3 positionM{0.0};          ///< Device frame (m).
    Vec3 velocityMps{0.0};        ///< Device frame (m/s).
    Quat orientation{1, 0, 0, 0}; ///< Stylus in the device frame (HD_CURRENT_TRANSFORM).
    Vec3 gimbalAnglesRad{0.0};    ///< HD_CURRENT_GIMBAL_ANGLES (rad).
    std::uint32_t buttons = 0;    ///< HD_CURRENT_BUTTONS.
    std::int64_t ageNs = 0;       ///< When it was taken, counted from the link's origin (ns).
};
static_assert(std::is_trivially_copyable_v<PhantomSample>);

/// Everything the HD callback and the servo thread share for one device, aligned so the HD
/// thread's and the servo thread's hot words sit on separate cache lines.
struct alignas(64) PhantomLink {
    const hd::HdApi* api = nullptr;               ///< Set before scheduling.
    hd::HHD handle = hd::kInvalidHandle;          ///< Set before scheduling.
    std::chrono::steady_clock::time_point origin; ///< Sample times count from here.
    std::int64_t (*commandClock)() = nullptr;     ///< Set before scheduling: stamps forces (ns).
    std::int64_t commandTimeoutNs = 0;            ///< Set before scheduling: max force age (ns).

    /// {px, py, pz (m), vx, vy, vz (m/s), buttons, time since origin (ns)}.
    alignas(64) Mailbox<PhantomSample> sample;
    /// The newest force and when it was written.
    alignas(64) Mailbox<PhantomForce> force;

    alignas(64) std::atomic<bool> zeroForce{false};     ///< Control -> HD: apply zero from now on.
    std::atomic<bool> zeroForceApplied{false};          ///< HD -> control: a zero was applied.
    std::atomic<std::uint32_t> faultCode{hd::kSuccess}; ///< First HD error, or kSuccess.
    std::atomic<int> faultInternal{0};                  ///< Its driver code.
    std::atomic<std::uint64_t> ticks{0};                ///< Callback runs since open.
    PhantomForce heldForce{{0.0, 0.0, 0.0}, 0};         ///< HD thread only: last force read.

    alignas(64) std::atomic<std::uint64_t> staleReads{0}; ///< Servo writes, anyone reads.
    std::uint64_t lastWrites = 0;                         ///< Servo only.
    PhantomSample lastSample{};                           ///< Servo only.

    /// Back to "just opened": only while the callback is not scheduled. [control]
    void reset() {
        sample.reset();
        force.reset();
        zeroForce.store(false);
        zeroForceApplied.store(false);
        faultCode.store(hd::kSuccess);
        faultInternal.store(0);
        ticks.store(0);
        heldForce = PhantomForce{};
        staleReads.store(0);
        lastWrites = 0;
        lastSample = {};
        origin = std::chrono::steady_clock::now();
    }
};

static_assert(alignof(PhantomLink) == 64, "HD-side and servo-side words on separate lines");

} // namespace detail

namespace {

using detail::PhantomForce;
using detail::PhantomLink;
using detail::PhantomSample;

/// The default command clock: the monotonic clock (core), signed for differences (ns).
std::int64_t steadyNowNs() {
    return static_cast<std::int64_t>(monotonicNs());
}
constexpr double kMmToM = 1.0e-3;
constexpr std::chrono::seconds kFirstSampleTimeout{2};
constexpr std::chrono::milliseconds kZeroForceTimeout{200};

/// The stylus rotation of an HD_CURRENT_TRANSFORM (PhantomHdApi.h: m[4 i + j] = R(j, i), a
/// column-major 4x4 of the column-vector transform) as a unit quaternion; a matrix that is no
/// rotation gives non-finite numbers, refused by read(). [HD thread]
Quat stylusOrientation(const hd::HDdouble m[16]) noexcept {
    glm::dmat3 r;
    for (int c = 0; c < 3; ++c) {
        for (int row = 0; row < 3; ++row) {
            r[c][row] = m[4 * c + row]; // glm: r[column][row]
        }
    }
    const Quat q = glm::quat_cast(r);
    const double n = glm::length(q);
    return n > 0.5 && n < 1.5 ? q / n : Quat{std::nan(""), 0, 0, 0};
}

/// The HD scheduler callback of one device. Runs on OpenHaptics' scheduler thread every tick.
hd::HDCallbackCode phantomServoCallback(void* userData) {
    PhantomLink& link = *static_cast<PhantomLink*>(userData);
    const hd::HdApi& api = *link.api;

    api.makeCurrentDevice(link.handle);
    api.beginFrame(link.handle);
    hd::HDdouble position[3] = {0.0, 0.0, 0.0};
    hd::HDdouble velocity[3] = {0.0, 0.0, 0.0};
    hd::HDint buttons = 0;
    api.getDoublev(hd::kCurrentPosition, position);
    api.getDoublev(hd::kCurrentVelocity, velocity);
    hd::HDdouble transform[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    hd::HDdouble gimbal[3] = {0.0, 0.0, 0.0};
    api.getDoublev(hd::kCurrentTransform, transform);
    api.getDoublev(hd::kCurrentGimbalAngles, gimbal);
    api.getIntegerv(hd::kCurrentButtons, &buttons);

    const bool zero = link.zeroForce.load(std::memory_order_acquire) ||
                      link.faultCode.load(std::memory_order_relaxed) != hd::kSuccess;
    hd::HDdouble force[3] = {0.0, 0.0, 0.0};
    if (!zero) {
        PhantomForce f{};
        std::uint64_t writes = 0;
        if (link.force.read(f, writes) && writes > 0) {
            link.heldForce = f; // else keep the last force: the writer is mid-update
        }
        // A stalled servo leaves its last force behind: apply it only while it is young.
        if (link.commandClock() - link.heldForce.timeNs <= link.commandTimeoutNs) {
            for (int i = 0; i < 3; ++i) {
                force[i] = link.heldForce.forceN[i];
            }
        }
    }
    api.setDoublev(hd::kCurrentForce, force);
    api.endFrame(link.handle);

    const hd::HDErrorInfo error = api.takeError();
    if (error.errorCode != hd::kSuccess) {
        if (link.faultCode.load(std::memory_order_relaxed) == hd::kSuccess) {
            link.faultInternal.store(error.internalErrorCode, std::memory_order_relaxed);
            link.faultCode.store(error.errorCode, std::memory_order_release);
        }
    } else {
        const auto age = std::chrono::steady_clock::now() - link.origin;
        link.sample.publish(PhantomSample{
            Vec3(position[0], position[1], position[2]) * kMmToM,
            Vec3(velocity[0], velocity[1], velocity[2]) * kMmToM, stylusOrientation(transform),
            Vec3(gimbal[0], gimbal[1], gimbal[2]), static_cast<std::uint32_t>(buttons),
            std::chrono::duration_cast<std::chrono::nanoseconds>(age).count()});
    }
    if (zero) {
        link.zeroForceApplied.store(true, std::memory_order_release);
    }
    link.ticks.fetch_add(1, std::memory_order_release);
    return hd::kCallbackContinue;
}

DeviceStatus statusForHdError(std::uint32_t code) {
    return (code == hd::kCommError || code == hd::kCommConfigError) ? DeviceStatus::Disconnected
                                                                    : DeviceStatus::Error;
}

std::string stringParam(const hd::HdApi& api, hd::HDenum name) {
    const hd::HDstring s = api.getString(name);
    return s ? std::string(s) : std::string();
}

/// Starts the HD scheduler again when open() stopped it to initialise a device (it was running).
void restartScheduler(hd::HdRuntime& rt, bool wasRunning) {
    if (wasRunning) {
        rt.api.startScheduler();
        rt.schedulerRunning = true;
    }
}

/// Reads the static HD properties of the current device (control thread, outside a frame).
PhantomInfo queryCurrentDevice(const hd::HdApi& api, const std::string& deviceName) {
    PhantomInfo info;
    info.deviceName = deviceName;
    info.model = stringParam(api, hd::kDeviceModelType);
    info.vendor = stringParam(api, hd::kDeviceVendor);
    info.serial = stringParam(api, hd::kDeviceSerialNumber);
    hd::HDdouble d = 0.0;
    api.getDoublev(hd::kNominalMaxForce, &d);
    info.maxForceN = std::isfinite(d) && d > 0.0 ? d : 0.0;
    d = 0.0;
    api.getDoublev(hd::kNominalMaxStiffness, &d);
    info.maxStiffness = std::isfinite(d) && d > 0.0 ? d * 1000.0 : 0.0; // N/mm -> N/m
    hd::HDdouble ws[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    api.getDoublev(hd::kUsableWorkspaceDimensions, ws);
    info.workspace = Aabb{Vec3(ws[0], ws[1], ws[2]) * kMmToM, Vec3(ws[3], ws[4], ws[5]) * kMmToM};
    api.takeError(); // a device without some property must not poison later calls
    return info;
}

} // namespace

// ---- PhantomDevice ----------------------------------------------------------------------------

PhantomDevice::PhantomDevice(std::string name, const PhantomConfig& config, double maxForceN)
    : mName(std::move(name)), mConfig(config), mMaxForceN(maxForceN),
      mLink(std::make_unique<PhantomLink>()) {
    mCommandClock = &steadyNowNs;
    const double timeoutMs = std::isfinite(config.commandTimeoutMs) && config.commandTimeoutMs > 0.0
                                 ? std::min(config.commandTimeoutMs, kMaxCommandTimeoutMs)
                                 : defaultCommandTimeoutMs(1000.0);
    mCommandTimeoutNs = static_cast<std::int64_t>(std::llround(timeoutMs * 1.0e6));
    mCaps.model = "PHANToM / Touch (OpenHaptics, not open)";
    mCaps.maxForceN = std::max(0.0, maxForceN);
    mCaps.buttonCount = 2;
}

PhantomDevice::~PhantomDevice() {
    close();
}

std::string PhantomDevice::hdDeviceLabel() const {
    return mConfig.deviceName.empty() ? std::string("the default OpenHaptics device")
                                      : "OpenHaptics device \"" + mConfig.deviceName + "\"";
}

DeviceCapabilities PhantomDevice::capabilities() const {
    return mCaps;
}

DeviceStatus PhantomDevice::open() {
    if (mRuntime) {
        return DeviceStatus::Ok;
    }
    std::lock_guard lock(hd::hdRegistryMutex());
    std::string why;
    hd::HdRuntime* rt = hd::findOrLoadHdRuntime(mConfig.library, why);
    const std::string who = "phantom \"" + mName + "\": ";
    if (!rt) {
        mError = who + why;
        return DeviceStatus::Error;
    }
    // OpenHaptics' examples initialise devices before the scheduler runs; do the same.
    const bool wasRunning = rt->schedulerRunning;
    if (wasRunning) {
        rt->api.stopScheduler();
        rt->schedulerRunning = false;
    }
    if (!initHdDevice(rt->api, who)) {
        restartScheduler(*rt, wasRunning);
        return DeviceStatus::Error;
    }
    if (const DeviceStatus s = startServo(*rt, wasRunning, who); s != DeviceStatus::Ok) {
        return s;
    }
    if (const DeviceStatus s = awaitFirstSample(who); s != DeviceStatus::Ok) {
        return s;
    }
    mError.clear();
    mOpen.store(true, std::memory_order_release);
    return DeviceStatus::Ok;
}

// Initialises the configured HD device, takes its model, workspace and force limit, and
// prepares the link for the callback; false (mError set) when OpenHaptics refuses.
bool PhantomDevice::initHdDevice(const hd::HdApi& api, const std::string& who) {
    api.takeError(); // forget errors left by someone else on this thread
    const hd::HHD handle =
        api.initDevice(mConfig.deviceName.empty() ? nullptr : mConfig.deviceName.c_str());
    const hd::HDErrorInfo error = api.takeError();
    if (error.errorCode != hd::kSuccess || handle == hd::kInvalidHandle) {
        mError = who + "OpenHaptics could not initialise " + hdDeviceLabel() + ": " +
                 api.describe(error) +
                 ". Check that the name matches one in Touch_Setup (empty = the default device) "
                 "and that the device is plugged in and powered.";
        return false;
    }

    api.makeCurrentDevice(handle);
    const PhantomInfo info = queryCurrentDevice(api, mConfig.deviceName);
    mCaps.model = info.model.empty() ? std::string("PHANToM / Touch") : info.model;
    mCaps.workspace = info.workspace;
    mCaps.maxStiffness = info.maxStiffness;
    mCaps.nominalRateHz = mSchedulerRateHz > 0 ? static_cast<double>(mSchedulerRateHz) : 1000.0;
    mCaps.buttonCount = 2;
    mForceLimitN = mMaxForceN > 0.0 ? mMaxForceN : info.maxForceN;
    if (info.maxForceN > 0.0) {
        mForceLimitN = std::min(mForceLimitN, info.maxForceN);
    }
    mCaps.maxForceN = mForceLimitN;

    PhantomLink& link = *mLink;
    link.reset();
    link.api = &api;
    link.handle = handle;
    link.commandClock = mCommandClock;
    link.commandTimeoutNs = mCommandTimeoutNs;
    return true;
}

// Enables force output, schedules the callback and starts the scheduler (at the configured
// rate when this is its first device); on failure undoes what it did.
DeviceStatus PhantomDevice::startServo(hd::HdRuntime& rt, bool wasRunning, const std::string& who) {
    const hd::HdApi& api = rt.api;
    const hd::HHD handle = mLink->handle;
    api.enable(hd::kForceOutput);
    const hd::HDSchedulerHandle scheduled =
        api.scheduleAsynchronous(&phantomServoCallback, mLink.get(), hd::kMaxSchedulerPriority);
    hd::HDErrorInfo error = api.takeError();
    if (error.errorCode != hd::kSuccess) {
        mError = who + "OpenHaptics could not schedule the servo callback of " + hdDeviceLabel() +
                 ": " + api.describe(error) + ".";
        api.disable(hd::kForceOutput);
        api.disableDevice(handle);
        api.takeError();
        restartScheduler(rt, wasRunning);
        return DeviceStatus::Error;
    }
    mScheduled = scheduled;
    ++rt.scheduledDevices;
    mRuntime = &rt;
    if (!wasRunning && rt.scheduledDevices == 1 && mSchedulerRateHz > 0) {
        api.setSchedulerRate(mSchedulerRateHz);
    }
    api.startScheduler();
    rt.schedulerRunning = true;
    error = api.takeError();
    if (error.errorCode != hd::kSuccess) {
        mError = who + "OpenHaptics could not start its scheduler: " + api.describe(error) +
                 ". Another program may be using the device.";
        releaseLocked();
        return DeviceStatus::Error;
    }
    return DeviceStatus::Ok;
}

// Waits (bounded) for the first sample so read() right after open() has data; a fault on the
// first tick or no sample within kFirstSampleTimeout releases the device.
DeviceStatus PhantomDevice::awaitFirstSample(const std::string& who) {
    const PhantomLink& link = *mLink;
    const hd::HdApi& api = mRuntime->api;
    const auto deadline = std::chrono::steady_clock::now() + kFirstSampleTimeout;
    for (;;) {
        PhantomSample s{};
        std::uint64_t writes = 0;
        if (const std::uint32_t code = link.faultCode.load(std::memory_order_acquire);
            code != hd::kSuccess) {
            mError = who + "OpenHaptics reported an error on the first servo tick of " +
                     hdDeviceLabel() + ": " +
                     api.describe({code, link.faultInternal.load(), link.handle}) + ".";
            releaseLocked();
            return statusForHdError(code);
        }
        if (link.sample.read(s, writes) && writes > 0) {
            return DeviceStatus::Ok;
        }
        if (std::chrono::steady_clock::now() > deadline) {
            mError = who + "the OpenHaptics scheduler gave no sample of " + hdDeviceLabel() +
                     " within 2 s of starting. Check that no other program holds the device.";
            releaseLocked();
            return DeviceStatus::Stalled;
        }
        std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
}

void PhantomDevice::releaseLocked() {
    hd::HdRuntime& rt = *mRuntime;
    const hd::HdApi& api = rt.api;
    const hd::HHD handle = mLink->handle;
    --rt.scheduledDevices;
    if (rt.scheduledDevices == 0 && rt.schedulerRunning) {
        api.stopScheduler(); // the vendor's order: stop, unschedule, disable
        rt.schedulerRunning = false;
    }
    api.unschedule(mScheduled); // returns once the callback cannot run again
    api.makeCurrentDevice(handle);
    api.disable(hd::kForceOutput);
    api.disableDevice(handle);
    api.takeError();
    mScheduled = 0;
    mRuntime = nullptr;
}

void PhantomDevice::close() {
    if (!mRuntime) {
        return;
    }
    mOpen.store(false, std::memory_order_release); // servo calls now answer NotOpen
    PhantomLink& link = *mLink;
    link.zeroForce.store(true, std::memory_order_release);
    const auto deadline = std::chrono::steady_clock::now() + kZeroForceTimeout;
    bool applied = false;
    while (!(applied = link.zeroForceApplied.load(std::memory_order_acquire)) &&
           std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    if (link.faultCode.load(std::memory_order_acquire) != hd::kSuccess) {
        mError = errorMessage(); // keep the HD fault for people after close
    }
    std::lock_guard lock(hd::hdRegistryMutex());
    releaseLocked();
    if (!applied) {
        mError = "phantom \"" + mName +
                 "\": the OpenHaptics scheduler did not run within 200 ms of close(), so zero "
                 "force was not confirmed; force output was disabled anyway.";
    }
}

DeviceStatus PhantomDevice::linkStatus() const noexcept {
    if (!mOpen.load(std::memory_order_acquire)) {
        return DeviceStatus::NotOpen;
    }
    const std::uint32_t code = mLink->faultCode.load(std::memory_order_acquire);
    return code == hd::kSuccess ? DeviceStatus::Ok : statusForHdError(code);
}

DeviceStatus PhantomDevice::read(DeviceState& state) noexcept {
    if (const DeviceStatus status = linkStatus(); status != DeviceStatus::Ok) {
        return status;
    }
    PhantomLink& link = *mLink;
    PhantomSample s{};
    std::uint64_t writes = 0;
    if (link.sample.read(s, writes) && writes > 0) {
        if (writes == link.lastWrites) {
            link.staleReads.fetch_add(1, std::memory_order_relaxed);
        }
        link.lastWrites = writes;
        link.lastSample = s;
    } else {
        // The HD thread was mid-write on every try: use the previous sample, count it stale.
        link.staleReads.fetch_add(1, std::memory_order_relaxed);
        s = link.lastSample;
        writes = link.lastWrites;
    }
    const auto now = std::chrono::steady_clock::now() - link.origin;
    const std::int64_t ageNs =
        std::chrono::duration_cast<std::chrono::nanoseconds>(now).count() - s.ageNs;
    if (writes == 0 || ageNs > mStaleTimeout.count()) {
        return DeviceStatus::Stalled;
    }
    const Quat& q = s.orientation;
    if (!finite(s.positionM) || !finite(s.velocityMps) || !finite(s.gimbalAnglesRad) ||
        !finite(Vec3(q.x, q.y, q.z)) || !std::isfinite(q.w)) {
        return DeviceStatus::BadData;
    }
    state.position = s.positionM;
    state.velocity = s.velocityMps;
    state.hasVelocity = true;
    state.orientation = q;
    state.hasOrientation = true;
    state.gimbalAnglesRad = s.gimbalAnglesRad;
    state.hasGimbalAngles = true;
    state.buttons = s.buttons;
    state.sequence = writes;
    return DeviceStatus::Ok;
}

DeviceStatus PhantomDevice::write(const Vec3& forceN) noexcept {
    if (const DeviceStatus status = linkStatus(); status != DeviceStatus::Ok) {
        return status;
    }
    PhantomLink& link = *mLink;
    if (!finite(forceN)) {
        link.force.publish(detail::PhantomForce{Vec3(0.0), mCommandClock()});
        return DeviceStatus::BadData;
    }
    Vec3 f = forceN;
    const double magnitude = glm::length(f);
    if (magnitude > mForceLimitN) {
        f *= mForceLimitN / magnitude; // magnitude > limit >= 0, so no division by zero
    }
    link.force.publish(detail::PhantomForce{f, mCommandClock()});
    return DeviceStatus::Ok;
}

std::string PhantomDevice::errorMessage() const {
    const std::uint32_t code = mLink->faultCode.load(std::memory_order_acquire);
    if (mRuntime && code != hd::kSuccess) {
        const hd::HDErrorInfo error{code, mLink->faultInternal.load(), mLink->handle};
        const bool gone = statusForHdError(code) == DeviceStatus::Disconnected;
        return "phantom \"" + mName + "\": the OpenHaptics scheduler reported " +
               mRuntime->api.describe(error) + " on " + hdDeviceLabel() +
               "; it now applies zero force. " +
               (gone ? "Check the cable and power, then close and reopen the device."
                     : "Close and reopen the device; run Touch_Diagnostic if it repeats.");
    }
    return mError;
}

void PhantomDevice::setCommandClock(std::int64_t (*nowNs)()) {
    mCommandClock = nowNs ? nowNs : &steadyNowNs;
}

std::uint64_t PhantomDevice::staleSampleCount() const {
    return mLink->staleReads.load(std::memory_order_relaxed);
}

std::uint64_t PhantomDevice::hdTickCount() const {
    return mLink->ticks.load(std::memory_order_acquire);
}

// ---- probe ------------------------------------------------------------------------------------

std::vector<PhantomInfo> probePhantoms(const std::string& library, std::string& whyNone) {
    whyNone.clear();
    std::lock_guard lock(hd::hdRegistryMutex());
    hd::HdRuntime* rt = hd::findOrLoadHdRuntime(library, whyNone);
    if (!rt) {
        return {};
    }
    if (rt->scheduledDevices > 0) {
        whyNone = "OpenHaptics (" + library + ") is in use by " +
                  std::to_string(rt->scheduledDevices) +
                  " open phantom device(s) in this process; probe before opening devices.";
        return {};
    }
    const hd::HdApi& api = rt->api;
    api.takeError();
    const hd::HHD handle = api.initDevice(nullptr);
    const hd::HDErrorInfo error = api.takeError();
    if (error.errorCode != hd::kSuccess || handle == hd::kInvalidHandle) {
        whyNone = "OpenHaptics (" + library +
                  ") loaded, but no default device answered: " + api.describe(error) +
                  ". Check that a PHANToM or Touch is plugged in and powered and that Touch_Setup "
                  "lists it.";
        return {};
    }
    api.makeCurrentDevice(handle);
    std::vector<PhantomInfo> found{queryCurrentDevice(api, std::string())};
    api.disableDevice(handle);
    api.takeError();
    return found;
}

} // namespace hapto
