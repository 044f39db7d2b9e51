#include "PhantomHdApi.h"

#include <dlfcn.h>

#include <cstdio>
#include <map>
#include <memory>

namespace hapto::hd {

const char* errorCodeName(HDerror code) {
    switch (code) {
    case kSuccess:
        return "HD_SUCCESS";
    case kInvalidEnum:
        return "HD_INVALID_ENUM";
    case kInvalidValue:
        return "HD_INVALID_VALUE";
    case kInvalidOperation:
        return "HD_INVALID_OPERATION";
    case kInvalidInputType:
        return "HD_INVALID_INPUT_TYPE";
    case kBadHandle:
        return "HD_BAD_HANDLE";
    case kWarmMotors:
        return "HD_WARM_MOTORS";
    case kExceededMaxForce:
        return "HD_EXCEEDED_MAX_FORCE";
    case kExceededMaxForceImpulse:
        return "HD_EXCEEDED_MAX_FORCE_IMPULSE";
    case kExceededMaxVelocity:
        return "HD_EXCEEDED_MAX_VELOCITY";
    case kForceError:
        return "HD_FORCE_ERROR";
    case kDeviceFault:
        return "HD_DEVICE_FAULT";
    case kDeviceAlreadyInitiated:
        return "HD_DEVICE_ALREADY_INITIATED";
    case kCommError:
        return "HD_COMM_ERROR";
    case kCommConfigError:
        return "HD_COMM_CONFIG_ERROR";
    case kTimerError:
        return "HD_TIMER_ERROR";
    case kIllegalBegin:
        return "HD_ILLEGAL_BEGIN";
    case kIllegalEnd:
        return "HD_ILLEGAL_END";
    case kFrameError:
        return "HD_FRAME_ERROR";
    case kInvalidPriority:
        return "HD_INVALID_PRIORITY";
    case kSchedulerFull:
        return "HD_SCHEDULER_FULL";
    case kInvalidLicense:
        return "HD_INVALID_LICENSE";
    default:
        return "HD_UNKNOWN_ERROR";
    }
}

HDErrorInfo HdApi::takeError() const {
    // hdGetError pops the newest error first; the oldest is the cause, later ones are often
    // its consequences (a failed hdBeginFrame makes hdSetDoublev fail too).
    HDErrorInfo oldest{kSuccess, 0, kInvalidHandle};
    for (int i = 0; i < 16; ++i) {
        const HDErrorInfo e = getError();
        if (e.errorCode == kSuccess) {
            break;
        }
        oldest = e;
    }
    return oldest;
}

std::string HdApi::describe(const HDErrorInfo& error) const {
    char code[16];
    std::snprintf(code, sizeof code, "0x%04X", error.errorCode);
    const HDstring text = getErrorString ? getErrorString(error.errorCode) : nullptr;
    std::string s = std::string("HD error ") + code + " " + errorCodeName(error.errorCode);
    if (text && *text) {
        s += std::string(" (") + text + ")";
    }
    s += ", driver code " + std::to_string(error.internalErrorCode);
    return s;
}

namespace {

/// Resolves one symbol into a typed function pointer; records the first missing name.
template <class Fn> void resolve(void* lib, const char* symbol, Fn& out, std::string& missing) {
    void* p = dlsym(lib, symbol);
    if (!p && missing.empty()) {
        missing = symbol;
    }
    // POSIX guarantees object/function pointer round trips for dlsym results.
    out = reinterpret_cast<Fn>(p);
}

std::string notFoundMessage(const std::string& library, const char* dlerr) {
    std::string s = "OpenHaptics " + library +
                    " not found: install OpenHaptics from 3D Systems; hapto loads it at run time";
    if (library != "libHD.so") {
        s += " (the device configuration names \"" + library + "\")";
    }
    if (dlerr) {
        s += std::string(". dlopen said: ") + dlerr;
    }
    return s;
}

} // namespace

std::mutex& hdRegistryMutex() {
    static std::mutex m;
    return m;
}

HdRuntime* findOrLoadHdRuntime(const std::string& library, std::string& whyNot) {
    static std::map<std::string, std::unique_ptr<HdRuntime>> loaded;
    if (auto it = loaded.find(library); it != loaded.end()) {
        return it->second.get();
    }
    void* lib = dlopen(library.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        whyNot = notFoundMessage(library, dlerror());
        return nullptr;
    }
    auto rt = std::make_unique<HdRuntime>();
    rt->path = library;
    HdApi& a = rt->api;
    std::string missing;
    resolve(lib, "hdInitDevice", a.initDevice, missing);
    resolve(lib, "hdDisableDevice", a.disableDevice, missing);
    resolve(lib, "hdMakeCurrentDevice", a.makeCurrentDevice, missing);
    resolve(lib, "hdBeginFrame", a.beginFrame, missing);
    resolve(lib, "hdEndFrame", a.endFrame, missing);
    resolve(lib, "hdGetError", a.getError, missing);
    resolve(lib, "hdGetErrorString", a.getErrorString, missing);
    resolve(lib, "hdEnable", a.enable, missing);
    resolve(lib, "hdDisable", a.disable, missing);
    resolve(lib, "hdGetDoublev", a.getDoublev, missing);
    resolve(lib, "hdGetIntegerv", a.getIntegerv, missing);
    resolve(lib, "hdGetString", a.getString, missing);
    resolve(lib, "hdSetDoublev", a.setDoublev, missing);
    resolve(lib, "hdStartScheduler", a.startScheduler, missing);
    resolve(lib, "hdStopScheduler", a.stopScheduler, missing);
    resolve(lib, "hdSetSchedulerRate", a.setSchedulerRate, missing);
    resolve(lib, "hdScheduleAsynchronous", a.scheduleAsynchronous, missing);
    resolve(lib, "hdUnschedule", a.unschedule, missing);
    if (!missing.empty()) {
        whyNot = library + " loaded but is not a usable OpenHaptics HD library: it has no " +
                 missing + ". Point the device's \"library\" at OpenHaptics' libHD.so";
        dlclose(lib);
        return nullptr;
    }
    HdRuntime* raw = rt.get();
    loaded.emplace(library, std::move(rt));
    return raw;
}

} // namespace hapto::hd
