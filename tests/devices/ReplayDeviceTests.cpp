#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/devices/TraceReader.h"
#include "hapto/devices/TraceRecorder.h"
#include "hapto/io/InputError.h"
#include "hapto/scenes/Generators.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

using namespace hapto;

namespace {

DeviceConfig replayConfig(const std::filesystem::path& trace, bool loop) {
    DeviceConfig c;
    c.name = "again";
    c.kind = DeviceKind::Replay;
    ReplayConfig r;
    r.trace = trace;
    r.loop = loop;
    c.params = r;
    return c;
}

// Records `ticks` ticks of a simulated hand, writing `force(tick)` each tick.
std::vector<TraceSample> recordSim(const std::filesystem::path& path, int ticks) {
    const Scene scene = makeDefaultScene();
    DeviceConfig c = defaultDeviceConfigs()[0];
    SimDevice d(c, scene);
    REQUIRE(d.open() == DeviceStatus::Ok);
    TraceHeader h;
    h.name = c.name;
    h.kind = "sim";
    h.rateHz = c.rateHz;
    TraceRecorder rec(path, h, 1024);
    std::vector<TraceSample> expected;
    DeviceState s;
    for (int t = 0; t < ticks; ++t) {
        TraceSample sample;
        sample.tick = static_cast<std::uint64_t>(t);
        sample.timeNs = static_cast<std::uint64_t>(t) * 1000000;
        sample.status = d.read(s);
        sample.positionM = s.position;
        sample.forceN = Vec3(0.001 * t, 0, 0);
        sample.buttons = s.buttons;
        d.write(sample.forceN);
        REQUIRE(rec.push(sample));
        expected.push_back(sample);
        if (t % 500 == 0) {
            rec.drain();
        }
    }
    rec.close();
    return expected;
}

} // namespace

TEST_CASE("replay: plays back the recorded positions tick by tick, then stalls") {
    test::TempDir dir;
    const auto recorded = recordSim(dir / "left.trace", 3000);
    const Scene scene;
    auto device = makeDevice(replayConfig(dir / "left.trace", false), scene);
    auto& replay = dynamic_cast<ReplayDevice&>(*device);
    CHECK(replay.kind() == DeviceKind::Replay);
    CHECK(replay.traceHeader().name == "left");
    CHECK(replay.capabilities().nominalRateHz == 1000.0);
    DeviceState s;
    CHECK(replay.read(s) == DeviceStatus::NotOpen);
    REQUIRE(replay.open() == DeviceStatus::Ok);
    for (const TraceSample& r : recorded) {
        REQUIRE(replay.read(s) == DeviceStatus::Ok);
        REQUIRE(s.position == r.positionM);
        REQUIRE(replay.currentSample().forceN == r.forceN);
        REQUIRE(replay.write(r.forceN * 2.0) == DeviceStatus::Ok);
        REQUIRE(replay.lastForceN() == r.forceN * 2.0);
    }
    CHECK(replay.read(s) == DeviceStatus::Stalled);
    CHECK(s.position == recorded.back().positionM);
    CHECK(replay.read(s) == DeviceStatus::Stalled);
    // open() rewinds.
    REQUIRE(replay.open() == DeviceStatus::Ok);
    REQUIRE(replay.read(s) == DeviceStatus::Ok);
    CHECK(s.position == recorded.front().positionM);
}

TEST_CASE("replay: loops when asked, and holds a sample over ticks missing from the trace") {
    test::TempDir dir;
    {
        TraceHeader h;
        h.name = "x";
        h.kind = "sim";
        TraceRecorder rec(dir / "gaps.trace", h);
        for (const std::uint64_t tick : {10u, 11u, 14u, 15u}) {
            TraceSample s;
            s.tick = tick;
            s.positionM = Vec3(static_cast<double>(tick), 0, 0);
            REQUIRE(rec.push(s));
        }
        rec.close();
    }
    ReplayDevice replay(replayConfig(dir / "gaps.trace", true));
    REQUIRE(replay.open() == DeviceStatus::Ok);
    DeviceState s;
    std::vector<double> xs;
    for (int i = 0; i < 12; ++i) {
        REQUIRE(replay.read(s) == DeviceStatus::Ok);
        xs.push_back(s.position.x);
    }
    CHECK(xs == std::vector<double>{10, 11, 11, 11, 14, 15, 10, 11, 11, 11, 14, 15});
    CHECK(replay.loops() == 1);
    CHECK(s.sequence == 12);
}

TEST_CASE("replay: a missing or corrupt trace is refused when the device is made") {
    test::TempDir dir;
    const Scene scene;
    CHECK_THROWS_AS(makeDevice(replayConfig(dir / "none.trace", false), scene), InputError);
    test::writeFile(dir / "bad.trace", "HAPTOTRC but not really");
    CHECK_THROWS_WITH(makeDevice(replayConfig(dir / "bad.trace", false), scene),
                      Catch::Contains("bad.trace: byte"));
    {
        TraceHeader h;
        TraceRecorder rec(dir / "empty.trace", h);
    }
    CHECK_THROWS_WITH(makeDevice(replayConfig(dir / "empty.trace", false), scene),
                      Catch::Contains("no samples"));
}

TEST_CASE("replay: a replay configuration takes its trace's rate, other kinds keep theirs") {
    test::TempDir dir;
    {
        TraceHeader h;
        h.name = "x";
        h.kind = "sim";
        h.rateHz = 2500.0;
        TraceRecorder rec(dir / "fast.trace", h);
        TraceSample s;
        REQUIRE(rec.push(s));
        rec.close();
    }
    std::vector<DeviceConfig> configs{replayConfig(dir / "fast.trace", false),
                                      defaultDeviceConfigs()[0]};
    configs[1].rateHz = 700.0;
    useTraceSettings(configs);
    CHECK(configs[0].rateHz == 2500.0);
    CHECK(configs[1].rateHz == 700.0);

    configs[0] = replayConfig(dir / "none.trace", false);
    CHECK_THROWS_WITH(useTraceSettings(configs), Catch::Contains("none.trace"));
}

TEST_CASE("replay: a trace rate the runtime cannot run is refused, naming the device") {
    test::TempDir dir;
    {
        TraceHeader h;
        h.name = "x";
        h.kind = "sim";
        h.rateHz = 500000.0; // a valid trace, but above the servo's 100 kHz
        TraceRecorder rec(dir / "odd.trace", h);
        TraceSample s;
        REQUIRE(rec.push(s));
        rec.close();
    }
    std::vector<DeviceConfig> configs{replayConfig(dir / "odd.trace", false)};
    CHECK_THROWS_WITH(useTraceSettings(configs),
                      Catch::Contains("'again'") && Catch::Contains("100..100000 Hz"));
}
