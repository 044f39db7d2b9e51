// Several simulated devices on one servo thread (RuntimeOptions::devicesPerThread), in the
// runtime's step mode: each member ticks as it would alone, keeps its own load record and
// faults, and a group that stalls or stops leaves every member at zero force. Time a device
// "takes" moves the ManualClock (ScriptedDevice::useClock). One [realtime] case runs real
// group threads and checks only what eventually happens.

#include "ScriptedDevice.h"
#include "SteppedRig.h"
#include "TestSupport.h"

#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <functional>
#include <thread>

using namespace hapto;
using hapto::test::cubeScene;
using test::Inject;
using test::ScriptedDevice;

namespace {

using test::kMs;

/// A stepped runtime of `count` scripted 1 kHz devices over the cube scene, `perThread` to a
/// servo thread: device i presses into the cube at x = 0.004 i - 0.01.
struct Rig : test::SteppedRig {
    Rig(int count, std::size_t perThread, std::function<void(int, ScriptedDevice&)> setup = {},
        RuntimeOptions options = {})
        : SteppedRig(count, 1000.0, std::move(setup), perThreadOptions(options, perThread)) {}

    static RuntimeOptions perThreadOptions(RuntimeOptions options, std::size_t perThread) {
        options.devicesPerThread = perThread;
        return options;
    }
};

/// The forces device `d` was sent, in order.
std::vector<Vec3> forces(const ScriptedDevice& d) {
    std::vector<Vec3> out;
    for (const ScriptedDevice::Written& w : d.forces()) {
        out.push_back(w.force);
    }
    return out;
}

double largest(const std::vector<Vec3>& fs) {
    double m = 0;
    for (const Vec3& f : fs) {
        m = std::max(m, glm::length(f));
    }
    return m;
}

} // namespace

TEST_CASE("each device in a group gets the forces it gets on its own thread") {
    Rig alone(5, 1);
    REQUIRE(alone.start() == 5);
    alone.runTo(300);
    alone.runtime->stop();
    const std::size_t perThread = GENERATE(2u, 3u, 5u);
    INFO("devices per thread " << perThread);
    Rig grouped(5, perThread);
    REQUIRE(grouped.start() == 5);
    grouped.runTo(300);
    grouped.runtime->stop();
    for (std::size_t i = 0; i < 5; ++i) {
        INFO("device " << i);
        const std::vector<Vec3> a = forces(*alone.devices[i]);
        const std::vector<Vec3> g = forces(*grouped.devices[i]);
        CHECK(largest(a) > 0.5); // it pressed into the cube: there is a force to compare
        REQUIRE(g.size() == a.size());
        for (std::size_t k = 0; k < a.size(); ++k) {
            REQUIRE(g[k] == a[k]); // bit for bit
        }
        CHECK(grouped.report(i).ticks == alone.report(i).ticks);
        CHECK(grouped.report(i).ticks == 300);
        CHECK(grouped.devices[i]->lastForce() == Vec3(0.0)); // stop zeroed every member
    }
}

TEST_CASE("a fault in one member zeroes that device and leaves the others of its group running") {
    const Inject what = GENERATE(Inject::NonFinite, Inject::ReadError);
    INFO("inject " << static_cast<int>(what));
    Rig alone(4, 1);
    REQUIRE(alone.start() == 4);
    alone.runTo(300);
    Rig grouped(4, 4, [what](int i, ScriptedDevice& d) {
        if (i == 1) {
            d.inject(what, 100);
        }
    });
    REQUIRE(grouped.start() == 4);
    grouped.runTo(300);
    const DeviceReport bad = grouped.report(1);
    CHECK_FALSE(bad.fault.empty());
    CHECK(bad.ticks == 100);
    CHECK(grouped.devices[1]->lastForce() == Vec3(0.0));
    CHECK(largest(forces(*grouped.devices[1])) > 0.5); // it had force before the fault
    for (std::size_t i : {0u, 2u, 3u}) {
        INFO("device " << i);
        CHECK(grouped.report(i).fault.empty());
        CHECK(grouped.report(i).ticks == 300);
        CHECK(forces(*grouped.devices[i]) == forces(*alone.devices[i]));
        CHECK(glm::length(grouped.devices[i]->lastForce()) > 0.5); // still pressing
    }
}

TEST_CASE("a member that faulted is reopened and ticks again inside its group") {
    RuntimeOptions options;
    options.reopenAfterNs = 20 * kMs;
    Rig rig(3, 3, {}, options);
    REQUIRE(rig.start() == 3);
    rig.devices[2]->goAway(100, rig.t0 + 150 * kMs); // unplugged from read 100 until 150 ms
    rig.runTo(130);
    CHECK_FALSE(rig.report(2).fault.empty());
    CHECK(rig.devices[2]->lastForce() == Vec3(0.0));
    const std::uint64_t before = rig.report(2).ticks;
    rig.runTo(400);
    const DeviceReport back = rig.report(2);
    CHECK(back.fault.empty());
    CHECK(back.reopens == 1);
    CHECK(back.ticks > before + 150); // driven again by its group
    CHECK(rig.report(0).ticks == 400);
    CHECK(rig.report(1).ticks == 400);
    CHECK(rig.report(0).faults == 0);
}

