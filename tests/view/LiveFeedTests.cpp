// The live feed in step mode: its frames say what the runtime's own metrics say.

#include "hapto/view/LiveFeed.h"

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <string_view>
#include <vector>

using namespace hapto;

namespace {

/// The two default hands over the default scene in step mode, with a feed (never started).
struct Session {
    explicit Session(std::string_view index)
        : world(scene, IndexSpec::parse(index)), runtime(makeRuntime()), feed(runtime, server) {}

    Runtime makeRuntime() {
        world.useClock(clock);
        std::vector<RuntimeDevice> devices;
        for (DeviceConfig c : defaultDeviceConfigs()) {
            devices.push_back({makeDevice(c, scene), c, nullptr});
        }
        RuntimeOptions options;
        options.realtime = false;
        return Runtime(world, std::move(devices), options);
    }

    const Scene scene = makeDefaultScene();
    ManualClock clock;
    World world;
    Runtime runtime;
    ViewServer server;
    LiveFeed feed;
};

} // namespace

TEST_CASE("a live frame carries each device's ticks, misses, load, point, force and contacts, "
          "and the poses of moved objects",
          "[threads]") {
    Session session(kDefaultIndexSpec);
    const Scene& scene = session.scene;
    ManualClock& clock = session.clock;
    World& world = session.world;
    Runtime& runtime = session.runtime;
    LiveFeed& feed = session.feed;
    REQUIRE(feed.devices().size() == 2);
    CHECK(feed.devices()[0].name == runtime.report().devices[0].name);

    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 2);
    runtime.runUntil(t0 + 500'000'000);
    const SceneObject& moved = scene.object(0);
    world.moveObject(moved.id, moved.center + Vec3(0, 0.01, 0), moved.rotation);
    feed.updatePoses(world.current());

    const auto frame = nlohmann::json::parse(feed.frame(500'000'000));
    CHECK(frame["t"] == 0.5);
    const RunReport report = runtime.report();
    for (std::size_t i = 0; i < 2; ++i) {
        const auto& d = frame["devices"][i];
        const DeviceReport& r = report.devices[i];
        INFO(r.name);
        CHECK(d["name"] == r.name);
        CHECK(d["ticks"] == r.ticks);
        CHECK(d["misses"] == r.missedDeadlines);
        CHECK(d["verdict"] == (r.stable ? "stable" : "UNSTABLE"));
        // The window covers the whole run so far: the report's quantiles (bucket bounds).
        CHECK(d["loadP50"].get<double>() >= r.loadFraction.p50 - 1e-12);
        CHECK(d["loadP50"].get<double>() <= r.loadFraction.p50 * 1.04 + 1e-12);
        // The first frame's second reaches back to the start: the report's mean.
        CHECK(d["candidates"].get<double>() == Approx(r.candidatesMean));
        ContactReport c;
        REQUIRE(runtime.lastTick(i, c));
        CHECK(d["point"] ==
              nlohmann::json::array({c.devicePoint.x, c.devicePoint.y, c.devicePoint.z}));
        CHECK(d["proxy"][0] == c.proxy.x);
        CHECK(d["forceN"].get<double>() == Approx(glm::length(c.force)));
        CHECK(d["contacts"].size() == c.contactCount);
    }
    REQUIRE(frame["poses"].size() == 1);
    CHECK(frame["poses"][0]["id"] == moved.id);
    CHECK(frame["poses"][0]["moving"] == true);
    CHECK(frame["poses"][0]["center"][1].get<double>() == Approx(moved.center.y + 0.01));

    // Once it rests and is re-indexed it keeps its new pose, no longer moving.
    runtime.runUntil(t0 + 800'000'000);
    runtime.maintain();
    feed.updatePoses(world.current());
    const auto later = nlohmann::json::parse(feed.frame(800'000'000));
    REQUIRE(later["poses"].size() == 1);
    CHECK(later["poses"][0]["moving"] == false);
    CHECK(later["poses"][0]["center"][1].get<double>() == Approx(moved.center.y + 0.01));
    CHECK(later["devices"][0]["ticks"].get<std::uint64_t>() >
          frame["devices"][0]["ticks"].get<std::uint64_t>());
    runtime.stop();
}

