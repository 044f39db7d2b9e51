#pragma once
/// A Device decorator that injects faults on command: for fault-injection tests and
/// `hapto soak`. It forwards everything to the wrapped device; an armed fault takes over the
/// next read().

#include "hapto/devices/Device.h"

#include <atomic>
#include <cstdint>
#include <memory>

namespace hapto {

/// A fault to inject at the next read().
enum class InjectedFault : std::uint8_t {
    None,
    Disconnect, ///< read() says Disconnected; open() fails the same way until the device
                ///< "comes back" after the given time.
    Garbage,    ///< read() returns a sample with non-finite coordinates and status Ok.
    ReadError,  ///< read() returns Error once.
    Stall,      ///< read() blocks for the given time once, then reads normally.
};

/// A short name ("disconnect", "garbage", ...). [any thread]
const char* injectedFaultName(InjectedFault fault) noexcept;

/// Wraps a device and injects faults into it. Writes always reach the wrapped device, also
/// while "disconnected", so a test can see what the runtime commanded.
class FaultInjectingDevice : public Device {
public:
    /// Wraps `inner`, passing everything through until a fault is injected. [control]
    explicit FaultInjectingDevice(std::unique_ptr<Device> inner);

    /// Arms `fault` for the next read(). `durationNs` is how long a Disconnect lasts or a
    /// Stall blocks. An armed fault not yet taken is replaced. [control]
    void inject(InjectedFault fault, std::uint64_t durationNs = 0) noexcept;
    /// Faults taken by read() so far. [any thread]
    std::uint64_t injected() const noexcept { return mTaken.load(std::memory_order_relaxed); }
    /// |force| of the first write() after the last injected fault was taken (N); negative
    /// until such a write happened. [any thread]
    double firstForceAfterFault() const noexcept {
        return mForceAfter.load(std::memory_order_relaxed);
    }
    /// The wrapped device. [control]
    Device& inner() noexcept { return *mInner; }

    std::string_view name() const override { return mInner->name(); }
    DeviceKind kind() const override { return mInner->kind(); }
    DeviceCapabilities capabilities() const override { return mInner->capabilities(); }
    DeviceStatus open() override;
    void close() override { mInner->close(); }
    DeviceStatus read(DeviceState& state) noexcept override;
    DeviceStatus write(const Vec3& forceN) noexcept override;
    void periodsSkipped(std::uint64_t periods) noexcept override {
        mInner->periodsSkipped(periods);
    }
    std::string errorMessage() const override;

private:
    std::unique_ptr<Device> mInner;
    std::atomic<InjectedFault> mArmed{InjectedFault::None};
    std::atomic<std::uint64_t> mDurationNs{0};
    std::atomic<std::uint64_t> mGoneUntilNs{0}; // monotonic ns; open() fails before it
    std::atomic<std::uint64_t> mTaken{0};
    std::atomic<bool> mAwaitingWrite{false};
    std::atomic<double> mForceAfter{-1.0};
};

} // namespace hapto
