// The runtime in step mode: the servo tick and the supervision pass driven from the test's
// thread with a ManualClock. No threads, no sleeps: every count here is exact and every run
// gives the same bytes. Time a device "takes" (a stall, a slow tick, an absence) moves the
// clock (ScriptedDevice::useClock).

#include "ScriptedDevice.h"
#include "SteppedRig.h"
#include "TestSupport.h"

#include "hapto/devices/TraceReader.h"
#include "hapto/devices/TraceRecorder.h"
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

using test::kMs;

using Rig = test::SteppedRig;

/// Every force device `d` was sent after its read number `afterReads` (1-based count).
std::vector<Vec3> forcesAfter(const ScriptedDevice& d, std::uint64_t afterReads) {
    std::vector<Vec3> out;
    for (const ScriptedDevice::Written& w : d.forces()) {
        if (w.reads > afterReads) {
            out.push_back(w.force);
        }
    }
    return out;
}

bool allZero(const std::vector<Vec3>& forces) {
    return std::all_of(forces.begin(), forces.end(), [](const Vec3& f) { return f == Vec3(0.0); });
}

} // namespace

TEST_CASE("step mode: D devices tick exactly on their deadlines, feel the cube, and the report "
          "agrees") {
    Rig rig(4, 2000.0);
    REQUIRE(rig.start() == 4);
    rig.runTo(1500.0); // 3000 periods of 500 us
    for (std::size_t i = 0; i < 4; ++i) {
        INFO("device " << i);
        CHECK(rig.runtime->metrics(i).ticks.load() == 3000);
        CHECK(rig.devices[i]->reads() == 3000);
        CHECK(rig.devices[i]->writes() == 3000);
        // 2 mm into a 500 N/m cube: 1 N up (and the 10 nm skin), never above the 5 N clamp.
        const Vec3 f = rig.force(i);
        CHECK(f.x == Approx(0.0).margin(1e-9));
        CHECK(f.y == Approx(1.0).margin(1e-4));
        CHECK(rig.devices[i]->maxForceSeen() <= 1.0 + 1e-4);
        CHECK(rig.runtime->nextDeadlineNs(i) == rig.t0 + 3001 * 500'000);
    }
    rig.runtime->stop();
    const RunReport r = rig.runtime->report();
    REQUIRE(r.devices.size() == 4);
    for (std::size_t i = 0; i < 4; ++i) {
        const DeviceReport& d = r.devices[i];
        INFO(d.name);
        CHECK(d.fault.empty());
        CHECK(d.ticks == 3000);
        CHECK(d.loadFraction.count == 3000);
        CHECK(d.loadFraction.max == 0.0); // the clock did not move inside a tick
        CHECK(d.lateWakeups == 0);
        CHECK(d.missedDeadlines == 0);
        CHECK(d.zeroedForMisses == 0);
        // The path reaches the top face between reads 41 and 42: ticks 42..2999 touch it.
        CHECK(d.contactTicks == 2958);
        CHECK(d.outsideTicks == 0);
        CHECK(d.candidatesMean >= 1.0);
        CHECK(d.stable);
        CHECK(glm::length(rig.devices[i]->lastForce()) == 0.0);
        CHECK(rig.devices[i]->closed());
    }
    CHECK(r.durationS == Approx(1.5).margin(1e-12));
    CHECK(r.stable);
}

TEST_CASE("step mode: the same calls give the same forces and the same report, bit for bit") {
    const auto session = [] {
        RuntimeOptions opt;
        opt.missLimit = 2;
        Rig rig(
            2, 1000.0,
            [](int i, ScriptedDevice& d) {
                if (i == 1) {
                    d.inject(Inject::SlowTicks, 100, 1'700'000, 140);
                }
            },
            opt);
        rig.start();
        rig.runTo(250.0);
        rig.runtime->stepAll(rig.t0 + 262 * kMs); // a late wake-up
        rig.runTo(400.0);
        rig.runtime->stop();
        std::vector<std::vector<ScriptedDevice::Written>> forces;
        for (auto* d : rig.devices) {
            forces.push_back(d->forces());
        }
        return std::make_pair(reportToJson(rig.runtime->report()), forces);
    };
    const auto a = session();
    const auto b = session();
    CHECK(a.first == b.first);
    REQUIRE(a.second.size() == b.second.size());
    for (std::size_t i = 0; i < a.second.size(); ++i) {
        REQUIRE(a.second[i].size() == b.second[i].size());
        for (std::size_t k = 0; k < a.second[i].size(); ++k) {
            CHECK(a.second[i][k].reads == b.second[i][k].reads);
            CHECK(a.second[i][k].force == b.second[i][k].force);
        }
    }
    const auto j = nlohmann::json::parse(a.first);
    CHECK(j["devices"][1]["missed_deadlines"].get<int>() > 0);
}

TEST_CASE("step mode: the warm-up before each tick changes no force, bit for bit, across a "
          "moved object") {
    const auto session = [](std::uint64_t warmUpNs) {
        RuntimeOptions opt;
        opt.warmUpNs = warmUpNs;
        Rig rig(3, 1000.0, {}, opt);
        rig.start();
        rig.runTo(120.0);
        rig.world.moveObject(7, Vec3(0.001, 0.0, 0.0), Quat(1, 0, 0, 0));
        rig.runTo(300.0);
        rig.runtime->stop();
        std::vector<std::vector<ScriptedDevice::Written>> forces;
        for (auto* d : rig.devices) {
            forces.push_back(d->forces());
        }
        return forces;
    };
    const auto cold = session(0);
    const auto warm = session(50'000);
    REQUIRE(cold.size() == warm.size());
    std::size_t pressing = 0;
    for (std::size_t i = 0; i < cold.size(); ++i) {
        REQUIRE(cold[i].size() == warm[i].size());
        for (std::size_t k = 0; k < cold[i].size(); ++k) {
            CHECK(cold[i][k].reads == warm[i][k].reads);
            CHECK(cold[i][k].force == warm[i][k].force);
            pressing += glm::length(cold[i][k].force) > 0.1 ? 1 : 0;
        }
    }
    CHECK(pressing > 100); // the hands press into the cube: the forces compared are not all zero
}

TEST_CASE("the warm-up is the runtime's choice unless set: on while every servo thread can have "
          "a core of its own, off when they share, as set when set, never in servo groups") {
    const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const auto report = [](int devices, RuntimeOptions opt) {
        Rig rig(devices, 1000.0, {}, opt);
        rig.start();
        rig.runTo(5.0);
        rig.runtime->stop();
        return rig.runtime->report();
    };
    SECTION("as many devices as cores: the default warm-up") {
        const RunReport r = report(cores, {});
        CHECK(r.warmUpNs == kDefaultWarmUpNs);
        CHECK(r.warmUpAutomatic);
        CHECK(r.cores == cores);
        const auto j = nlohmann::json::parse(reportToJson(r));
        CHECK(j["total"]["warm_up_us"].get<double>() == kDefaultWarmUpNs / 1000.0);
        CHECK(j["total"]["warm_up_automatic"] == true);
    }
    SECTION("one device more than cores: off") {
        const RunReport r = report(cores + 1, {});
        CHECK(r.warmUpNs == 0);
        CHECK(r.warmUpAutomatic);
        CHECK(nlohmann::json::parse(reportToJson(r))["total"]["warm_up_us"].get<double>() == 0.0);
    }
    SECTION("set: as set, however many devices") {
        RuntimeOptions opt;
        opt.warmUpNs = 7'000;
        const RunReport r = report(cores + 1, opt);
        CHECK(r.warmUpNs == 7'000);
        CHECK_FALSE(r.warmUpAutomatic);
        opt.warmUpNs = 0;
        CHECK(report(1, opt).warmUpNs == 0);
    }
    SECTION("servo groups never warm up, even when asked") {
        RuntimeOptions opt;
        opt.devicesPerThread = 2;
        CHECK(report(2, opt).warmUpNs == 0);
        opt.warmUpNs = 7'000;
        CHECK(report(2, opt).warmUpNs == 0);
    }
}

TEST_CASE("step mode: each injected fault zeroes that device in the tick it happens, and the "
          "others never notice") {
    struct Case {
        Inject inject;
        FaultKind expected;
        const char* text;
    };
    const Case c =
        GENERATE(Case{Inject::ReadError, FaultKind::ReadFailed, "read-failed: error"},
                 Case{Inject::Disconnect, FaultKind::ReadFailed, "read-failed: disconnected"},
                 Case{Inject::NonFinite, FaultKind::NonFinite, "non-finite: bad-data"},
                 Case{Inject::Stall, FaultKind::Watchdog, "watchdog: no tick for 50 ms"});
    INFO(c.text);
    RuntimeOptions never;
    never.reopenAfterNs = 0; // the fault keeps the device down
    Rig rig(
        3, 1000.0,
        [&](int i, ScriptedDevice& d) {
            if (i == 1) {
                d.inject(c.inject, 200); // its 201st read
            }
        },
        never);
    rig.start();
    rig.runTo(1000.0);
    CHECK(rig.runtime->metrics(1).fault.load() == c.expected);
    CHECK_FALSE(rig.runtime->metrics(1).running.load());
    CHECK(rig.runtime->metrics(1).ticks.load() == 200);
    CHECK(rig.devices[1]->reads() == 201);
    CHECK(glm::length(rig.devices[1]->forces().at(199).force) > 0.5); // pressing before it
    CHECK(allZero(forcesAfter(*rig.devices[1], 200)));                // zero from the fault on
    CHECK_FALSE(forcesAfter(*rig.devices[1], 200).empty());
    CHECK(rig.devices[1]->closed());
    for (std::size_t i : {0u, 2u}) {
        CHECK(rig.runtime->metrics(i).ticks.load() == 1000);
        CHECK(rig.runtime->metrics(i).fault.load() == FaultKind::None);
        CHECK(rig.runtime->metrics(i).missedDeadlines.load() == 0);
        CHECK(rig.runtime->metrics(i).zeroedForMisses.load() == 0);
    }
    CHECK(rig.runtime->anyRunning());
    rig.runtime->stop();
    const RunReport r = rig.runtime->report();
    CHECK(r.devices[1].fault == c.text);
    CHECK(r.devices[1].faults == 1);
    CHECK(r.devices[1].reopens == 0);
    REQUIRE(r.devices[1].events.size() == 1);
    CHECK(r.devices[1].events[0] == "0.201 s: " + std::string(c.text) + "; force zeroed");
    CHECK_FALSE(r.devices[1].stable);
    CHECK(r.devices[0].stable);
    CHECK(r.devices[2].stable);
    CHECK_FALSE(r.stable);
}

TEST_CASE("step mode: a device that is unplugged and comes back is zeroed at once, tried every "
          "reopenAfterNs, reopened and driven again from zero force") {
    RuntimeOptions opt;
    opt.reopenAfterNs = 100 * kMs;
    Rig rig(
        2, 1000.0,
        [&](int i, ScriptedDevice& d) {
            if (i == 1) {
                d.setPath(test::pressLiftPress(0.0));
            }
        },
        opt);
    rig.start();
    rig.devices[1]->goAway(200, rig.t0 + 450 * kMs); // unplugged at its 201st read until 450 ms
    rig.runTo(1500.0);
    const DeviceReport d = rig.report(1);
    INFO(nlohmann::json(d.events).dump());
    // Read 200 at 201 ms fails: zeroed and closed in that pass; tried at 301 ms (still away)
    // and 401 ms (the same error, not logged again), opened at 501 ms.
    const std::vector<std::string> expected = {
        "0.201 s: read-failed: disconnected; force zeroed",
        "0.301 s: reopen failed, disconnected: ; trying every 100 ms",
        "0.501 s: reopened; driving again from zero force"};
    CHECK(d.events == expected);
    CHECK(d.faults == 1);
    CHECK(d.reopens == 1);
    CHECK(d.fault.empty());
    CHECK(d.downS == Approx(0.300).margin(1e-12));
    CHECK(rig.devices[1]->opens() == 2);
    // 200 ticks before, then from 502 ms to 1500 ms: 999 more.
    CHECK(d.ticks == 200 + 999);
    // The first force after the reopen is zero: the device point was inside the cube, which
    // the fresh proxy ignores until it has left it (it lifts at read 400) ...
    const std::vector<Vec3> after = forcesAfter(*rig.devices[1], 201);
    REQUIRE_FALSE(after.empty());
    CHECK(after.front() == Vec3(0.0));
    // ... and it presses again from read 500: the force is back.
    CHECK(rig.force(1).y == Approx(1.0).margin(1e-4));
    // The other device never paused.
    CHECK(rig.report(0).ticks == 1500);
    CHECK(rig.report(0).faults == 0);
    CHECK(rig.report(0).events.empty());
    rig.runtime->stop();
    for (auto* dev : rig.devices) {
        CHECK(glm::length(dev->lastForce()) == 0.0);
        CHECK(dev->closed());
    }
    const auto j = nlohmann::json::parse(reportToJson(rig.runtime->report()));
    CHECK(j["devices"][1]["faults"] == 1);
    CHECK(j["devices"][1]["reopens"] == 1);
    CHECK(j["devices"][1]["down_s"].get<double>() == Approx(0.300).margin(1e-12));
}

TEST_CASE("step mode: a slow open (homing) delays only its own device's restart") {
    RuntimeOptions opt;
    opt.reopenAfterNs = 100 * kMs;
    Rig rig(
        2, 1000.0,
        [](int i, ScriptedDevice& d) {
            if (i == 1) {
                d.inject(Inject::ReadError, 100);
            }
        },
        opt);
    rig.start();
    rig.devices[1]->setOpenTakes(2'000 * kMs); // every later open() takes 2 s
    rig.runTo(300.0);
    // The fault at 101 ms, the reopen at 201 ms which returns at 2.201 s (device time): the
    // other device went on meanwhile, on time.
    CHECK(rig.report(0).ticks == 300);
    CHECK(rig.report(0).missedDeadlines == 0);
    CHECK(rig.report(1).reopens == 1);
    CHECK(rig.runtime->nextDeadlineNs(1) == rig.t0 + 2'202 * kMs);
    rig.runtime->stop();
}

TEST_CASE("step mode: after K missed deadlines in a row the device gets zero force until a tick "
          "is on time again") {
    RuntimeOptions opt;
    opt.missLimit = 2;
    // Reads 100..199 take 3 periods each: every one of those ticks misses its deadline.
    Rig rig(
        1, 1000.0, [](int, ScriptedDevice& d) { d.inject(Inject::SlowTicks, 100, 3 * kMs, 200); },
        opt);
    rig.start();
    rig.runTo(1000.0);
    const DeviceMetrics& m = rig.runtime->metrics(0);
    // Ticks 100 and 101 miss (K = 2 in a row); 102..199 are zeroed, and so is 200, the first
    // on time, which still follows two misses; 201 sends force again.
    CHECK(m.missedDeadlines.load() == 100);
    // Each 3-period read ended on the third deadline after its own: those 3 slots had no tick,
    // and the device was told (a simulated hand's clock runs on through them).
    CHECK(rig.devices[0]->skippedPeriods() == 300);
    CHECK(m.zeroedForMisses.load() == 99);
    CHECK(m.lateWakeups.load() == 0); // every wake-up was on its (skipped-ahead) deadline
    const std::vector<ScriptedDevice::Written> f = rig.devices[0]->forces();
    // forces()[k] is tick k's write (made after read k + 1).
    CHECK(glm::length(f.at(101).force) > 0.5);
    for (std::size_t k = 102; k <= 200; ++k) {
        INFO("tick " << k);
        CHECK(f.at(k).force == Vec3(0.0));
    }
    // Then force grows back from zero at the safety filter's rate (1 N per tick at most).
    CHECK(glm::length(f.at(201).force) > 0.0);
    CHECK(glm::length(f.at(201).force) <= 1.0 + 1e-12);
    CHECK(rig.force(0).y == Approx(1.0).margin(1e-4));
    CHECK(m.fault.load() == FaultKind::None); // 3 ms per read is far from the watchdog
    rig.runtime->stop();
    CHECK_FALSE(rig.runtime->report().devices[0].stable);
}

TEST_CASE("step mode: a wake-up K periods late commands zero for that tick, a later one is "
          "counted late and sends force, one past the watchdog faults") {
    Rig rig(1, 1000.0);
    rig.start();
    rig.runTo(100.0);
    const DeviceMetrics& m = rig.runtime->metrics(0);
    REQUIRE(rig.runtime->nextDeadlineNs(0) == rig.t0 + 101 * kMs);
    const Vec3 before = rig.force(0);
    REQUIRE(before.y == Approx(1.0).margin(1e-4));

    SECTION("2 periods late: late, missed, force sent") {
        REQUIRE(rig.runtime->step(0, rig.t0 + 103 * kMs));
        CHECK(m.lateWakeups.load() == 1);
        CHECK(m.missedDeadlines.load() == 1);
        CHECK(m.zeroedForMisses.load() == 0);
        CHECK(rig.force(0).y == Approx(before.y).epsilon(1e-12));
        CHECK(rig.runtime->nextDeadlineNs(0) == rig.t0 + 104 * kMs);
        // The 101 ms tick ran at 103: the slots of 102 and 103 ms had none, and the device
        // hears of both.
        CHECK(rig.devices[0]->skippedPeriods() == 2);
    }
    SECTION("K = 3 periods late: zero force that tick, then force grows back from zero") {
        REQUIRE(rig.runtime->step(0, rig.t0 + 104 * kMs));
        CHECK(m.lateWakeups.load() == 1);
        CHECK(m.zeroedForMisses.load() == 1);
        CHECK(rig.force(0) == Vec3(0.0));
        CHECK(rig.devices[0]->lastForce() == Vec3(0.0));
        REQUIRE(rig.runtime->nextDeadlineNs(0) == rig.t0 + 105 * kMs);
        REQUIRE(rig.runtime->step(0, rig.t0 + 105 * kMs)); // on time
        CHECK(m.zeroedForMisses.load() == 1);
        CHECK(glm::length(rig.force(0)) == Approx(1.0).margin(1e-4)); // one 1 N step: all of it
    }
    SECTION("more than the stall timeout late: the watchdog's fault, zero, recovered") {
        REQUIRE_FALSE(rig.runtime->step(0, rig.t0 + 160 * kMs));
        CHECK(m.fault.load() == FaultKind::Watchdog);
        CHECK(rig.devices[0]->lastForce() == Vec3(0.0));
        // Reported as the supervisor will name it, before it has taken it.
        CHECK(rig.report(0).fault == "watchdog: no tick for 50 ms");
        CHECK(rig.report(0).faults == 1);
        rig.runtime->supervise(rig.t0 + 160 * kMs);
        CHECK(rig.devices[0]->closed());
        CHECK(rig.report(0).events ==
              std::vector<std::string>{"0.160 s: watchdog: no tick for 50 ms; force zeroed"});
        CHECK(rig.report(0).downS == Approx(0.060).margin(1e-12)); // since its last tick
    }
    CHECK(rig.runtime->step(0, rig.t0) == false); // not yet due: nothing happens
    rig.runtime->stop();
}

TEST_CASE("step mode: a device unstable by late wake-ups alone is told so, with how many of "
          "its misses started late, and one unstable by slow ticks is not") {
    SECTION("short ticks, five wake-ups two periods late") {
        Rig rig(1, 1000.0);
        rig.start();
        rig.runTo(100.0);
        for (int k = 0; k < 5; ++k) {
            const std::uint64_t deadline = rig.runtime->nextDeadlineNs(0);
            REQUIRE(rig.runtime->step(0, deadline + 2 * kMs));
            rig.runtime->runUntil(deadline + 200 * kMs);
        }
        rig.runtime->stop();
        const DeviceReport d = rig.report(0);
        REQUIRE(d.missedDeadlines == 5);
        REQUIRE(d.ticks > 1000);
        REQUIRE(d.ticks < 2000); // so at most 1 tick may have taken its whole period
        CHECK_FALSE(d.stable);
        CHECK(d.loadFraction.p999 < 0.01); // the step mode's clock stands still in a tick
        const std::string note = lateWakeupNote(d);
        INFO(note);
        CHECK(note.find("5 missed deadlines") == 0);
        CHECK(note.find("at least 4 of them ticks shorter than their period that started "
                        "late") != std::string::npos);
        CHECK(note.find("the latest wake-up 2.00 ms after its deadline") != std::string::npos);
        // The --report JSON carries the same note.
        const auto j = nlohmann::json::parse(reportToJson(rig.runtime->report()));
        CHECK(j["devices"][0]["note"] == note);
    }
    SECTION("ticks that take three periods") {
        Rig rig(1, 1000.0,
                [](int, ScriptedDevice& d) { d.inject(Inject::SlowTicks, 100, 3 * kMs, 200); });
        rig.start();
        rig.runTo(1000.0);
        rig.runtime->stop();
        const DeviceReport d = rig.report(0);
        REQUIRE_FALSE(d.stable);
        REQUIRE(d.missedDeadlines == 100);
        CHECK(d.loadFraction.p999 >= 1.0);
        CHECK(lateWakeupNote(d).empty());
        CHECK_FALSE(
            nlohmann::json::parse(reportToJson(rig.runtime->report()))["devices"][0].contains(
                "note"));
    }
    SECTION("a stable device") {
        Rig rig(1, 1000.0);
        rig.start();
        rig.runTo(500.0);
        rig.runtime->stop();
        REQUIRE(rig.report(0).stable);
        CHECK(lateWakeupNote(rig.report(0)).empty());
    }
}

TEST_CASE("step mode: a device whose thread cannot run is caught by the watchdog, gets zero "
          "when it runs again, is reopened, and the other device never notices") {
    RuntimeOptions opt;
    opt.reopenAfterNs = 200 * kMs;
    Rig rig(2, 1000.0, {}, opt);
    rig.start();
    rig.runTo(300.0);
    REQUIRE(rig.force(0).y == Approx(1.0).margin(1e-4));
    // 300 ms in which only device 0 runs (a CPU hog on device 1's core), supervision too.
    for (std::uint64_t t = rig.t0 + 301 * kMs; t <= rig.t0 + 600 * kMs; t += kMs) {
        CHECK(rig.runtime->step(0, t));
        rig.runtime->supervise(t);
    }
    // The watchdog fired 51 ms after device 1's last tick, and asked its servo to stop.
    CHECK(rig.runtime->metrics(1).fault.load() == FaultKind::Watchdog);
    CHECK(rig.runtime->metrics(1).running.load());
    CHECK(rig.devices[1]->reads() == 300);
    rig.runTo(1500.0);
    // When it ran again it left at once with zero, was closed, and reopened 200 ms later.
    const DeviceReport d = rig.report(1);
    INFO(nlohmann::json(d.events).dump());
    CHECK(rig.devices[1]->forceAfterGap() == 0.0);
    CHECK(d.faults == 1);
    CHECK(d.reopens == 1);
    CHECK(d.events == std::vector<std::string>{"0.600 s: watchdog: no tick for 50 ms; force zeroed",
                                               "0.800 s: reopened; driving again from zero force"});
    CHECK(d.downS == Approx(0.500).margin(1e-12)); // from its last tick at 300 ms
    CHECK(rig.report(0).faults == 0);
    CHECK(rig.report(0).ticks == 1500);
    CHECK(rig.devices[0]->forceAfterGap() < 0.0); // device 0 never went 20 ms without a write
    rig.runtime->stop();
}

TEST_CASE("step mode: a device that fails to open is reported and the others run") {
    Rig rig(2, 1000.0, [](int i, ScriptedDevice& d) {
        if (i == 0) {
            d.inject(Inject::OpenFails, 0);
        }
    });
    CHECK(rig.start() == 1);
    rig.runTo(300.0);
    rig.runtime->stop();
    const RunReport r = rig.runtime->report();
    CHECK(r.devices[0].fault == "open-failed: error: injected open failure");
    CHECK(r.devices[0].ticks == 0);
    CHECK(r.devices[1].ticks == 300);
    CHECK_FALSE(r.stable);
}

TEST_CASE("step mode: stop and emergencyStop leave every device at zero force and closed") {
    const bool emergency = GENERATE(false, true);
    Rig rig(2, 1000.0);
    rig.start();
    rig.runTo(200.0);
    REQUIRE(glm::length(rig.devices[0]->lastForce()) > 0.5);
    if (emergency) {
        rig.runtime->emergencyStop();
    } else {
        rig.runtime->stop();
    }
    CHECK_FALSE(rig.runtime->anyRunning());
    for (std::size_t i = 0; i < 2; ++i) {
        CHECK(rig.devices[i]->lastForce() == Vec3(0.0));
        CHECK(rig.devices[i]->closed());
        CHECK_FALSE(rig.runtime->metrics(i).running.load());
    }
    rig.runtime->stop(); // after an emergency stop, the orderly one is still safe
}

TEST_CASE("step-mode calls outside step mode are refused") {
    Rig rig(1, 1000.0);
    CHECK_THROWS_AS(rig.runtime->stepAll(0), std::logic_error);
    CHECK_THROWS_AS(rig.runtime->runUntil(0), std::logic_error);
    CHECK_THROWS_AS(rig.runtime->supervise(0), std::logic_error);
}

TEST_CASE("step mode: a moved object is felt at the next tick and goes back into the index once "
          "it has rested for the rest delay") {
    Rig rig(1, 1000.0);
    rig.world.setRestDelay(std::chrono::milliseconds(50));
    rig.start();
    rig.runTo(100.0);
    REQUIRE(rig.force(0).y == Approx(1.0).margin(1e-4)); // 2 mm into the cube
    const std::uint64_t builds = rig.world.buildsPublished();

    // The cube moves up 1 mm: the proxy rides on it, the device point is now 3 mm deep.
    rig.world.moveObject(7, Vec3(0, 0.001, 0), Quat(1, 0, 0, 0));
    CHECK(rig.world.isMoving(7));
    rig.runTo(101.0);
    CHECK(rig.report(0).snapshotsSeen == 1);
    CHECK(rig.force(0).y == Approx(1.5).margin(1e-4));

    // Not yet rested at 149 ms (moved at 100 ms); at 150 ms maintain() re-indexes it, inline.
    rig.runtime->runUntil(rig.t0 + 149 * kMs);
    rig.runtime->maintain();
    CHECK(rig.world.isMoving(7));
    CHECK(rig.world.buildsPublished() == builds);
    rig.runtime->runUntil(rig.t0 + 150 * kMs);
    rig.runtime->maintain();
    CHECK_FALSE(rig.world.isMoving(7));
    CHECK(rig.world.buildsPublished() == builds + 1);
    CHECK(rig.world.current().moving.empty());
    rig.runTo(151.0);
    CHECK(rig.report(0).snapshotsSeen == 2);
    CHECK(rig.force(0).y == Approx(1.5).margin(1e-4)); // the same wall, now from the index
    rig.runtime->stop();
    rig.runtime->maintain();
    CHECK(rig.world.retiredCount() == 0);
}

TEST_CASE("step mode: an added object is felt at once by brute force, a removed one vanishes when "
          "its rebuild is published") {
    Rig rig(1, 1000.0, [](int, ScriptedDevice& d) { d.setPath(test::pressIntoCube(0.06)); });
    rig.world.setRestDelay(std::chrono::milliseconds(20));
    rig.start();
    // A second 500 N/m cube where the device is about to press, 6 cm right of the first.
    Material m;
    m.stiffness = 500.0;
    rig.world.addObject(makeBox(8, Vec3(0.06, 0, 0), Vec3(0.025), Quat(1, 0, 0, 0), m));
    rig.runTo(10.0);
    CHECK(rig.world.isMoving(8)); // on the brute-force path until it rests and is indexed
    CHECK(rig.world.current().moving.size() == 1);
    rig.runTo(100.0);
    CHECK(rig.force(0).y == Approx(1.0).margin(1e-4));
    rig.runtime->maintain(); // rested since 0 ms: indexed now
    CHECK_FALSE(rig.world.isMoving(8));
    rig.runTo(200.0);
    CHECK(rig.force(0).y == Approx(1.0).margin(1e-4));

    // Removed: still felt until maintain() publishes the index built without it.
    rig.world.removeObject(8);
    rig.runTo(201.0);
    CHECK(rig.force(0).y == Approx(1.0).margin(1e-4));
    rig.runtime->maintain();
    CHECK_FALSE(rig.world.current().scene->slotOf(8).has_value());
    rig.runTo(202.0);
    CHECK(rig.force(0) == Vec3(0.0)); // free space: the proxy is back on the device point
    ContactReport c;
    REQUIRE(rig.runtime->lastTick(0, c));
    CHECK(c.contactCount == 0);
    CHECK(c.proxy == c.devicePoint);
    rig.runtime->stop();
}

TEST_CASE("step mode: a publisher flooding snapshot updates never faults a servo, and every old "
          "snapshot is freed") {
    const auto session = [] {
        Rig rig(3, 2000.0);
        rig.world.setRestDelay(std::chrono::milliseconds(2)); // re-index often, too
        rig.start();
        for (int i = 0; i < 800; ++i) {
            // Every millisecond a move, and now and then an add and a remove.
            rig.world.moveObject(7, Vec3(0, 1e-6 * (i % 100), 0), Quat(1, 0, 0, 0));
            if (i % 50 == 0) {
                rig.world.addObject(makeSphere(1000 + i, Vec3(0.1, 0.1, 0.1), 0.005));
            }
            if (i % 50 == 25) {
                rig.world.removeObject(1000 + i - 25);
            }
            rig.runtime->maintain();
            rig.runTo(i + 1);
        }
        rig.runtime->stop();
        rig.world.settle();
        CHECK(rig.world.retiredCount() == 0);
        const RunReport r = rig.runtime->report();
        for (const DeviceReport& d : r.devices) {
            CHECK(d.fault.empty());
            CHECK(d.ticks == 1600);
            // A new version every millisecond, picked up at the millisecond's first tick (the
            // first one, before any tick, is where each servo starts).
            CHECK(d.snapshotsSeen == 799);
            CHECK(d.safety.nonFinite == 0);
        }
        return reportToJson(r);
    };
    CHECK(session() == session());
}

TEST_CASE("step mode: a recorded trace holds every tick, its wake-up time, the position read and "
          "the force written, and is the same file every run") {
    hapto::test::TempDir dir;
    const auto session = [&](const std::string& name) {
        TraceHeader header;
        header.rateHz = 1000.0;
        header.kind = "scripted";
        header.name = "d0";
        TraceRecorder recorder(dir / name, header);
        RuntimeOptions opt;
        opt.missLimit = 2;
        // Ticks 300..309 take 2.5 periods: missed deadlines, then zeroed forces.
        Rig rig(1, 1000.0,
                [](int, ScriptedDevice& d) { d.inject(Inject::SlowTicks, 300, 2'500'000, 310); },
                opt, cubeScene(), {&recorder});
        rig.start();
        for (int ms = 50; ms <= 500; ms += 50) {
            rig.runTo(ms);
            recorder.drain(); // the control thread's part, between ticks
        }
        const std::vector<ScriptedDevice::Written> forces = rig.devices[0]->forces();
        rig.runtime->stop();
        recorder.close();
        return forces;
    };
    const std::vector<ScriptedDevice::Written> forces = session("a.trace");
    (void)session("b.trace");
    CHECK(hapto::test::readFile(dir / "a.trace") == hapto::test::readFile(dir / "b.trace"));

    const std::vector<TraceSample> samples = TraceReader::load(dir / "a.trace");
    REQUIRE(samples.size() > 400);
    const ScriptedDevice::Path path = test::pressIntoCube(-0.01);
    std::uint64_t expectedTime = 1'000'000; // the first tick is one period after the start
    for (std::size_t k = 0; k < samples.size(); ++k) {
        const TraceSample& s = samples[k];
        INFO("sample " << k);
        REQUIRE(s.tick == k);
        CHECK(s.timeNs == expectedTime);
        CHECK(s.positionM == path(k));
        CHECK(s.forceN == forces.at(k).force);
        CHECK(s.status == DeviceStatus::Ok);
        const bool slow = k >= 300 && k < 310;
        CHECK(s.computeNs == (slow ? 2'500'000u : 0u));
        CHECK(s.ioNs == s.computeNs);
        // A slow tick skips the deadlines it overran: the next wake-up is 3 periods on.
        expectedTime += slow ? 3'000'000 : 1'000'000;
    }
}
