// A stand-in for OpenHaptics' libHD, built by the tests and dlopened by PhantomDevice.
//
// It exports the HD functions hapto's PHANToM backend calls, with the published signatures and
// constant values (OpenHaptics 3.x hdDefines.h / hdDevice.h / hdScheduler.h, declared again here
// on purpose so a mistake in hapto's own declarations is not mirrored), and a scripted device:
//   - three devices: 0 "Default Device" (HD_DEFAULT_DEVICE), 1 "Left Touch", 2 "Right Touch";
//   - one scheduler thread calling the scheduled callbacks, highest priority first, at 1 kHz
//     (hdSetSchedulerRate changes it);
//   - positions following p0 + v * t (mm, t = scheduler ticks / rate), velocity v (mm/s);
//   - a stylus orientation (axis, angle) and gimbal angles (rad) set by the test:
//     HD_CURRENT_TRANSFORM (0x2052) gives them as OpenHaptics does, 16 doubles laid out as
//     hduMatrix stores them (HDU/hduMatrix.h: "stored by row", translations "along the last
//     row": m[4 i + j] = R(j, i) for the column-vector rotation R, m[12..14] = the position in
//     mm, m[15] = 1), HD_CURRENT_GIMBAL_ANGLES (0x2150) three doubles (rad);
//   - a force recorder: the force applied by each hdEndFrame with force output enabled.
// Errors go on a per-thread stack (hdGetError pops the newest), the current device is
// per-thread, as in the HD API. Test hooks (fakehd_*) script errors, stalls and removal, and
// step the scheduler by hand: with the thread stalled, fakehd_step runs whole ticks on the
// caller's thread, so a test decides exactly when each callback runs.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

extern "C" {
typedef unsigned int HHD;
typedef unsigned int HDenum;
typedef unsigned int HDerror;
typedef int HDint;
typedef double HDdouble;
typedef unsigned long HDulong;
typedef unsigned short HDushort;
typedef const char* HDstring;
typedef unsigned int HDCallbackCode;
typedef unsigned long HDSchedulerHandle;
typedef HDCallbackCode (*HDSchedulerCallback)(void*);
typedef struct {
    HDerror errorCode;
    int internalErrorCode;
    HHD hHD;
} HDErrorInfo;
}

