// The runtime on its threads ([realtime]: the wall clock, real servo threads and a real
// supervisor). These wait, with a generous bound, for what must eventually happen and assert
// no counts of ticks or sleeps; the exact counts, the fault rules tick by tick and the world
// updates are tested on the step mode (SteppedRuntimeTests.cpp), which runs the same tick and
// the same supervision pass.

#include "CubeScene.h"
#include "ScriptedDevice.h"

#include "hapto/devices/FaultInjectingDevice.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <functional>
#include <thread>

using namespace hapto;
using hapto::test::cubeScene;
using test::Inject;
using test::ScriptedDevice;

namespace {

struct ThreadRig {
    World world;
    std::vector<ScriptedDevice*> devices;
    std::vector<FaultInjectingDevice*> injectors; // wraps each device
    std::unique_ptr<Runtime> runtime;

    ThreadRig(Scene scene, int count, double rateHz,
              std::function<void(int, ScriptedDevice&)> setup = {}, RuntimeOptions options = {})
        : world(std::move(scene), IndexSpec::parse(kDefaultIndexSpec)) {
        std::vector<RuntimeDevice> rds;
        for (int i = 0; i < count; ++i) {
            auto d = std::make_unique<ScriptedDevice>("d" + std::to_string(i),
                                                      test::pressIntoCube(0.004 * i - 0.01));
            if (setup) {
                setup(i, *d);
            }
            devices.push_back(d.get());
            auto wrapped = std::make_unique<FaultInjectingDevice>(std::move(d));
            injectors.push_back(wrapped.get());
            rds.push_back({std::move(wrapped), test::scriptedConfig(i, rateHz), nullptr});
        }
        options.realtime = false; // tests share a noisy machine; SCHED_FIFO is for sessions
        runtime = std::make_unique<Runtime>(world, std::move(rds), options);
    }

    /// Calls maintain() until `done`, at most 30 s; true if it came.
    template <class F> bool pump(F done) {
        const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
        while (!done() && std::chrono::steady_clock::now() < until) {
            runtime->maintain();
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
        }
        return done();
    }
};

} // namespace

TEST_CASE("servo threads: D devices tick, feel the cube, and the report agrees with what they "
          "saw",
          "[realtime]") {
    // A sanitizer build can stall a thread for tens of ms: a generous watchdog here, and no
    // reopen, so a real fault shows.
    RuntimeOptions opt;
    opt.stallTimeoutNs = 250'000'000;
    opt.reopenAfterNs = 0;
    ThreadRig rig(cubeScene(), 4, 2000.0, {}, opt);
    rig.runtime->start();
    // Until each presses 2 mm into the cube and feels it (about 1 N), or faults.
    REQUIRE(rig.pump([&] {
        for (std::size_t i = 0; i < 4; ++i) {
            const DeviceMetrics& m = rig.runtime->metrics(i);
            if (m.forceN[1].load() < 0.99 && m.fault.load() == FaultKind::None) {
                return false;
            }
        }
        return true;
    }));
    rig.runtime->stop();
    const RunReport r = rig.runtime->report();
    REQUIRE(r.devices.size() == 4);
    for (std::size_t i = 0; i < 4; ++i) {
        const DeviceReport& d = r.devices[i];
        INFO(d.name << " fault '" << d.fault << "' missed " << d.missedDeadlines << " zeroed "
                    << d.zeroedForMisses);
        CHECK(d.fault.empty());
        CHECK(d.ticks > 0);
        CHECK(d.ticks == rig.runtime->metrics(i).ticks.load());
        CHECK(d.ticks <= rig.devices[i]->reads());
        CHECK(rig.devices[i]->writes() >= d.ticks); // every tick wrote, plus the final zero
        CHECK(d.loadFraction.count == d.ticks);
        CHECK(d.loadFraction.p50 > 0.0);
        CHECK(d.loadFraction.p50 <= d.loadFraction.p99);
        CHECK(d.loadFraction.p99 <= d.loadFraction.p999);
        CHECK(d.loadFraction.p999 <= d.loadFraction.max);
        CHECK(d.contactTicks > 0);
        CHECK(d.contactTicks <= d.ticks);
        CHECK(d.candidatesMean >= 1.0);
        CHECK(d.rateHz == 2000.0);
        // 2 mm into a 500 N/m cube: about 1 N, never above the 5 N clamp.
        CHECK(rig.devices[i]->maxForceSeen() <= 5.0 + 1e-9);
        CHECK(rig.devices[i]->maxForceSeen() == Approx(1.0).margin(0.2));
        CHECK(glm::length(rig.devices[i]->lastForce()) == 0.0);
        CHECK(rig.devices[i]->closed());
    }
    CHECK(r.loadSum == Approx(r.devices[0].loadFraction.mean + r.devices[1].loadFraction.mean +
                              r.devices[2].loadFraction.mean + r.devices[3].loadFraction.mean));
    CHECK(r.loadPerCore == Approx(r.loadSum / r.cores));

    const auto j = nlohmann::json::parse(reportToJson(r));
    REQUIRE(j["devices"].size() == 4);
    for (const char* key :
         {"name", "kind", "rate_hz", "ticks", "load", "late_wakeups", "missed_deadlines", "io",
          "locate_steps_mean", "candidates_mean", "faults", "stable"}) {
        CHECK(j["devices"][0].contains(key));
    }
    for (const char* key : {"mean", "p50", "p99", "p999", "max"}) {
        CHECK(j["devices"][0]["load"].contains(key));
    }
    for (const char* key : {"load_sum", "load_per_core", "stable"}) {
        CHECK(j["total"].contains(key));
    }
}

