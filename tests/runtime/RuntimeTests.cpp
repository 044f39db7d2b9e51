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

/// A watchdog fault of a stall of this machine: the whole process stopped past the watchdog
/// (50 ms), which a sanitizer build beside the tests can cause.
bool isStall(const std::string& event) {
    return event.find("watchdog: no tick for 50 ms") != std::string::npos;
}

/// A report's events without this machine's stalls (each stall's fault and the reopening that
/// follows it): what a test did.
std::vector<std::string> withoutStalls(const std::vector<std::string>& events) {
    std::vector<std::string> own;
    for (std::size_t k = 0; k < events.size(); ++k) {
        if (!isStall(events[k])) {
            own.push_back(events[k]);
        } else if (k + 1 < events.size() && events[k + 1].find("reopened") != std::string::npos) {
            ++k;
        }
    }
    return own;
}

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
    // Both press into the cube and feel it. A stall of this machine past the watchdog (50 ms;
    // a sanitizer build beside the tests can cause one) faults a hand and reopens it, and a
    // hand reopened inside the cube feels nothing until it leaves it (the renderer's reset):
    // that is the watchdog's business, not this test's, so a hand's force is waited for until
    // it comes or such a stall is reported, and the stalls are counted apart below.
    const auto stalled = [&](int i) {
        const std::vector<std::string> events = runtime.report().devices[i].events;
        return std::any_of(events.begin(), events.end(), isStall);
    };
    // The events of hand i that this test caused.
    const auto own = [&](int i) { return withoutStalls(runtime.report().devices[i].events); };
    const auto ownHas = [&](int i, const std::string& text) {
        const std::vector<std::string> events = own(i);
        return std::any_of(events.begin(), events.end(),
                           [&](const std::string& e) { return e.find(text) != std::string::npos; });
    };
    const auto feels = [&](int i) {
        const auto pushed = [&] { return glm::length(rig.devices[i]->lastForce()) > 0.0; };
        pump([&] { return pushed() || stalled(i); });
        return pushed() || stalled(i);
    };
    REQUIRE(pump([&] { return rig.devices[0]->reads() >= 200 && rig.devices[1]->reads() >= 200; }));
    CHECK(feels(1));

    // Unplugged for 300 ms while pressing.
    rig.injectors[1]->inject(InjectedFault::Disconnect, 300'000'000);
    REQUIRE(pump([&] { return ownHas(1, "read-failed: disconnected"); }));
    CHECK(rig.injectors[1]->injected() == 1);
    CHECK(rig.injectors[1]->firstForceAfterFault() == 0.0); // zero in the tick it went away
    CHECK(glm::length(rig.devices[1]->lastForce()) == 0.0);
    CHECK(runtime.report().devices[1].fault == "read-failed: disconnected");
    CHECK(runtime.anyRunning());
    const std::uint64_t other = runtime.metrics(0).ticks.load();

    // It comes back, is reopened, lifts off and presses again: the force returns.
    REQUIRE(pump([&] { return ownHas(1, "reopened"); }));
    REQUIRE(pump([&] { return rig.devices[1]->reads() >= 700; }));
    CHECK(feels(1));
    CHECK(runtime.metrics(0).ticks.load() > other); // the other hand never paused
    CHECK(feels(0));
    runtime.stop();

    // What this machine adds: a stall is a watchdog fault on a hand and its reopening, or
    // still open if it came as the run stopped. Those are counted apart; every other event is
    // this test's.
    const auto stalls = [](const DeviceReport& d) {
        return static_cast<std::uint32_t>(std::count_if(d.events.begin(), d.events.end(), isStall));
    };
    const auto endsRecovered = [](const DeviceReport& d) {
        const std::uint32_t open = d.fault.empty() ? 0 : 1;
        return d.reopens + open == d.faults &&
               (d.fault.empty() || d.fault == "watchdog: no tick for 50 ms");
    };
    const RunReport r = runtime.report();
    const DeviceReport& back = r.devices[1];
    INFO("events: " << nlohmann::json(back.events).dump() << " and the other hand's "
                    << nlohmann::json(r.devices[0].events).dump());
    // The disconnect, the reopenings tried while it was away, the one that found it back.
    const std::vector<std::string> mine = withoutStalls(back.events);
    REQUIRE(mine.size() >= 3);
    CHECK(mine.front().find("read-failed: disconnected") != std::string::npos);
    for (std::size_t k = 1; k + 1 < mine.size(); ++k) {
        CHECK(mine[k].find("reopen failed, disconnected") != std::string::npos);
    }
    CHECK(mine.back().find("reopened") != std::string::npos);
    CHECK(back.faults == 1 + stalls(back));
    CHECK(endsRecovered(back));
    CHECK(back.downS >= 0.2); // away for 300 ms; noticed within a few ms
    CHECK_FALSE(back.stable);
    CHECK(withoutStalls(r.devices[0].events).empty()); // the other hand: nothing but stalls
    CHECK(r.devices[0].faults == stalls(r.devices[0]));
    CHECK(endsRecovered(r.devices[0]));
    for (auto* d : rig.devices) {
        CHECK(glm::length(d->lastForce()) == 0.0);
    }
    // The report names it all.
    const auto j = nlohmann::json::parse(reportToJson(r));
    CHECK(j["devices"][1]["faults"] == back.faults);
    CHECK(j["devices"][1]["reopens"] == back.reopens);
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
