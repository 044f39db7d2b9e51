// Supervision without the control thread: the watchdog, recovery and a slow open run on the
// runtime's own threads. These need the wall clock ([realtime]): they wait, with a generous
// bound, for what must eventually happen, and assert no counts of ticks or sleeps. The test
// thread never calls maintain(): it stands for a control thread that is blocked.

#include "CubeScene.h"
#include "ScriptedDevice.h"

#include "hapto/devices/FaultInjectingDevice.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/Runtime.h"

#include <catch2/catch.hpp>

#include <condition_variable>
#include <mutex>
#include <thread>

using namespace hapto;
using test::cubeScene;
using test::ScriptedDevice;

namespace {

/// A scripted device whose open() can be held shut (a Falcon homing for 30 s), and which
/// notes how many reads any device of the test had made when it was opened.
class GatedDevice : public ScriptedDevice {
public:
    GatedDevice(std::string name, std::atomic<std::uint64_t>& allReads)
        : ScriptedDevice(std::move(name), test::pressIntoCube()), mAllReads(allReads) {}

    void holdOpens(bool hold) {
        {
            std::lock_guard lock(mMutex);
            mHold = hold;
        }
        mGate.notify_all();
    }
    bool openWaiting() const { return mWaiting.load(); }
    std::uint64_t readsSeenAtFirstOpen() const { return mReadsAtFirstOpen.load(); }

    DeviceStatus open() override {
        std::uint64_t unset = kUnset;
        mReadsAtFirstOpen.compare_exchange_strong(unset, mAllReads.load());
        std::unique_lock lock(mMutex);
        mWaiting.store(mHold);
        mGate.wait(lock, [&] { return !mHold; });
        mWaiting.store(false);
        return ScriptedDevice::open();
    }
    DeviceStatus read(DeviceState& s) noexcept override {
        mAllReads.fetch_add(1);
        return ScriptedDevice::read(s);
    }

private:
    static constexpr std::uint64_t kUnset = ~0ull;
    std::atomic<std::uint64_t>& mAllReads;
    std::atomic<std::uint64_t> mReadsAtFirstOpen{kUnset};
    std::mutex mMutex;
    std::condition_variable mGate;
    bool mHold = false;
    std::atomic<bool> mWaiting{false};
};

struct SupervisedRig {
    World world{cubeScene(), IndexSpec::parse(kDefaultIndexSpec)};
    std::atomic<std::uint64_t> allReads{0};
    std::vector<GatedDevice*> devices;
    std::vector<FaultInjectingDevice*> injectors;
    std::unique_ptr<Runtime> runtime;

    SupervisedRig(int count, RuntimeOptions options) {
        std::vector<RuntimeDevice> rds;
        for (int i = 0; i < count; ++i) {
            auto d = std::make_unique<GatedDevice>("d" + std::to_string(i), allReads);
            devices.push_back(d.get());
            auto wrapped = std::make_unique<FaultInjectingDevice>(std::move(d));
            injectors.push_back(wrapped.get());
            DeviceConfig c;
            c.name = "d" + std::to_string(i);
            c.kind = DeviceKind::Scripted;
            c.rateHz = 1000.0;
            rds.push_back({std::move(wrapped), c, nullptr});
        }
        options.realtime = false;
        runtime = std::make_unique<Runtime>(world, std::move(rds), options);
    }

    /// Waits (without maintain()) until `done`, at most 20 s; true if it came.
    template <class F> bool waitFor(F done) {
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
        while (!done() && std::chrono::steady_clock::now() < until) {
            std::this_thread::yield();
        }
        return done();
    }
    const DeviceReport device(std::size_t i) const { return runtime->report().devices.at(i); }
};

} // namespace

TEST_CASE("every device is opened before any servo thread starts", "[realtime]") {
    SupervisedRig rig(3, {});
    rig.runtime->start();
    REQUIRE(rig.waitFor([&] { return rig.devices[2]->reads() > 10; }));
    for (GatedDevice* d : rig.devices) {
        CHECK(d->readsSeenAtFirstOpen() == 0);
    }
    rig.runtime->stop();
}