namespace {

constexpr HDerror kSuccess = 0x0000;
constexpr HDerror kInvalidEnum = 0x0100;
constexpr HDerror kInvalidOperation = 0x0102;
constexpr HDerror kBadHandle = 0x0104;
constexpr HDerror kDeviceAlreadyInitiated = 0x0301;
constexpr HDerror kCommError = 0x0302;
constexpr HDerror kCommConfigError = 0x0303;
constexpr HDerror kIllegalBegin = 0x0400;
constexpr HDerror kIllegalEnd = 0x0401;

constexpr HDenum kCurrentButtons = 0x2000;
constexpr HDenum kCurrentPosition = 0x2050;
constexpr HDenum kCurrentVelocity = 0x2051;
constexpr HDenum kCurrentTransform = 0x2052;
constexpr HDenum kCurrentGimbalAngles = 0x2150;
constexpr HDenum kDeviceModelType = 0x2501;
constexpr HDenum kDeviceVendor = 0x2503;
constexpr HDenum kDeviceSerialNumber = 0x2504;
constexpr HDenum kUsableWorkspaceDimensions = 0x2551;
constexpr HDenum kNominalMaxStiffness = 0x2602;
constexpr HDenum kNominalMaxForce = 0x2603;
constexpr HDenum kCurrentForce = 0x2700;
constexpr HDenum kForceOutput = 0x4000;
constexpr HHD kInvalidHandle = 0xFFFFFFFFu;
constexpr HDCallbackCode kCallbackDone = 0;

constexpr int kDevices = 3;
const char* const kNames[kDevices] = {"Default Device", "Left Touch", "Right Touch"};

struct FakeDevice {
    bool initialised = false;
    bool forceOutput = false;
    bool removed = false;
    bool inFrame = false;
    double p0[3] = {0, 0, 0}; // mm
    double v[3] = {0, 0, 0};  // mm/s
    int buttons = 0;
    double axis[3] = {0, 0, 1}; // stylus rotation axis (unit) and angle (rad)
    double angle = 0.0;
    double gimbal[3] = {0, 0, 0}; // rad
    double framePos[3] = {0, 0, 0};
    double pendingForce[3] = {0, 0, 0};
    double lastForce[3] = {0, 0, 0};
    unsigned long long forceFrames = 0;
    double maxForceSeen = 0.0;
    HDerror injectCode = kSuccess;
    int injectInternal = 0;
};

struct Scheduled {
    HDSchedulerHandle handle;
    HDSchedulerCallback callback;
    void* data;
    HDushort priority;
};

std::mutex gState; // devices and counters
FakeDevice gDevices[kDevices];
std::atomic<unsigned long long> gTick{0};
std::atomic<unsigned long> gRateHz{1000};
int gInitWhileRunning = 0;
unsigned gFramedMask = 0; // devices framed in the current tick
int gMaxFramedPerTick = 0;

std::mutex gSched; // callback list; held for a whole tick
std::vector<Scheduled> gCallbacks;
HDSchedulerHandle gNextHandle = 1;

std::mutex gThreadMutex; // scheduler thread start/stop
std::thread gThread;
std::atomic<bool> gRunning{false};
std::atomic<bool> gStalled{false};
std::atomic<int> gStarts{0};

thread_local std::vector<HDErrorInfo> tErrors;
thread_local HHD tCurrent = kInvalidHandle;

void pushError(HDerror code, int internal = 0) {
    tErrors.push_back(HDErrorInfo{code, internal, tCurrent});
}

int indexOf(HHD h) {
    return (h >= 1 && h <= kDevices) ? static_cast<int>(h) - 1 : -1;
}

FakeDevice* current() {
    const int i = indexOf(tCurrent);
    return (i >= 0 && gDevices[i].initialised) ? &gDevices[i] : nullptr;
}

void positionNow(const FakeDevice& d, double out[3]) {
    const double t = static_cast<double>(gTick.load()) / static_cast<double>(gRateHz.load());
    for (int k = 0; k < 3; ++k) {
        out[k] = d.p0[k] + d.v[k] * t;
    }
}

/// One scheduler tick: every scheduled callback once, highest priority first. The scheduler
/// thread's ticks are skipped while stalled (checked under gSched, so none runs after
/// fakehd_stall(1) returns); fakehd_step's are not.
void runTick(bool fromSchedulerThread) {
    std::lock_guard sched(gSched);
    if (fromSchedulerThread && gStalled.load()) {
        return;
    }
    gTick.fetch_add(1);
    {
        std::lock_guard state(gState);
        gFramedMask = 0;
    }
    for (std::size_t i = 0; i < gCallbacks.size();) {
        const Scheduled s = gCallbacks[i];
        if (s.callback(s.data) == kCallbackDone) {
            gCallbacks.erase(gCallbacks.begin() + static_cast<long>(i));
        } else {
            ++i;
        }
    }
    std::lock_guard state(gState);
    gMaxFramedPerTick = std::max(gMaxFramedPerTick, __builtin_popcount(gFramedMask));
}

void schedulerLoop() {
    auto next = std::chrono::steady_clock::now();
    while (gRunning.load()) {
        next += std::chrono::nanoseconds(1000000000LL / static_cast<long long>(gRateHz.load()));
        const auto now = std::chrono::steady_clock::now();
        if (next < now - std::chrono::milliseconds(20)) {
            next = now; // fell far behind (loaded machine): do not burst
        }
        std::this_thread::sleep_until(next);
        runTick(true);
    }
}

void stopThread() {
    std::lock_guard lock(gThreadMutex);
    if (gRunning.exchange(false)) {
        gThread.join();
    }
}

} // namespace

#define FAKEHD_EXPORT extern "C" __attribute__((visibility("default")))

// ---- HD API ---------------------------------------------------------------------------------

FAKEHD_EXPORT HHD hdInitDevice(HDstring name) {
    std::lock_guard lock(gState);
    int index = -1;
    if (name == nullptr) {
        index = 0;
    } else {
        for (int i = 0; i < kDevices; ++i) {
            if (std::strcmp(name, kNames[i]) == 0) {
                index = i;
            }
        }
    }
    if (index < 0 || gDevices[index].removed) {
        pushError(kCommConfigError, 7);
        return kInvalidHandle;
    }
    if (gDevices[index].initialised) {
        pushError(kDeviceAlreadyInitiated);
        return kInvalidHandle;
    }
    if (gRunning.load()) {
        ++gInitWhileRunning;
    }
    gDevices[index].initialised = true;
    gDevices[index].forceOutput = false;
    tCurrent = static_cast<HHD>(index + 1);
    return tCurrent;
}

