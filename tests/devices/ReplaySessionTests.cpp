// A recorded run, replayed: the same scene, index and recorded configuration give the same
// forces tick for tick (step mode, ManualClock: no thread, no wall clock).

#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/devices/TraceReader.h"
#include "hapto/devices/TraceRecorder.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/Generators.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <memory>

using namespace hapto;

namespace {

constexpr std::uint64_t kRunNs = 2'000'000'000; // 2 s: both hands reach their surfaces

TraceHeader headerFor(const DeviceConfig& c) {
    TraceHeader h;
    h.rateHz = c.rateHz;
    h.kind = std::string(name(c.kind));
    h.name = c.name;
    h.transform = c.transform;
    h.toolTipM = c.toolTipM;
    h.maxForceN = c.maxForceN;
    return h;
}

// Runs `configs` in step mode for `runNs` against `scene` (octree index), recording every
// device to DIR/<name>.trace; returns the traces' samples, per device.
std::vector<std::vector<TraceSample>> runAndRecord(const Scene& scene,
                                                   std::vector<DeviceConfig> configs,
                                                   const std::filesystem::path& dir,
                                                   std::uint64_t runNs = kRunNs) {
    ManualClock clock;
    World world(scene, IndexSpec::parse(kDefaultIndexSpec));
    world.useClock(clock);
    std::vector<std::unique_ptr<TraceRecorder>> recorders;
    std::vector<RuntimeDevice> devices;
    for (const DeviceConfig& c : configs) {
        recorders.push_back(
            std::make_unique<TraceRecorder>(dir / (c.name + ".trace"), headerFor(c)));
        devices.push_back({makeDevice(c, scene), c, recorders.back().get()});
    }
    RuntimeOptions opt;
    opt.realtime = false;
    Runtime runtime(world, std::move(devices), opt);
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == configs.size());
    for (std::uint64_t ms = 100; ms * 1'000'000 <= runNs; ms += 100) {
        runtime.runUntil(t0 + ms * 1'000'000);
        for (auto& r : recorders) {
            r->drain();
        }
    }
    runtime.stop();
    std::vector<std::vector<TraceSample>> out;
    for (auto& r : recorders) {
        r->close();
        out.push_back(TraceReader::load(r->path()));
    }
    return out;
}

// Replay configurations for the traces in `from`, named like the recorded devices.
std::vector<DeviceConfig> replaysOf(const std::vector<DeviceConfig>& recorded,
                                    const std::filesystem::path& from) {
    std::vector<DeviceConfig> out;
    for (const DeviceConfig& c : recorded) {
        DeviceConfig r;
        r.name = c.name;
        r.kind = DeviceKind::Replay;
        ReplayConfig p;
        p.trace = from / (c.name + ".trace");
        r.params = p;
        out.push_back(r);
    }
    return out;
}

std::size_t contactTicks(const std::vector<TraceSample>& samples) {
    std::size_t n = 0;
    for (const TraceSample& s : samples) {
        n += s.contactCount > 0;
    }
    return n;
}

} // namespace

