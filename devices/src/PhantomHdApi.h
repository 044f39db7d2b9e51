#pragma once
/// Private: the few OpenHaptics HD types, constants and functions hapto uses, loaded at run time.
///
/// hapto never includes the vendor's headers nor links libHD at build time. The declarations
/// below are facts of the published HD API (OpenHaptics 3.x, <HD/hdDefines.h>, <HD/hdDevice.h>,
/// <HD/hdScheduler.h>, <HD/hdExport.h>); where each value comes from:
///   - Types (HHD = unsigned int, HDenum/HDerror = unsigned int, HDint = int, HDdouble = double,
///     HDulong = unsigned long, HDushort = unsigned short, HDstring = const char*, the
///     HDErrorInfo layout {errorCode, internalErrorCode, hHD}): hdDefines.h.
///   - Error codes 0x0000..0x0600, parameter codes (HD_CURRENT_BUTTONS 0x2000,
///     HD_CURRENT_POSITION 0x2050, HD_CURRENT_VELOCITY 0x2051, HD_DEVICE_MODEL_TYPE 0x2501,
///     HD_DEVICE_VENDOR 0x2503, HD_DEVICE_SERIAL_NUMBER 0x2504, HD_USABLE_WORKSPACE_DIMENSIONS
///     0x2551, HD_NOMINAL_MAX_STIFFNESS 0x2602, HD_NOMINAL_MAX_FORCE 0x2603, HD_CURRENT_FORCE
///     0x2700, HD_CURRENT_TRANSFORM 0x2052, HD_CURRENT_GIMBAL_ANGLES 0x2150), HD_FORCE_OUTPUT
///     0x4000, HD_INVALID_HANDLE 0xFFFFFFFF, HD_DEFAULT_DEVICE = NULL,
///     scheduler priorities (HD_MAX_SCHEDULER_PRIORITY = USHRT_MAX): hdDefines.h.
///   - HD_CALLBACK_DONE 0 / HD_CALLBACK_CONTINUE 1, HDCallbackCode = unsigned int,
///     HDSchedulerHandle = unsigned long, the callback type HDCallbackCode (*)(void*):
///     hdScheduler.h.
///   - Function signatures: hdDevice.h and hdScheduler.h. On Linux hdExport.h declares HDAPIENTRY
///     as __attribute__((stdcall)), which x86-64 ignores: plain C calling convention. hapto
///     supports x86-64 Linux only for this backend.
///   - Units (OpenHaptics Programmer's Guide and every vendor example): positions and workspace
///     in millimetres, velocity in mm/s, force in newtons, nominal max stiffness in N/mm.
///     Workspace dimensions are six doubles {minX, minY, minZ, maxX, maxY, maxZ}.
///   - HD_CURRENT_TRANSFORM is 16 doubles, the stylus frame as an hduMatrix stores it
///     (HDU/hduMatrix.h: "Constructor from array of 16 values stored by row", translations "set
///     along the last row" {.., x y z 1}, points multiplied as row vectors): element 4 i + j is
///     row i, column j of that row-vector matrix, so m[4 i + j] = R(j, i) for the
///     column-vector rotation R (read as a column-major 4x4, it is the column-vector transform,
///     OpenGL's layout), m[12..14] the position (mm). HD_CURRENT_GIMBAL_ANGLES is 3 doubles,
///     the gimbal joint angles (rad), like HD_CURRENT_JOINT_ANGLES.
/// Consulted: the OpenHaptics 3.x Linux headers as redistributed in a public mirror of the SDK
/// (github.com/danepowell/openhaptics, usr/include/HD/), the SDK's console examples (units,
/// call order: init, enable force output, schedule, start; stop, unschedule, disable), and
/// SenseGraphics' HAPI (HD_NOMINAL_MAX_STIFFNESS times 1e3 = N/m). Reference only; nothing here
/// is copied from them.

#include <climits>
#include <mutex>
#include <string>