FAKEHD_EXPORT void hdDisableDevice(HHD h) {
    std::lock_guard lock(gState);
    const int i = indexOf(h);
    if (i < 0 || !gDevices[i].initialised) {
        pushError(kBadHandle);
        return;
    }
    FakeDevice& d = gDevices[i];
    d.initialised = false;
    d.forceOutput = false; // lastForce stays: it shows what the last frame applied
}

FAKEHD_EXPORT void hdMakeCurrentDevice(HHD h) {
    if (indexOf(h) < 0) {
        pushError(kBadHandle);
        return;
    }
    tCurrent = h;
}

FAKEHD_EXPORT void hdBeginFrame(HHD h) {
    std::lock_guard lock(gState);
    const int i = indexOf(h);
    if (i < 0 || !gDevices[i].initialised) {
        pushError(kBadHandle);
        return;
    }
    tCurrent = h;
    FakeDevice& d = gDevices[i];
    if (d.removed) {
        pushError(kCommError, -5);
        return;
    }
    if (d.inFrame) {
        pushError(kIllegalBegin);
        return;
    }
    d.inFrame = true;
    positionNow(d, d.framePos);
    std::fill(std::begin(d.pendingForce), std::end(d.pendingForce), 0.0);
    gFramedMask |= 1u << i;
}

FAKEHD_EXPORT void hdEndFrame(HHD h) {
    std::lock_guard lock(gState);
    const int i = indexOf(h);
    if (i < 0 || !gDevices[i].initialised) {
        pushError(kBadHandle);
        return;
    }
    FakeDevice& d = gDevices[i];
    if (!d.inFrame) {
        if (!d.removed) {
            pushError(kIllegalEnd);
        }
        return;
    }
    d.inFrame = false;
    if (d.injectCode != kSuccess) {
        pushError(d.injectCode, d.injectInternal);
        d.injectCode = kSuccess;
    }
    if (d.forceOutput) {
        std::copy(std::begin(d.pendingForce), std::end(d.pendingForce), d.lastForce);
        ++d.forceFrames;
        const double m =
            std::sqrt(d.lastForce[0] * d.lastForce[0] + d.lastForce[1] * d.lastForce[1] +
                      d.lastForce[2] * d.lastForce[2]);
        d.maxForceSeen = std::max(d.maxForceSeen, m);
    } else {
        std::fill(std::begin(d.lastForce), std::end(d.lastForce), 0.0);
    }
}

FAKEHD_EXPORT HDErrorInfo hdGetError() {
    if (tErrors.empty()) {
        return HDErrorInfo{kSuccess, 0, tCurrent};
    }
    const HDErrorInfo e = tErrors.back();
    tErrors.pop_back();
    return e;
}

FAKEHD_EXPORT HDstring hdGetErrorString(HDerror code) {
    switch (code) {
    case kSuccess:
        return "No error";
    case kCommError:
        return "Communication error (fake)";
    case kCommConfigError:
        return "Device configuration not found (fake)";
    case 0x0300:
        return "Device fault (fake)";
    case kBadHandle:
        return "Bad handle (fake)";
    default:
        return "Some HD error (fake)";
    }
}

FAKEHD_EXPORT void hdEnable(HDenum cap) {
    std::lock_guard lock(gState);
    FakeDevice* d = current();
    if (!d || cap != kForceOutput) {
        pushError(d ? kInvalidEnum : kBadHandle);
        return;
    }
    d->forceOutput = true;
}

FAKEHD_EXPORT void hdDisable(HDenum cap) {
    std::lock_guard lock(gState);
    FakeDevice* d = current();
    if (!d || cap != kForceOutput) {
        pushError(d ? kInvalidEnum : kBadHandle);
        return;
    }
    d->forceOutput = false;
}