TEST_CASE("replay: a recorded run replayed against the same scene and index writes the same "
          "forces, tick for tick, with the recorded transform and rate",
          "[threads]") {
    test::TempDir dir;
    std::filesystem::create_directories(dir / "run");
    std::filesystem::create_directories(dir / "replay");
    const Scene scene = makeDefaultScene();
    std::vector<DeviceConfig> configs = defaultDeviceConfigs(); // left slides, right touches
    for (DeviceConfig& c : configs) {
        c.rateHz = 2000.0; // not the default: the replay must take the trace's
        c.maxForceN = 2.0;
    }
    configs[1].transform.rotation = glm::angleAxis(0.3, glm::normalize(Vec3(0, 0, 1)));
    // The left hand holds a turning stylus touching with a 1 mm tool tip: the replay must play
    // the orientation and angular velocity back and take the recorded tip.
    configs[0].toolTipM = Vec3(0.0, 0.0, 0.001);
    std::get<SimConfig>(configs[0].params).spinRadPerS = Vec3(0.0, 0.8, 0.0);
    const auto recorded = runAndRecord(scene, configs, dir / "run");

    std::vector<DeviceConfig> replays = replaysOf(configs, dir / "run");
    useTraceSettings(replays);
    for (std::size_t i = 0; i < replays.size(); ++i) {
        CHECK(replays[i].rateHz == 2000.0);
        CHECK(replays[i].maxForceN == 2.0);
        CHECK(replays[i].transform.translation == configs[i].transform.translation);
        CHECK(replays[i].transform.rotation == configs[i].transform.rotation);
        CHECK(replays[i].toolTipM == configs[i].toolTipM);
    }
    const auto replayed = runAndRecord(scene, replays, dir / "replay");

    REQUIRE(recorded.size() == 2);
    REQUIRE(replayed.size() == 2);
    for (std::size_t d = 0; d < recorded.size(); ++d) {
        INFO("device " << configs[d].name);
        REQUIRE(recorded[d].size() == kRunNs / 500'000); // every tick at 2 kHz
        REQUIRE(replayed[d].size() == recorded[d].size());
        // The run touched something: the comparison is about forces, not zeros.
        CHECK(contactTicks(recorded[d]) > 100);
        for (std::size_t k = 0; k < recorded[d].size(); ++k) {
            INFO("tick " << k);
            const TraceSample& a = recorded[d][k];
            const TraceSample& b = replayed[d][k];
            // Bitwise: the replay feeds the tick the same doubles (position, velocity) in the
            // same order through the same code, so nothing can round differently.
            REQUIRE(b.forceN == a.forceN);
            REQUIRE(b.proxyM == a.proxyM);
            REQUIRE(b.contactCount == a.contactCount);
            REQUIRE(b.positionM == a.positionM);
            REQUIRE(b.velocityMps == a.velocityMps);
            REQUIRE(b.orientation == a.orientation);
            REQUIRE(b.angularVelocity == a.angularVelocity);
            REQUIRE(b.hasOrientation == (d == 0));
        }
    }
}

TEST_CASE("replay: a device's own transform overrides the recorded one (and then the forces "
          "differ)",
          "[threads]") {
    test::TempDir dir;
    std::filesystem::create_directories(dir / "run");
    std::filesystem::create_directories(dir / "replay");
    const Scene scene = makeDefaultScene();
    std::vector<DeviceConfig> configs = defaultDeviceConfigs();
    configs.resize(1);
    const auto recorded = runAndRecord(scene, configs, dir / "run");

    std::vector<DeviceConfig> replays = replaysOf(configs, dir / "run");
    replays[0].transform.translation = Vec3(0.0, 0.05, 0.0); // away from the surface touched
    std::get<ReplayConfig>(replays[0].params).ownTransform = true;
    replays[0].rateHz = 500.0;
    std::get<ReplayConfig>(replays[0].params).ownRate = true;
    useTraceSettings(replays);
    CHECK(replays[0].transform.translation == Vec3(0.0, 0.05, 0.0));
    CHECK(replays[0].rateHz == 500.0);
    replays[0].rateHz = 1000.0; // the same tick count below
    const auto replayed = runAndRecord(scene, replays, dir / "replay");
    REQUIRE(replayed[0].size() == recorded[0].size());
    CHECK(contactTicks(recorded[0]) > 100);
    std::size_t differing = 0;
    for (std::size_t k = 0; k < recorded[0].size(); ++k) {
        differing += replayed[0][k].forceN != recorded[0][k].forceN;
    }
    CHECK(differing > 100);
}

TEST_CASE("replay: a version 1 trace replays with the device's own settings") {
    // tools/fuzz/corpus/trace_file/three-ticks.trace is a version 1 file, kept as written by
    // the version 1 recorder.
    const std::filesystem::path v1 =
        std::filesystem::path(HAPTO_SOURCE_DIR) / "tools/fuzz/corpus/trace_file/three-ticks.trace";
    TraceHeader header;
    const std::vector<TraceSample> samples = TraceReader::load(v1, &header);
    REQUIRE(header.version == 1);
    CHECK_FALSE(header.hasConfiguration());
    REQUIRE(samples.size() == 3);
    DeviceConfig c;
    c.name = "v1";
    c.kind = DeviceKind::Replay;
    c.transform.translation = Vec3(0.5, 0.0, 0.0);
    ReplayConfig p;
    p.trace = v1;
    c.params = p;
    std::vector<DeviceConfig> configs{c};
    useTraceSettings(configs);
    CHECK(configs[0].transform.translation == Vec3(0.5, 0.0, 0.0)); // nothing recorded to use
    CHECK(configs[0].rateHz == header.rateHz);
    const Scene scene;
    auto device = makeDevice(configs[0], scene);
    REQUIRE(device->open() == DeviceStatus::Ok);
    DeviceState s;
    REQUIRE(device->read(s) == DeviceStatus::Ok);
    CHECK(s.position == samples[0].positionM);
    CHECK_FALSE(s.hasVelocity);
    CHECK_FALSE(s.hasOrientation);
}

namespace {

// A version 2 trace of a stylus lowered onto the top of a 5 cm cube at the origin: the gimbal
// comes down from y = 6 cm to 3.5 cm over 250 ticks and stays there, 1 cm above the face;
// turned a quarter turn about +x (`turned`), the stylus's +z points down (device -y).
void writeLoweredStylus(const std::filesystem::path& path, const Vec3& toolTip, bool turned) {
    TraceHeader h;
    h.kind = "sim";
    h.name = "tool";
    h.toolTipM = toolTip;
    TraceRecorder rec(path, h);
    const Quat quarter = glm::angleAxis(std::acos(0.0), Vec3(1, 0, 0));
    for (std::uint64_t t = 0; t < 600; ++t) {
        TraceSample s;
        s.tick = t;
        s.timeNs = t * 1'000'000;
        s.positionM =
            Vec3(0.0, 0.06 - 0.0001 * static_cast<double>(std::min<std::uint64_t>(t, 250)), 0.0);
        s.orientation = turned ? quarter : Quat{1, 0, 0, 0};
        s.hasOrientation = turned;
        REQUIRE(rec.push(s));
    }
    rec.close();
}

Scene cubeScene() {
    Material m;
    m.stiffness = 500.0;
    return Scene(Aabb{Vec3(-0.125), Vec3(0.125)},
                 {makeBox(7, Vec3(0), Vec3(0.025), Quat(1, 0, 0, 0), m)});
}

} // namespace

TEST_CASE("tool tip: the contact point is position + R * tip, and its force pushes the tip out "
          "(step mode, a replayed stylus)") {
    test::TempDir dir;
    std::filesystem::create_directories(dir / "run");
    const Vec3 tip(0.0, 0.0, 0.02); // 2 cm along the stylus's +z
    // Turned: the tip points down and reaches 1 cm into the cube. Not turned: it points along
    // +z, beside the cube's top. Without a tip: the gimbal centre, 1 cm above the face.
    writeLoweredStylus(dir / "turned.trace", tip, true);
    writeLoweredStylus(dir / "level.trace", tip, false);
    writeLoweredStylus(dir / "notip.trace", Vec3(0.0), true);
    const Scene scene = cubeScene();
    std::vector<DeviceConfig> replays;
    for (const char* name : {"turned", "level", "notip"}) {
        DeviceConfig c;
        c.name = name;
        c.kind = DeviceKind::Replay;
        ReplayConfig p;
        p.trace = dir / (std::string(name) + ".trace");
        c.params = p;
        replays.push_back(c);
    }
    useTraceSettings(replays);
    CHECK(replays[0].toolTipM == tip); // the recorded tip
    CHECK(replays[2].toolTipM == Vec3(0.0));
    for (DeviceConfig& c : replays) {
        c.rateHz = 1000.0;
    }
    const auto runs = runAndRecord(scene, replays, dir / "run", 600'000'000); // the whole traces
    for (const auto& run : runs) {
        REQUIRE(run.size() == 600);
    }
    const TraceSample& turned = runs[0][550];
    const TraceSample& level = runs[1][550];
    const TraceSample& notip = runs[2][550];
    // The turned tip is 1 cm deep: the proxy stays on the face (its point is the tip's), and
    // the force pushes up, 500 N/m x 1 cm = 5 N before the safety clamp.
    CHECK(turned.contactCount == 1);
    CHECK(std::abs(turned.proxyM.y - 0.025) < 1e-6); // on the face, within the renderer's skin
    CHECK(std::abs(turned.proxyM.z) < 1e-9);
    CHECK(turned.forceN.y > 1.0);
    CHECK(std::abs(turned.forceN.x) < 1e-9);
    CHECK(std::abs(turned.forceN.z) < 1e-9);
    // The level tip is 2 cm along +z, still 1 cm above the face: no contact.
    CHECK(level.contactCount == 0);
    CHECK(level.forceN == Vec3(0.0));
    CHECK(notip.contactCount == 0);
    CHECK(notip.forceN == Vec3(0.0));
}
