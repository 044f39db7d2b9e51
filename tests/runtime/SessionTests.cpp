// The session driver (Session.h), in step mode but for one [realtime] case on the wall clock: where
// it stops (duration, request, the control step's word, the end of every device), what it leaves
// (zero force, closed or abandoned recordings) and the report it returns. In step mode every count
// is exact: the clock is the test's.

#include "ScriptedDevice.h"
#include "SteppedRig.h"
#include "TestSupport.h"

#include "hapto/devices/TraceReader.h"
#include "hapto/devices/TraceRecorder.h"
#include "hapto/runtime/Session.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <vector>

using namespace hapto;
using test::Inject;
using test::ScriptedDevice;
using Rig = test::SteppedRig;

namespace {

/// Step mode on the rig's clock, a control step of 1 ms.
SessionOptions steppedOptions(Rig& rig, double durationS = 0) {
    SessionOptions options;
    options.steppedClock = &rig.clock;
    options.controlPeriodNs = 1'000'000;
    options.durationS = durationS;
    return options;
}

/// Every device of the rig was last sent zero force, and the runtime says so too.
bool allAtZeroForce(const Rig& rig) {
    for (std::size_t i = 0; i < rig.devices.size(); ++i) {
        ContactReport last;
        if (rig.devices[i]->lastForce() != Vec3(0.0) || !rig.runtime->lastTick(i, last) ||
            last.force != Vec3(0.0)) {
            return false;
        }
    }
    return true;
}

} // namespace

TEST_CASE("session, step mode: it ends at its duration on the session's clock, every device "
          "ticked each period up to it, then at zero force, with a complete report") {
    Rig rig(2, 1000.0);
    Session session(*rig.runtime, steppedOptions(rig, 0.1));
    REQUIRE(session.start() == 2);
    std::vector<double> steps;
    double pressedN = 0; // the largest force felt during the session
    const SessionEnd end = session.run([&](double tS) {
        steps.push_back(tS);
        pressedN = std::max(pressedN, rig.devices[0]->lastForce().y);
        return true;
    });
    CHECK(end == SessionEnd::Duration);
    CHECK(session.timeS() == 0.1);
    // A control step at every millisecond before the duration, none at it.
    REQUIRE(steps.size() == 99);
    CHECK(steps.front() == 0.001);
    CHECK(steps.back() == Approx(0.099).margin(1e-12));
    CHECK(pressedN > 0.5); // the devices pressed into the cube: there was force to take away
    const RunReport& r = session.stop();
    CHECK(allAtZeroForce(rig));
    REQUIRE(r.devices.size() == 2);
    for (const DeviceReport& d : r.devices) {
        INFO(d.name);
        CHECK(d.ticks == 100);
        CHECK(d.fault.empty());
        CHECK(d.missedDeadlines == 0);
        CHECK(d.contactTicks > 0);
    }
    CHECK(r.durationS == Approx(0.1));
    CHECK(r.devices[0].name == "d0");
    CHECK(r.devices[1].name == "d1");
    CHECK(&session.stop() == &r); // stop() once; later calls return the same report
}

TEST_CASE("session, step mode: a stop request ends it at the next control step, with zero "
          "force") {
    Rig rig(2, 1000.0);
    bool requested = false;
    SessionOptions options = steppedOptions(rig, 10.0);
    options.stopRequested = [&] { return requested; };
    Session session(*rig.runtime, options);
    REQUIRE(session.start() == 2);
    int steps = 0;
    const SessionEnd end = session.run([&](double tS) {
        ++steps;
        requested = tS >= 0.08; // asked during the step at 80 ms
        return true;
    });
    CHECK(end == SessionEnd::Requested);
    CHECK(steps == 80);
    CHECK(session.timeS() == 0.08); // no period ran after the request
    const RunReport& r = session.stop();
    CHECK(allAtZeroForce(rig));
    CHECK(r.devices.at(0).ticks == 80);
    CHECK(r.devices.at(1).ticks == 80);
}

TEST_CASE("session, step mode: the control step's false ends it after that step, and run() "
          "goes on when called again") {
    Rig rig(1, 1000.0);
    Session session(*rig.runtime, steppedOptions(rig));
    REQUIRE(session.start() == 1);
    CHECK(session.run([](double tS) { return tS < 0.03; }) == SessionEnd::Finished);
    CHECK(session.timeS() == 0.03);
    CHECK(session.run([](double tS) { return tS < 0.05; }) == SessionEnd::Finished);
    CHECK(session.timeS() == 0.05);
    CHECK(session.stop().devices.at(0).ticks == 50);
    CHECK(allAtZeroForce(rig));
}