TEST_CASE("a watchdog fault is recovered like any other fault, and the session goes on",
          "[realtime]") {
    RuntimeOptions opt;
    opt.stallTimeoutNs = 50'000'000;
    opt.reopenAfterNs = 50'000'000;
    SupervisedRig rig(2, opt);
    rig.runtime->start();
    REQUIRE(rig.waitFor([&] { return rig.devices[0]->reads() > 100; }));
    // The device hangs inside read() for 300 ms: as a stalled host or USB stack would.
    rig.injectors[0]->inject(InjectedFault::Stall, 300'000'000);
    bool alwaysRunning = true;
    REQUIRE(rig.waitFor([&] {
        alwaysRunning = alwaysRunning && rig.runtime->anyRunning();
        return rig.device(0).reopens >= 1;
    }));
    const DeviceReport d = rig.device(0);
    INFO(d.fault);
    CHECK(alwaysRunning);
    CHECK(d.faults >= 1);
    CHECK(test::hasEvent(d, "watchdog"));
    CHECK(test::hasEvent(d, "reopened"));
    CHECK(rig.injectors[0]->firstForceAfterFault() == 0.0); // the stalled tick sent nothing
    // Driven again: it ticks and presses into the cube once more.
    const std::uint64_t before = rig.devices[0]->reads();
    REQUIRE(rig.waitFor([&] { return rig.devices[0]->reads() > before + 100; }));
    CHECK(rig.runtime->anyRunning());
    rig.runtime->stop();
    CHECK_FALSE(rig.runtime->anyRunning());
    CHECK(glm::length(rig.devices[0]->lastForce()) == 0.0);
    CHECK(glm::length(rig.devices[1]->lastForce()) == 0.0);
}

TEST_CASE("supervision never waits for a slow open: while one device's reopen hangs, another "
          "device's stall is caught, zeroed and recovered",
          "[realtime]") {
    RuntimeOptions opt;
    opt.stallTimeoutNs = 50'000'000;
    opt.reopenAfterNs = 20'000'000;
    SupervisedRig rig(2, opt);
    rig.runtime->start();
    REQUIRE(rig.waitFor([&] { return rig.devices[1]->reads() > 100; }));

    // Device 0 goes away; its reopen then hangs in open() (homing) until released.
    rig.devices[0]->holdOpens(true);
    rig.injectors[0]->inject(InjectedFault::Disconnect, 0);
    REQUIRE(rig.waitFor([&] { return rig.devices[0]->openWaiting(); }));

    // Meanwhile device 1 stalls: the watchdog must still fault it, zero it and reopen it.
    rig.injectors[1]->inject(InjectedFault::Stall, 300'000'000);
    REQUIRE(rig.waitFor([&] { return rig.device(1).reopens >= 1; }));
    CHECK(rig.devices[0]->openWaiting()); // all of it while device 0's open still hangs
    CHECK(test::hasEvent(rig.device(1), "watchdog"));
    CHECK(rig.injectors[1]->firstForceAfterFault() == 0.0);
    CHECK(rig.runtime->anyRunning());

    rig.devices[0]->holdOpens(false);
    REQUIRE(rig.waitFor([&] { return rig.device(0).reopens >= 1; }));
    CHECK(rig.device(0).fault.empty());
    rig.runtime->stop();
}

TEST_CASE("stop() during a hanging reopen waits for it and leaves every device at zero force",
          "[realtime]") {
    RuntimeOptions opt;
    opt.reopenAfterNs = 10'000'000;
    SupervisedRig rig(2, opt);
    rig.runtime->start();
    REQUIRE(rig.waitFor([&] { return rig.devices[0]->reads() > 100; }));
    rig.devices[0]->holdOpens(true);
    rig.injectors[0]->inject(InjectedFault::ReadError, 0);
    REQUIRE(rig.waitFor([&] { return rig.devices[0]->openWaiting(); }));
    std::thread release([&] {
        // stop() is waiting for the open; let the open return.
        while (rig.runtime->anyRunning()) {
            std::this_thread::yield();
        }
        rig.devices[0]->holdOpens(false);
    });
    rig.runtime->stop();
    release.join();
    for (GatedDevice* d : rig.devices) {
        CHECK(glm::length(d->lastForce()) == 0.0);
        CHECK(d->closed());
    }
}

TEST_CASE("emergencyStop from another thread zeroes and closes every device without the "
          "control thread",
          "[realtime]") {
    SupervisedRig rig(2, {});
    rig.runtime->start();
    REQUIRE(rig.waitFor([&] {
        return glm::length(rig.devices[0]->lastForce()) > 0.1 &&
               glm::length(rig.devices[1]->lastForce()) > 0.1;
    }));
    std::thread second([&] { rig.runtime->emergencyStop(); });
    second.join();
    CHECK_FALSE(rig.runtime->anyRunning());
    for (std::size_t i = 0; i < 2; ++i) {
        CHECK(glm::length(rig.devices[i]->lastForce()) == 0.0);
        CHECK(rig.devices[i]->closed());
        CHECK_FALSE(rig.runtime->metrics(i).running.load());
    }
    rig.runtime->stop(); // after an emergency stop, the orderly one is still safe
}
