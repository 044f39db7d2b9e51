#pragma once
/// A test device: follows a position function of the tick, records every force written, and
/// injects faults on request. Given a ManualClock (useClock), time it "takes" (a stall, a slow
/// tick, an absence) moves that clock on instead of sleeping: the runtime's step mode.

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/runtime/ManualClock.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace hapto::test {

/// What to inject, from which tick on.
enum class Inject { Nothing, ReadError, Disconnect, NonFinite, Stall, SlowTicks, OpenFails };

class ScriptedDevice : public Device {
public:
    using Path = std::function<Vec3(std::uint64_t tick)>;

    ScriptedDevice(std::string name, Path path) : mName(std::move(name)), mPath(std::move(path)) {}

    /// Replaces the position function (before start). [control]
    void setPath(Path path) { mPath = std::move(path); }

    /// Injects `what` from read `fromTick` on (SlowTicks: each read takes slowNs, up to read
    /// `untilTick`; Stall: read `fromTick` takes 300 ms). [control]
    void inject(Inject what, std::uint64_t fromTick, std::uint64_t slowNs = 0,
                std::uint64_t untilTick = ~0ull) {
        mInject = what;
        mFromTick = fromTick;
        mSlowNs = slowNs;
        mUntilTick = untilTick;
    }
    /// Step mode: stalls and slow ticks advance `clock` instead of sleeping, and forces are
    /// kept as a history (forces()). [control]
    void useClock(ManualClock* clock) { mClock = clock; }
    /// Step mode: from read `fromRead` on the device is unplugged (reads and opens say
    /// Disconnected) until the clock reaches `backAtNs`. [control]
    void goAway(std::uint64_t fromRead, std::uint64_t backAtNs) {
        mAwayFrom = fromRead;
        mBackAtNs = backAtNs;
    }
    /// Step mode: every open() takes `ns` of the clock. [control]
    void setOpenTakes(std::uint64_t ns) { mOpenNs = ns; }

    std::string_view name() const override { return mName; }
    DeviceKind kind() const override { return DeviceKind::Scripted; }
    DeviceCapabilities capabilities() const override {
        return {"scripted test device", Aabb{Vec3(-1), Vec3(1)}, 10.0, 0.0, 1000.0, 0};
    }
    DeviceStatus open() override {
        if (mInject == Inject::OpenFails) {
            return DeviceStatus::Error;
        }
        if (mClock) {
            mClock->advance(mOpenNs);
            if (gone()) {
                return DeviceStatus::Disconnected;
            }
        }
        ++mOpens;
        mOpen = true;
        return DeviceStatus::Ok;
    }
    void close() override {
        if (mOpen) {
            recordForce(Vec3(0.0));
        }
        mOpen = false;
        mClosed = true;
    }
    DeviceStatus read(DeviceState& s) noexcept override {
        const std::uint64_t t = mReads.load(std::memory_order_relaxed);
        mReads.store(t + 1, std::memory_order_relaxed);
        if (mClock && t >= mAwayFrom && gone()) {
            return DeviceStatus::Disconnected;
        }
        if (t >= mFromTick) {
            switch (mInject) {
            case Inject::ReadError:
                return DeviceStatus::Error;
            case Inject::Disconnect:
                return DeviceStatus::Disconnected;
            case Inject::NonFinite:
                s.position = Vec3(std::numeric_limits<double>::quiet_NaN());
                return DeviceStatus::Ok;
            case Inject::Stall:
                if (t == mFromTick) {
                    pass(300'000'000);
                }
                break;
            case Inject::SlowTicks:
                if (t < mUntilTick) {
                    pass(mSlowNs);
                }
                break;
            default:
                break;
            }
        }
        s.position = mPath(t);
        s.hasVelocity = false;
        s.sequence = t;
        return DeviceStatus::Ok;
    }
    DeviceStatus write(const Vec3& f) noexcept override {
        recordForce(f);
        return DeviceStatus::Ok;
    }
    void periodsSkipped(std::uint64_t periods) noexcept override {
        mSkipped.fetch_add(periods, std::memory_order_relaxed);
    }
    std::string errorMessage() const override {
        return mInject == Inject::OpenFails ? "injected open failure" : "";
    }

    std::uint64_t reads() const { return mReads.load(); }
    /// Periods the servo told this device it skipped (periodsSkipped), in total.
    std::uint64_t skippedPeriods() const { return mSkipped.load(); }
    std::uint64_t opens() const { return mOpens; }
    /// Step mode: every force written, with the read count when it was written. [control]
    struct Written {
        std::uint64_t reads;
        Vec3 force;
    };
    std::vector<Written> forces() const {
        std::lock_guard lock(mHistoryMutex);
        return mHistory;
    }
    std::uint64_t writes() const { return mWrites.load(); }
    Vec3 lastForce() const { return {mLast[0].load(), mLast[1].load(), mLast[2].load()}; }
    double maxForceSeen() const { return mMaxForce.load(); }
    /// |force| of the first write that came more than 20 ms after the one before it (a thread
    /// that could not run); negative if no such gap happened.
    double forceAfterGap() const { return mForceAfterGap.load(); }
    /// Forgets any gap seen so far: forceAfterGap() is about the gaps from here on.
    void forgetGaps() { mForceAfterGap.store(-1.0); }
    /// Largest force magnitude written while reads >= tick (for "zero after K misses" checks).
    bool closed() const { return mClosed; }

private:
    bool gone() const { return mClock && mAwayFrom != ~0ull && mClock->nowNs() < mBackAtNs; }
    void pass(std::uint64_t ns) {
        if (mClock) {
            mClock->advance(ns);
        } else {
            std::this_thread::sleep_for(std::chrono::nanoseconds(ns));
        }
    }
    void recordForce(const Vec3& f) {
        const std::int64_t now = mClock ? static_cast<std::int64_t>(mClock->nowNs())
                                        : std::chrono::duration_cast<std::chrono::nanoseconds>(
                                              std::chrono::steady_clock::now().time_since_epoch())
                                              .count();
        if (mClock) {
            std::lock_guard lock(mHistoryMutex);
            mHistory.push_back({mReads.load(), f});
        }
        const auto last = mLastWriteNs.exchange(now);
        if (last != 0 && now - last > 20'000'000 && mForceAfterGap.load() < 0) {
            mForceAfterGap.store(glm::length(f));
        }
        for (int i = 0; i < 3; ++i) {
            mLast[i].store(f[i]);
        }
        const double n = glm::length(f);
        if (n > mMaxForce.load()) {
            mMaxForce.store(n);
        }
        mWrites.fetch_add(1);
    }

    std::string mName;
    Path mPath;
    Inject mInject = Inject::Nothing;
    std::uint64_t mFromTick = 0, mSlowNs = 0, mUntilTick = ~0ull;
    ManualClock* mClock = nullptr;
    std::uint64_t mAwayFrom = ~0ull, mBackAtNs = 0, mOpenNs = 0, mOpens = 0;
    mutable std::mutex mHistoryMutex;
    std::vector<Written> mHistory;
    std::atomic<std::uint64_t> mReads{0}, mWrites{0}, mSkipped{0};
    std::atomic<double> mLast[3]{};
    std::atomic<double> mMaxForce{0};
    std::atomic<double> mForceAfterGap{-1.0};
    std::atomic<std::int64_t> mLastWriteNs{0};
    bool mOpen = false, mClosed = false;
};

/// A millisecond on the runtime's clocks (ns).
inline constexpr std::uint64_t kMs = 1'000'000;

/// The configuration the runtime tests give scripted device i: named "d<i>", at `rateHz`,
/// forces clamped at 5 N.
inline DeviceConfig scriptedConfig(int i, double rateHz) {
    DeviceConfig c;
    c.name = "d" + std::to_string(i);
    c.kind = DeviceKind::Scripted;
    c.rateHz = rateHz;
    c.maxForceN = 5.0;
    return c;
}

/// A path that starts 1 cm above the top face of a 5 cm cube at the origin and presses 2 mm
/// into it after 50 ticks, then holds.
inline ScriptedDevice::Path pressIntoCube(double x = 0.0) {
    return [x](std::uint64_t t) {
        const double top = 0.025;
        if (t < 50) {
            return Vec3(x, top + 0.01 - 0.012 * static_cast<double>(t) / 50.0, 0.0);
        }
        return Vec3(x, top - 0.002, 0.0);
    };
}

/// pressIntoCube(x), lifted off at read 400 (1 cm above the top face) and pressing again from
/// read 500 on.
inline ScriptedDevice::Path pressLiftPress(double x) {
    const ScriptedDevice::Path press = pressIntoCube(x);
    return [press](std::uint64_t t) {
        if (t < 400) {
            return press(t);
        }
        if (t < 500) {
            return press(0);
        }
        return press(t - 500);
    };
}

/// Whether any of a report's events (a DeviceReport's) contains `text`.
template <class Report> bool hasEvent(const Report& d, const std::string& text) {
    return std::any_of(d.events.begin(), d.events.end(),
                       [&](const std::string& e) { return e.find(text) != std::string::npos; });
}

} // namespace hapto::test