TEST_CASE("servo threads: each injected fault zeroes that device and leaves the others running",
          "[realtime]") {
    struct Case {
        Inject inject;
        FaultKind expected;
    };
    const Case c = GENERATE(Case{Inject::ReadError, FaultKind::ReadFailed},
                            Case{Inject::Disconnect, FaultKind::ReadFailed},
                            Case{Inject::NonFinite, FaultKind::NonFinite},
                            Case{Inject::Stall, FaultKind::Watchdog});
    INFO("inject " << static_cast<int>(c.inject));
    RuntimeOptions never;
    never.reopenAfterNs = 0; // the fault keeps the device down
    // A watchdog well under the injected 300 ms stall but above the stalls a loaded machine
    // (or a sanitizer) gives a thread now and then: those would fault a device first.
    never.stallTimeoutNs = 150'000'000;
    ThreadRig rig(
        cubeScene(), 3, 1000.0,
        [&](int i, ScriptedDevice& d) {
            if (i == 1) {
                d.inject(c.inject, 200);
            }
        },
        never);
    rig.runtime->start();
    // Wait for the fault, then for the healthy devices to go on past it.
    REQUIRE(rig.pump([&] { return rig.runtime->metrics(1).fault.load() != FaultKind::None; }));
    const std::uint64_t ticksAtFault = rig.runtime->metrics(0).ticks.load();
    REQUIRE(rig.pump([&] { return rig.runtime->metrics(0).ticks.load() > ticksAtFault; }));
    // The faulted thread ends by itself (the stalled one once its read returns).
    REQUIRE(rig.pump([&] { return !rig.runtime->metrics(1).running.load(); }));
    CHECK(rig.runtime->metrics(1).fault.load() == c.expected);
    CHECK_FALSE(rig.runtime->metrics(1).running.load());
    CHECK(glm::length(rig.devices[1]->lastForce()) == 0.0); // zero before the thread ended
    CHECK(rig.runtime->metrics(0).running.load());
    CHECK(rig.runtime->metrics(2).running.load());
    CHECK(rig.runtime->metrics(0).fault.load() == FaultKind::None);
    rig.runtime->stop();
    const RunReport r = rig.runtime->report();
    CHECK_FALSE(r.devices[1].fault.empty());
    CHECK(r.devices[1].faults == 1);
    CHECK(r.devices[1].reopens == 0);
    CHECK_FALSE(r.devices[1].stable);
    CHECK(r.devices[0].fault.empty());
    CHECK(r.devices[0].faults == 0);
    CHECK(r.devices[0].ticks > ticksAtFault);
    for (auto* d : rig.devices) {
        CHECK(glm::length(d->lastForce()) == 0.0);
    }
}