TEST_CASE("session, step mode: when no device is driven any more (a fault, no reopening), it "
          "ends") {
    RuntimeOptions noReopen;
    noReopen.reopenAfterNs = 0;
    Rig rig(
        1, 1000.0, [](int, ScriptedDevice& d) { d.inject(Inject::ReadError, 20); }, noReopen);
    Session session(*rig.runtime, steppedOptions(rig, 1.0));
    REQUIRE(session.start() == 1);
    CHECK(session.run() == SessionEnd::NoneRunning);
    CHECK(session.timeS() < 0.1);
    const RunReport& r = session.stop();
    CHECK_FALSE(r.devices.at(0).fault.empty());
    CHECK(allAtZeroForce(rig));
}

TEST_CASE("session, step mode: recorders are drained while it runs and closed once the devices "
          "are stopped, and a session whose devices all fail to open leaves an older trace alone") {
    test::TempDir dir;
    TraceHeader header;
    header.rateHz = 1000.0;
    header.kind = "scripted";
    header.name = "d0";
    {
        TraceRecorder recorder(dir / "d0.trace", header);
        Rig rig(1, 1000.0, {}, {}, test::cubeScene(), {&recorder});
        SessionOptions options = steppedOptions(rig, 0.2);
        options.recorders = {&recorder};
        Session session(*rig.runtime, options);
        REQUIRE(session.start() == 1);
        std::size_t drainedBy100 = 0;
        session.run([&](double tS) {
            if (tS == 0.1) {
                drainedBy100 = recorder.written();
            }
            return true;
        });
        CHECK(drainedBy100 == 99); // drained after each step: ticks 1..99 by the step at 100
        session.stop();
        CHECK(TraceReader::load(dir / "d0.trace").size() == 200);
    }
    const std::string before = test::readFile(dir / "d0.trace");
    {
        TraceRecorder recorder(dir / "d0.trace", header);
        Rig rig(1, 1000.0, [](int, ScriptedDevice& d) { d.inject(Inject::OpenFails, 0); }, {},
                test::cubeScene(), {&recorder});
        SessionOptions options = steppedOptions(rig, 0.2);
        options.recorders = {&recorder};
        Session session(*rig.runtime, options);
        CHECK(session.start() == 0);
        session.stop();
    }
    CHECK(test::readFile(dir / "d0.trace") == before);
    // Nothing but the trace in the folder: no temporary left behind.
    CHECK(std::distance(std::filesystem::directory_iterator(dir.path()),
                        std::filesystem::directory_iterator()) == 1);
}

TEST_CASE("session, step mode: a session let go without stop() stops its devices at zero force") {
    Rig rig(2, 1000.0);
    {
        Session session(*rig.runtime, steppedOptions(rig, 0.1));
        REQUIRE(session.start() == 2);
        session.run();
    }
    CHECK(allAtZeroForce(rig));
    CHECK(rig.devices[0]->closed());
    CHECK(rig.devices[1]->closed());
}

TEST_CASE("session names why it ended") {
    CHECK(sessionEndName(SessionEnd::Duration) == "duration");
    CHECK(sessionEndName(SessionEnd::Requested) == "requested");
    CHECK(sessionEndName(SessionEnd::Finished) == "finished");
    CHECK(sessionEndName(SessionEnd::NoneRunning) == "none running");
}

TEST_CASE("session, wall clock: it ends at its duration with every device at zero force, and a "
          "stop request ends an untimed one",
          "[realtime]") {
    for (const double durationS : {0.2, 0.0}) {
        INFO("duration " << durationS);
        World world(test::cubeScene(), IndexSpec::parse("octree:2:0.005"));
        std::vector<RuntimeDevice> devices;
        std::vector<ScriptedDevice*> scripted;
        for (int i = 0; i < 2; ++i) {
            auto d = std::make_unique<ScriptedDevice>("d" + std::to_string(i),
                                                      test::pressIntoCube(0.004 * i - 0.01));
            scripted.push_back(d.get());
            devices.push_back({std::move(d), test::scriptedConfig(i, 1000.0), nullptr});
        }
        RuntimeOptions threads;
        threads.realtime = false;
        Runtime runtime(world, std::move(devices), threads);
        SessionOptions options;
        options.durationS = durationS;
        bool requested = false;
        options.stopRequested = [&] { return requested; };
        Session session(runtime, options);
        REQUIRE(session.start() == 2);
        const SessionEnd end = session.run([&](double tS) {
            requested = durationS == 0 && tS >= 0.2;
            return true;
        });
        CHECK(end == (durationS > 0 ? SessionEnd::Duration : SessionEnd::Requested));
        CHECK(session.timeS() >= 0.2);
        const RunReport& r = session.stop();
        for (std::size_t i = 0; i < 2; ++i) {
            CHECK(scripted[i]->lastForce() == Vec3(0.0));
            CHECK(r.devices.at(i).ticks > 0);
        }
    }
}