TEST_CASE("a live frame gives the run report's late wake-up note for a device unstable by late "
          "wake-ups alone, and none while it is stable",
          "[threads]") {
    Session session(kDefaultIndexSpec);
    ManualClock& clock = session.clock;
    Runtime& runtime = session.runtime;
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 2);
    runtime.runUntil(t0 + 100'000'000);
    const auto before = nlohmann::json::parse(session.feed.frame(100'000'000));
    for (std::size_t i = 0; i < 2; ++i) {
        REQUIRE(runtime.report().devices[i].stable);
        CHECK_FALSE(before["devices"][i].contains("note"));
    }
    // Device 0 wakes two periods late five times in about 1.1 s (the step mode's one clock
    // jumps, so device 1's next tick is late as well): 5 misses in ~1100 ticks.
    for (int k = 0; k < 5; ++k) {
        const std::uint64_t deadline = runtime.nextDeadlineNs(0);
        REQUIRE(runtime.step(0, deadline + 2'000'000));
        runtime.runUntil(deadline + 200'000'000);
    }
    const auto frame = nlohmann::json::parse(session.feed.frame(clock.nowNs() - t0));
    const RunReport report = runtime.report();
    REQUIRE(report.devices[0].missedDeadlines == 5);
    REQUIRE_FALSE(lateWakeupNote(report.devices[0]).empty());
    for (std::size_t i = 0; i < 2; ++i) {
        INFO(report.devices[i].name);
        const std::string note = lateWakeupNote(report.devices[i]);
        CHECK(frame["devices"][i]["verdict"] == (report.devices[i].stable ? "stable" : "UNSTABLE"));
        CHECK(frame["devices"][i].contains("note") == !note.empty());
        if (!note.empty()) {
            CHECK(frame["devices"][i]["note"] == note);
        }
    }
    runtime.stop();
}

TEST_CASE("a live frame shows each device's cursor leaf: the box holding its point and the "
          "objects the leaf lists, as a fresh locate in the same snapshot gives them",
          "[threads]") {
    Session session("octree:4:0.005");
    ManualClock& clock = session.clock;
    World& world = session.world;
    Runtime& runtime = session.runtime;
    LiveFeed& feed = session.feed;
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 2);
    int checked = 0;
    for (int step = 1; step <= 8; ++step) {
        runtime.runUntil(t0 + step * 150'000'000ull);
        const WorldSnapshot& snap = world.current();
        feed.updateLeaves(snap);
        const auto frame = nlohmann::json::parse(feed.frame(step * 150'000'000ull));
        for (std::size_t i = 0; i < 2; ++i) {
            ContactReport c;
            REQUIRE(runtime.lastTick(i, c));
            const LocateResult fresh = snap.index->locate(c.devicePoint);
            const auto& d = frame["devices"][i];
            if (fresh.outside) {
                CHECK_FALSE(d.contains("leaf"));
                continue;
            }
            REQUIRE(d.contains("leaf"));
            const Aabb box = snap.index->leafBounds(fresh.leaf);
            CHECK(d["leaf"]["min"] == nlohmann::json::array({box.min.x, box.min.y, box.min.z}));
            CHECK(d["leaf"]["max"] == nlohmann::json::array({box.max.x, box.max.y, box.max.z}));
            CHECK(d["leaf"]["items"] == fresh.candidates.size());
            std::vector<ObjectId> ids;
            for (const std::uint32_t item : fresh.candidates) {
                ids.push_back(snap.scene->object(snap.scene->objectSlotOf(item)).id);
            }
            std::sort(ids.begin(), ids.end());
            ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
            CHECK(d["leaf"]["objects"].get<std::vector<ObjectId>>() == ids);
            ++checked;
        }
    }
    CHECK(checked > 0); // the hands were inside the bounds at some of the frames
    runtime.stop();
}
