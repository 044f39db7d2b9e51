#include "hapto/devices/FaultInjectingDevice.h"

#include "hapto/core/Clock.h"

#include <cerrno>
#include <cmath>
#include <ctime>
#include <limits>

namespace hapto {

const char* injectedFaultName(InjectedFault fault) noexcept {
    switch (fault) {
    case InjectedFault::None:
        return "none";
    case InjectedFault::Disconnect:
        return "disconnect";
    case InjectedFault::Garbage:
        return "garbage";
    case InjectedFault::ReadError:
        return "read-error";
    case InjectedFault::Stall:
        return "stall";
    }
    return "unknown";
}

FaultInjectingDevice::FaultInjectingDevice(std::unique_ptr<Device> inner)
    : mInner(std::move(inner)) {}

void FaultInjectingDevice::inject(InjectedFault fault, std::uint64_t durationNs) noexcept {
    mDurationNs.store(durationNs, std::memory_order_relaxed);
    mArmed.store(fault, std::memory_order_release);
}

DeviceStatus FaultInjectingDevice::open() {
    if (monotonicNs() < mGoneUntilNs.load(std::memory_order_relaxed)) {
        return DeviceStatus::Disconnected;
    }
    return mInner->open();
}

DeviceStatus FaultInjectingDevice::read(DeviceState& state) noexcept {
    const InjectedFault fault = mArmed.exchange(InjectedFault::None, std::memory_order_acq_rel);
    if (fault == InjectedFault::None) {
        return mInner->read(state);
    }
    mTaken.fetch_add(1, std::memory_order_relaxed);
    mAwaitingWrite.store(true, std::memory_order_relaxed);
    const std::uint64_t duration = mDurationNs.load(std::memory_order_relaxed);
    switch (fault) {
    case InjectedFault::Disconnect:
        mGoneUntilNs.store(monotonicNs() + duration, std::memory_order_relaxed);
        return DeviceStatus::Disconnected;
    case InjectedFault::Garbage:
        state.position = Vec3(std::numeric_limits<double>::quiet_NaN());
        return DeviceStatus::Ok;
    case InjectedFault::ReadError:
        return DeviceStatus::Error;
    case InjectedFault::Stall: {
        // The device blocks the servo thread, as a hung USB transfer would.
        const std::uint64_t until = monotonicNs() + duration;
        timespec ts{static_cast<time_t>(until / 1'000'000'000ull),
                    static_cast<long>(until % 1'000'000'000ull)};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
        }
        return mInner->read(state);
    }
    case InjectedFault::None:
        break;
    }
    return mInner->read(state);
}

DeviceStatus FaultInjectingDevice::write(const Vec3& forceN) noexcept {
    if (mAwaitingWrite.exchange(false, std::memory_order_relaxed)) {
        mForceAfter.store(
            std::sqrt(forceN.x * forceN.x + forceN.y * forceN.y + forceN.z * forceN.z),
            std::memory_order_relaxed);
    }
    return mInner->write(forceN);
}

std::string FaultInjectingDevice::errorMessage() const {
    if (monotonicNs() < mGoneUntilNs.load(std::memory_order_relaxed)) {
        return "injected disconnect: the device is away";
    }
    return mInner->errorMessage();
}

} // namespace hapto