TEST_CASE("servo threads: a device that disconnects and comes back is zeroed at once, reopened "
          "and driven again while the others go on",
          "[realtime]") {
    RuntimeOptions opt;
    opt.reopenAfterNs = 100'000'000; // try every 100 ms
    ThreadRig rig(
        cubeScene(), 2, 1000.0,
        [](int i, ScriptedDevice& d) {
            if (i == 1) {
                d.setPath(test::pressLiftPress(0.0));
            }
        },
        opt);
    Runtime& runtime = *rig.runtime;
    runtime.start();
    const auto pump = [&](const std::function<bool()>& done) { return rig.pump(done); };
    // Both press into the cube and feel it.
    REQUIRE(pump([&] { return rig.devices[0]->reads() >= 200 && rig.devices[1]->reads() >= 200; }));
    CHECK(glm::length(rig.devices[1]->lastForce()) > 0.0);

    // Unplugged for 300 ms while pressing.
    rig.injectors[1]->inject(InjectedFault::Disconnect, 300'000'000);
    REQUIRE(pump([&] { return runtime.report().devices[1].faults == 1; }));
    CHECK(rig.injectors[1]->injected() == 1);
    CHECK(rig.injectors[1]->firstForceAfterFault() == 0.0); // zero in the tick it went away
    CHECK(glm::length(rig.devices[1]->lastForce()) == 0.0);
    CHECK(runtime.report().devices[1].fault == "read-failed: disconnected");
    CHECK(runtime.anyRunning());
    const std::uint64_t other = runtime.metrics(0).ticks.load();

    // It comes back, is reopened, lifts off and presses again: the force returns.
    REQUIRE(pump([&] { return runtime.report().devices[1].reopens == 1; }));
    REQUIRE(pump([&] { return rig.devices[1]->reads() >= 700; }));
    CHECK(glm::length(rig.devices[1]->lastForce()) > 0.0);
    CHECK(runtime.metrics(0).ticks.load() > other); // the other hand never paused
    CHECK(glm::length(rig.devices[0]->lastForce()) > 0.0);
    runtime.stop();

    const RunReport r = runtime.report();
    const DeviceReport& back = r.devices[1];
    INFO("events: " << nlohmann::json(back.events).dump());
    CHECK(back.fault.empty());
    CHECK(back.faults == 1);
    CHECK(back.reopens == 1);
    CHECK(back.downS >= 0.2); // away for 300 ms; noticed within a few ms
    CHECK(test::hasEvent(back, "read-failed: disconnected"));
    CHECK(test::hasEvent(back, "reopen failed, disconnected")); // tried while it was away
    CHECK(test::hasEvent(back, "reopened"));
    CHECK_FALSE(back.stable);
    CHECK(r.devices[0].faults == 0);
    CHECK(r.devices[0].fault.empty());
    CHECK(r.devices[0].events.empty());
    for (auto* d : rig.devices) {
        CHECK(glm::length(d->lastForce()) == 0.0);
    }
    // The report names it all.
    const auto j = nlohmann::json::parse(reportToJson(r));
    CHECK(j["devices"][1]["faults"] == 1);
    CHECK(j["devices"][1]["reopens"] == 1);
    CHECK(j["devices"][1]["events"].size() == back.events.size());
}

TEST_CASE("servo threads pick up a new snapshot at their next tick", "[realtime]") {
    ThreadRig rig(cubeScene(), 2, 1000.0);
    rig.runtime->start();
    REQUIRE(rig.pump([&] {
        return rig.runtime->metrics(0).ticks.load() > 0 && rig.runtime->metrics(1).ticks.load() > 0;
    }));
    rig.world.moveObject(7, Vec3(0, 0.001, 0), Quat(1, 0, 0, 0));
    CHECK(rig.pump([&] {
        return rig.runtime->metrics(0).snapshotsSeen.load() >= 1 &&
               rig.runtime->metrics(1).snapshotsSeen.load() >= 1;
    }));
    rig.runtime->stop();
}

TEST_CASE("servo threads: a publisher flooding snapshot updates never stops or faults a servo "
          "thread",
          "[realtime]") {
    ThreadRig rig(cubeScene(), 3, 2000.0);
    rig.world.setRestDelay(std::chrono::milliseconds(2)); // re-index often, too
    rig.runtime->start();
    for (int published = 0; published < 2000; ++published) {
        // As fast as the control thread can: a move, and now and then an add and a remove.
        rig.world.moveObject(7, Vec3(0, 1e-6 * (published % 100), 0), Quat(1, 0, 0, 0));
        if (published % 50 == 0) {
            rig.world.addObject(makeSphere(1000 + published, Vec3(0.1, 0.1, 0.1), 0.005));
        }
        if (published % 50 == 25) {
            rig.world.removeObject(1000 + published - 25);
        }
        rig.runtime->maintain();
    }
    // Every servo picks up the newest snapshot.
    CHECK(rig.pump([&] {
        for (std::size_t i = 0; i < 3; ++i) {
            if (rig.runtime->metrics(i).snapshotsSeen.load() == 0) {
                return false;
            }
        }
        return true;
    }));
    rig.runtime->stop();
    rig.world.settle();
    const RunReport r = rig.runtime->report();
    for (const DeviceReport& d : r.devices) {
        CHECK(d.fault.empty());
    }
    CHECK(rig.world.retiredCount() == 0); // every old snapshot was freed
    for (auto* d : rig.devices) {
        CHECK(glm::length(d->lastForce()) == 0.0);
    }
}