FAKEHD_EXPORT void hdGetDoublev(HDenum name, HDdouble* out) {
    std::lock_guard lock(gState);
    FakeDevice* d = current();
    if (!d) {
        pushError(kBadHandle);
        return;
    }
    switch (name) {
    case kCurrentPosition:
        if (d->inFrame) {
            std::copy(std::begin(d->framePos), std::end(d->framePos), out);
        } else {
            positionNow(*d, out);
        }
        break;
    case kCurrentVelocity:
        std::copy(std::begin(d->v), std::end(d->v), out);
        break;
    case kCurrentTransform: {
        // Rodrigues: R = I cos a + sin a [k]x + (1 - cos a) k k^T, then hduMatrix's layout.
        const double* k = d->axis;
        const double c = std::cos(d->angle), s = std::sin(d->angle);
        double r[3][3];
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                r[i][j] = (i == j ? c : 0.0) + (1.0 - c) * k[i] * k[j];
            }
        }
        r[0][1] -= s * k[2];
        r[0][2] += s * k[1];
        r[1][0] += s * k[2];
        r[1][2] -= s * k[0];
        r[2][0] -= s * k[1];
        r[2][1] += s * k[0];
        double p[3];
        if (d->inFrame) {
            std::copy(std::begin(d->framePos), std::end(d->framePos), p);
        } else {
            positionNow(*d, p);
        }
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
                out[4 * i + j] = r[j][i];
            }
            out[4 * i + 3] = 0.0;
            out[12 + i] = p[i];
        }
        out[15] = 1.0;
        break;
    }
    case kCurrentGimbalAngles:
        std::copy(std::begin(d->gimbal), std::end(d->gimbal), out);
        break;
    case kNominalMaxForce:
        *out = 3.3; // N, a Touch
        break;
    case kNominalMaxStiffness:
        *out = 1.26; // N/mm
        break;
    case kUsableWorkspaceDimensions: {
        const double ws[6] = {-80, -60, -35, 80, 60, 35}; // mm
        std::copy(std::begin(ws), std::end(ws), out);
        break;
    }
    default:
        pushError(kInvalidEnum);
    }
}

FAKEHD_EXPORT void hdGetIntegerv(HDenum name, HDint* out) {
    std::lock_guard lock(gState);
    FakeDevice* d = current();
    if (!d) {
        pushError(kBadHandle);
        return;
    }
    if (name != kCurrentButtons) {
        pushError(kInvalidEnum);
        return;
    }
    *out = d->buttons;
}

FAKEHD_EXPORT HDstring hdGetString(HDenum name) {
    switch (name) {
    case kDeviceModelType:
        return "Fake Touch";
    case kDeviceVendor:
        return "hapto tests";
    case kDeviceSerialNumber:
        return "FAKE-0001";
    default:
        pushError(kInvalidEnum);
        return nullptr;
    }
}

FAKEHD_EXPORT void hdSetDoublev(HDenum name, const HDdouble* values) {
    std::lock_guard lock(gState);
    FakeDevice* d = current();
    if (!d) {
        pushError(kBadHandle);
        return;
    }
    if (name != kCurrentForce) {
        pushError(kInvalidEnum);
        return;
    }
    if (!d->inFrame) {
        pushError(kInvalidOperation);
        return;
    }
    std::copy(values, values + 3, d->pendingForce);
}

FAKEHD_EXPORT void hdStartScheduler() {
    std::lock_guard lock(gThreadMutex);
    if (gRunning.exchange(true)) {
        return;
    }
    ++gStarts;
    gThread = std::thread(schedulerLoop);
}

FAKEHD_EXPORT void hdStopScheduler() {
    stopThread();
}

FAKEHD_EXPORT void hdSetSchedulerRate(HDulong rateHz) {
    if (rateHz < 100 || rateHz > 10000) {
        pushError(0x0101);
        return;
    }
    gRateHz.store(rateHz);
}

FAKEHD_EXPORT HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback cb, void* data,
                                                       HDushort priority) {
    std::lock_guard lock(gSched);
    const Scheduled s{gNextHandle++, cb, data, priority};
    const auto at = std::find_if(gCallbacks.begin(), gCallbacks.end(),
                                 [&](const Scheduled& o) { return o.priority < priority; });
    gCallbacks.insert(at, s);
    return s.handle;
}

FAKEHD_EXPORT void hdUnschedule(HDSchedulerHandle handle) {
    std::lock_guard lock(gSched); // waits for a tick in progress
    const auto it = std::find_if(gCallbacks.begin(), gCallbacks.end(),
                                 [&](const Scheduled& s) { return s.handle == handle; });
    if (it == gCallbacks.end()) {
        pushError(kInvalidOperation);
        return;
    }
    gCallbacks.erase(it);
}

// ---- test hooks -----------------------------------------------------------------------------

/// Stops the scheduler, drops every callback, and puts every device back to its start.
FAKEHD_EXPORT void fakehd_reset() {
    gStalled.store(false);
    stopThread();
    {
        std::lock_guard sched(gSched);
        gCallbacks.clear();
    }
    std::lock_guard lock(gState);
    for (auto& d : gDevices) {
        d = FakeDevice{};
    }
    gTick.store(0);
    gRateHz.store(1000);
    gInitWhileRunning = 0;
    gFramedMask = 0;
    gMaxFramedPerTick = 0;
    gStarts.store(0);
    tErrors.clear();
}