namespace hapto::hd {

using HHD = unsigned int;                ///< Device handle.
using HDenum = unsigned int;             ///< Parameter / capability code.
using HDerror = unsigned int;            ///< Error code.
using HDint = int;                       ///< Integer parameter.
using HDdouble = double;                 ///< Floating-point parameter.
using HDulong = unsigned long;           ///< Scheduler rate (Hz).
using HDushort = unsigned short;         ///< Scheduler priority.
using HDstring = const char*;            ///< A C string owned by the library.
using HDCallbackCode = unsigned int;     ///< What a scheduler callback returns.
using HDSchedulerHandle = unsigned long; ///< A scheduled callback.
using HDSchedulerCallback = HDCallbackCode (*)(void* userData); ///< A scheduler callback.

/// What hdGetError returns: the HD code, the driver's own code, and the current device.
struct HDErrorInfo {
    HDerror errorCode;     ///< An HD_* error code; HD_SUCCESS when the stack is empty.
    int internalErrorCode; ///< The device driver's own code.
    HHD hHD;               ///< The current device when the error happened.
};

inline constexpr HDerror kSuccess = 0x0000;
inline constexpr HDerror kInvalidEnum = 0x0100;
inline constexpr HDerror kInvalidValue = 0x0101;
inline constexpr HDerror kInvalidOperation = 0x0102;
inline constexpr HDerror kInvalidInputType = 0x0103;
inline constexpr HDerror kBadHandle = 0x0104;
inline constexpr HDerror kWarmMotors = 0x0200;
inline constexpr HDerror kExceededMaxForce = 0x0201;
inline constexpr HDerror kExceededMaxForceImpulse = 0x0202;
inline constexpr HDerror kExceededMaxVelocity = 0x0203;
inline constexpr HDerror kForceError = 0x0204;
inline constexpr HDerror kDeviceFault = 0x0300;
inline constexpr HDerror kDeviceAlreadyInitiated = 0x0301;
inline constexpr HDerror kCommError = 0x0302;
inline constexpr HDerror kCommConfigError = 0x0303;
inline constexpr HDerror kTimerError = 0x0304;
inline constexpr HDerror kIllegalBegin = 0x0400;
inline constexpr HDerror kIllegalEnd = 0x0401;
inline constexpr HDerror kFrameError = 0x0402;
inline constexpr HDerror kInvalidPriority = 0x0500;
inline constexpr HDerror kSchedulerFull = 0x0501;
inline constexpr HDerror kInvalidLicense = 0x0600;

inline constexpr HDenum kCurrentButtons = 0x2000;
inline constexpr HDenum kCurrentPosition = 0x2050;
inline constexpr HDenum kCurrentVelocity = 0x2051;
inline constexpr HDenum kCurrentTransform = 0x2052;
inline constexpr HDenum kCurrentGimbalAngles = 0x2150;
inline constexpr HDenum kDeviceModelType = 0x2501;
inline constexpr HDenum kDeviceVendor = 0x2503;
inline constexpr HDenum kDeviceSerialNumber = 0x2504;
inline constexpr HDenum kUsableWorkspaceDimensions = 0x2551;
inline constexpr HDenum kNominalMaxStiffness = 0x2602;
inline constexpr HDenum kNominalMaxForce = 0x2603;
inline constexpr HDenum kCurrentForce = 0x2700;
inline constexpr HDenum kForceOutput = 0x4000;

inline constexpr HHD kInvalidHandle = 0xFFFFFFFFu;
inline constexpr HDushort kMaxSchedulerPriority = USHRT_MAX;
inline constexpr HDCallbackCode kCallbackDone = 0;
inline constexpr HDCallbackCode kCallbackContinue = 1;

/// The symbolic name of an HD error code ("HD_COMM_ERROR"), or "HD_UNKNOWN_ERROR". [any thread]
const char* errorCodeName(HDerror code);

/// Every HD function hapto calls, resolved with dlsym from one loaded library.
struct HdApi {
    HHD (*initDevice)(HDstring configName) = nullptr;                  ///< hdInitDevice
    void (*disableDevice)(HHD device) = nullptr;                       ///< hdDisableDevice
    void (*makeCurrentDevice)(HHD device) = nullptr;                   ///< hdMakeCurrentDevice
    void (*beginFrame)(HHD device) = nullptr;                          ///< hdBeginFrame
    void (*endFrame)(HHD device) = nullptr;                            ///< hdEndFrame
    HDErrorInfo (*getError)() = nullptr;                               ///< hdGetError
    HDstring (*getErrorString)(HDerror code) = nullptr;                ///< hdGetErrorString
    void (*enable)(HDenum capability) = nullptr;                       ///< hdEnable
    void (*disable)(HDenum capability) = nullptr;                      ///< hdDisable
    void (*getDoublev)(HDenum name, HDdouble* values) = nullptr;       ///< hdGetDoublev
    void (*getIntegerv)(HDenum name, HDint* values) = nullptr;         ///< hdGetIntegerv
    HDstring (*getString)(HDenum name) = nullptr;                      ///< hdGetString
    void (*setDoublev)(HDenum name, const HDdouble* values) = nullptr; ///< hdSetDoublev
    void (*startScheduler)() = nullptr;                                ///< hdStartScheduler
    void (*stopScheduler)() = nullptr;                                 ///< hdStopScheduler
    void (*setSchedulerRate)(HDulong rateHz) = nullptr;                ///< hdSetSchedulerRate
    HDSchedulerHandle (*scheduleAsynchronous)(HDSchedulerCallback callback, void* userData,
                                              HDushort priority) =
        nullptr;                                            ///< hdScheduleAsynchronous
    void (*unschedule)(HDSchedulerHandle handle) = nullptr; ///< hdUnschedule

    /// Pops every pending error of the calling thread (at most 16); returns the oldest one, the
    /// cause, or {kSuccess} when there was none. [any thread]
    HDErrorInfo takeError() const;
    /// "HD error 0x0302 HD_COMM_ERROR (<library text>), driver code 5". [control]
    std::string describe(const HDErrorInfo& error) const;
};

/// One loaded HD library and its scheduler bookkeeping, shared by every PhantomDevice that
/// names the same library path. Lives until the process ends (never dlclosed: a vendor library
/// may leave threads or atexit handlers behind).
struct HdRuntime {
    std::string path;              ///< The library path as configured.
    HdApi api;                     ///< Its functions.
    int scheduledDevices = 0;      ///< Open devices with a callback on the scheduler. Guarded by
                                   ///< the registry mutex.
    bool schedulerRunning = false; ///< hdStartScheduler was called and not yet stopped. Guarded.
};

/// Finds or loads the HD library at `library`; on failure returns nullptr and says why in
/// `whyNot` (not found / not an HD library / missing symbol). Call with hdRegistryMutex() held.
/// [control]
HdRuntime* findOrLoadHdRuntime(const std::string& library, std::string& whyNot);

/// The process-wide mutex guarding every HdRuntime's bookkeeping and every HD call made from a
/// control thread (open, close, probe). Never taken on a servo or HD scheduler thread.
/// [control]
std::mutex& hdRegistryMutex();

} // namespace hapto::hd