TEST_CASE("a stalled group zeroes every one of its devices, one device stalled alone zeroes "
          "only itself") {
    // Device 0's read 100 takes 300 ms: longer than the watchdog's 50 ms.
    const auto stallFirst = [](int i, ScriptedDevice& d) {
        if (i == 0) {
            d.inject(Inject::Stall, 100);
        }
    };
    Rig grouped(4, 2, stallFirst);
    REQUIRE(grouped.start() == 4);
    grouped.runTo(250);
    for (std::size_t i = 0; i < 2; ++i) { // the stalled group: both down, both at zero
        INFO("device " << i);
        CHECK(grouped.report(i).fault.find("watchdog") != std::string::npos);
        CHECK(grouped.devices[i]->lastForce() == Vec3(0.0));
        CHECK(largest(forces(*grouped.devices[i])) > 0.5);
    }
    for (std::size_t i = 2; i < 4; ++i) { // the other group ran on
        INFO("device " << i);
        CHECK(grouped.report(i).fault.empty());
        CHECK(grouped.report(i).ticks == 250);
    }
    Rig alone(4, 1, stallFirst);
    REQUIRE(alone.start() == 4);
    alone.runTo(250);
    CHECK(alone.report(0).fault.find("watchdog") != std::string::npos);
    CHECK(alone.report(1).fault.empty());
    CHECK(alone.report(1).ticks == 250);
}

TEST_CASE("each member keeps its own load record: a slow member's work is its load, the "
          "wait behind it the others' lateness") {
    // Device 0 takes 300 us per read; the others take no time.
    Rig rig(3, 3, [](int i, ScriptedDevice& d) {
        if (i == 0) {
            d.inject(Inject::SlowTicks, 0, 300'000);
        }
    });
    REQUIRE(rig.start() == 3);
    rig.runTo(200);
    const DeviceReport slow = rig.report(0);
    CHECK(slow.ticks == 200);
    CHECK(slow.loadFraction.mean == Approx(0.3).margin(0.01));
    CHECK(slow.latenessNs.mean < 1000);
    for (std::size_t i = 1; i < 3; ++i) {
        INFO("device " << i);
        const DeviceReport d = rig.report(i);
        CHECK(d.ticks == 200);
        CHECK(d.loadFraction.mean < 0.01);
        CHECK(d.latenessNs.mean == Approx(300'000).margin(10'000)); // it waited for device 0
        CHECK(d.lateWakeups == 200); // 0.3 of a period: past the 0.1 limit
        CHECK(d.missedDeadlines == 0);
        CHECK(d.stable);
    }
}

TEST_CASE("devices per thread: 0, or a hardware device in a group, is refused") {
    CHECK_THROWS_AS(Rig(2, 0), std::invalid_argument);
    ManualClock clock;
    World world(cubeScene(), IndexSpec::parse(kDefaultIndexSpec));
    std::vector<RuntimeDevice> rds;
    for (int i = 0; i < 2; ++i) {
        DeviceConfig c;
        c.name = i == 0 ? "sim0" : "arm";
        c.kind = i == 0 ? DeviceKind::Sim : DeviceKind::Falcon;
        c.rateHz = 1000;
        rds.push_back(
            {std::make_unique<ScriptedDevice>(c.name, test::pressIntoCube()), c, nullptr});
    }
    RuntimeOptions options;
    options.devicesPerThread = 2;
    try {
        Runtime runtime(world, std::move(rds), options);
        FAIL("a falcon in a group was accepted");
    } catch (const std::invalid_argument& e) {
        CHECK_THAT(e.what(), Catch::Contains("'arm'") && Catch::Contains("falcon") &&
                                 Catch::Contains("simulated devices only"));
    }
}

TEST_CASE("group threads drive every device and leave each at zero force on stop", "[realtime]") {
    World world(cubeScene(), IndexSpec::parse(kDefaultIndexSpec));
    std::vector<ScriptedDevice*> devices;
    std::vector<RuntimeDevice> rds;
    for (int i = 0; i < 6; ++i) {
        auto d = std::make_unique<ScriptedDevice>("d" + std::to_string(i),
                                                  test::pressIntoCube(0.004 * i - 0.01));
        devices.push_back(d.get());
        DeviceConfig c;
        c.name = "d" + std::to_string(i);
        c.kind = DeviceKind::Scripted;
        c.rateHz = 1000;
        c.maxForceN = 5.0;
        rds.push_back({std::move(d), c, nullptr});
    }
    RuntimeOptions options;
    options.realtime = false;
    options.devicesPerThread = 4; // a group of four and one of two
    Runtime runtime(world, std::move(rds), options);
    REQUIRE(runtime.start() == 6);
    const auto pressing = [&] {
        for (ScriptedDevice* d : devices) {
            if (d->maxForceSeen() < 0.5) {
                return false;
            }
        }
        return true;
    };
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!pressing() && std::chrono::steady_clock::now() < until) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    CHECK(pressing());
    runtime.stop();
    const RunReport r = runtime.report();
    for (std::size_t i = 0; i < devices.size(); ++i) {
        INFO("device " << i);
        CHECK(r.devices[i].fault.empty());
        CHECK(devices[i]->lastForce() == Vec3(0.0));
    }
}