/// The device's position p (mm) at scheduler time 0 and its constant velocity v (mm/s).
FAKEHD_EXPORT void fakehd_set_motion(int dev, double px, double py, double pz, double vx, double vy,
                                     double vz) {
    std::lock_guard lock(gState);
    FakeDevice& d = gDevices[dev];
    const double t = static_cast<double>(gTick.load()) / static_cast<double>(gRateHz.load());
    // Keep p0 + v t continuous from now on: p0 is chosen so the position NOW is p.
    const double p[3] = {px, py, pz}, v[3] = {vx, vy, vz};
    for (int k = 0; k < 3; ++k) {
        d.v[k] = v[k];
        d.p0[k] = p[k] - v[k] * t;
    }
}

/// The stylus orientation: a rotation of `angle` rad about the unit axis (x, y, z), and the
/// gimbal angles (rad) reported with it.
FAKEHD_EXPORT void fakehd_set_stylus(int dev, double x, double y, double z, double angle, double g0,
                                     double g1, double g2) {
    std::lock_guard lock(gState);
    FakeDevice& d = gDevices[dev];
    d.axis[0] = x;
    d.axis[1] = y;
    d.axis[2] = z;
    d.angle = angle;
    d.gimbal[0] = g0;
    d.gimbal[1] = g1;
    d.gimbal[2] = g2;
}

FAKEHD_EXPORT void fakehd_set_buttons(int dev, int mask) {
    std::lock_guard lock(gState);
    gDevices[dev].buttons = mask;
}

/// The force (N) the device's last frame applied (zero for a frame with force output off, and
/// after removal). hdDisableDevice leaves it, so it shows the last force before release.
FAKEHD_EXPORT void fakehd_last_force(int dev, double out[3]) {
    std::lock_guard lock(gState);
    std::copy(std::begin(gDevices[dev].lastForce), std::end(gDevices[dev].lastForce), out);
}

FAKEHD_EXPORT unsigned long long fakehd_force_frames(int dev) {
    std::lock_guard lock(gState);
    return gDevices[dev].forceFrames;
}

FAKEHD_EXPORT double fakehd_max_force_seen(int dev) {
    std::lock_guard lock(gState);
    return gDevices[dev].maxForceSeen;
}

/// The next hdEndFrame of the device pushes this error.
FAKEHD_EXPORT void fakehd_inject_error(int dev, unsigned code, int internal) {
    std::lock_guard lock(gState);
    gDevices[dev].injectCode = code;
    gDevices[dev].injectInternal = internal;
}

/// While on, the scheduler thread keeps running but calls no callback.
FAKEHD_EXPORT void fakehd_stall(int on) {
    std::lock_guard sched(gSched); // a tick in progress finishes first
    gStalled.store(on != 0);
}

/// Runs `ticks` scheduler ticks now, on the calling thread (use with fakehd_stall(1), so the
/// scheduler thread runs none in between). Returns the tick count afterwards.
FAKEHD_EXPORT unsigned long long fakehd_step(int ticks) {
    for (int i = 0; i < ticks; ++i) {
        runTick(false);
    }
    return gTick.load();
}

/// Unplugs the device: hdBeginFrame fails with HD_COMM_ERROR, no force reaches it.
FAKEHD_EXPORT void fakehd_remove_device(int dev) {
    std::lock_guard lock(gState);
    gDevices[dev].removed = true;
    std::fill(std::begin(gDevices[dev].lastForce), std::end(gDevices[dev].lastForce), 0.0);
}

FAKEHD_EXPORT int fakehd_is_initialised(int dev) {
    std::lock_guard lock(gState);
    return gDevices[dev].initialised ? 1 : 0;
}

FAKEHD_EXPORT int fakehd_force_output_enabled(int dev) {
    std::lock_guard lock(gState);
    return gDevices[dev].forceOutput ? 1 : 0;
}

FAKEHD_EXPORT int fakehd_scheduler_running() {
    return gRunning.load() ? 1 : 0;
}

FAKEHD_EXPORT int fakehd_scheduler_starts() {
    return gStarts.load();
}

FAKEHD_EXPORT int fakehd_callbacks_scheduled() {
    std::lock_guard lock(gSched);
    return static_cast<int>(gCallbacks.size());
}

/// The most devices framed within one scheduler tick so far.
FAKEHD_EXPORT int fakehd_max_devices_per_tick() {
    std::lock_guard lock(gState);
    return gMaxFramedPerTick;
}

FAKEHD_EXPORT int fakehd_init_while_running() {
    std::lock_guard lock(gState);
    return gInitWhileRunning;
}

FAKEHD_EXPORT unsigned long long fakehd_ticks() {
    return gTick.load();
}
