// Proves the servo path never allocates: this binary replaces the global operator new and
// counts every allocation made inside a servo loop (a servo thread's, or a step-mode tick).

#include "CountingNew.h"
#include "MeshShapes.h"

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/scenes/Generators.h"
#include "hapto/view/LiveFeed.h"
#include "hapto/view/ViewServer.h"

#include <catch2/catch.hpp>
#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <thread>

namespace {
// Every allocation is counted (tests/support/CountingNew.h); those made inside a servo loop
// (rt::inServoLoop: a servo thread's, or a step-mode tick) are flagged.
auto& gServoAllocations = hapto::test::gFlaggedAllocations;
auto& gAllAllocations = hapto::test::gAllocations;
[[maybe_unused]] const bool gFlagsServo = [] {
    hapto::test::gFlagAllocation = []() noexcept { return hapto::rt::inServoLoop(); };
    return true;
}();
} // namespace

using namespace hapto;

namespace {

/// A hook that does what a hook may: reads atomics and computes (a pull towards the other
/// device's point).
struct PullToOther {
    const DeviceMetrics* other = nullptr;
    std::atomic<std::uint64_t> calls{0};
};

Vec3 pullToOther(void* context, const TickHookArgs& tick) noexcept {
    auto& pull = *static_cast<PullToOther*>(context);
    pull.calls.fetch_add(1, std::memory_order_relaxed);
    const Vec3 there(pull.other->positionM[0].load(), pull.other->positionM[1].load(),
                     pull.other->positionM[2].load());
    return 10.0 * (there - tick.devicePointM) + 0.001 * static_cast<double>(tick.contacts.size());
}

/// Every kind of effect, and a hook on every device.
std::vector<ForceEffect> everyEffect(double k) {
    return {ForceEffect::springToPoint(Vec3(0, 0.01, 0), k),
            ForceEffect::springToLine(Vec3(0), Vec3(1, 0, 0), k),
            ForceEffect::springToPlane(Vec3(0), Vec3(0, 1, 0), k),
            ForceEffect::damper(1.0, EffectRegion::box(Vec3(0), Vec3(0.05))),
            ForceEffect::damper(0.5, EffectRegion::sphere(Vec3(0), 0.03)),
            ForceEffect::constant(Vec3(0, -0.1, 0))};
}

} // namespace

TEST_CASE("the servo tick makes no heap allocation, across snapshot updates (step mode)",
          "[threads]") {
    const Scene scene = makeDefaultScene();
    const std::string spec =
        GENERATE(std::string("octree:2:0.005"), std::string("grid:5"), std::string("brute"));
    // With and without the warm-up before each tick (the step mode runs it too).
    const std::uint64_t warmUpNs = GENERATE(std::uint64_t{0}, std::uint64_t{50'000});
    INFO(spec << ", warm-up " << warmUpNs << " ns");
    ManualClock clock;
    World world(scene, IndexSpec::parse(spec));
    world.useClock(clock);
    world.setRestDelay(std::chrono::milliseconds(5));
    std::vector<RuntimeDevice> devices;
    for (DeviceConfig c : defaultDeviceConfigs()) {
        c.rateHz = 2000;
        // A turning stylus with a tool tip: the tip's point and velocity are servo work too.
        c.toolTipM = Vec3(0.0, 0.0, 0.01);
        std::get<SimConfig>(c.params).spinRadPerS = Vec3(0.0, 1.0, 0.0);
        DeviceRendering rendering{everyEffect(20.0), {}};
        rendering.renderer.contactDampingNsPerM = 1.0;
        devices.push_back({makeDevice(c, scene), c, nullptr, rendering});
    }
    RuntimeOptions opt;
    opt.realtime = false;
    opt.warmUpNs = warmUpNs;
    Runtime runtime(world, std::move(devices), opt);
    PullToOther hooks[2];
    for (std::size_t i = 0; i < 2; ++i) {
        hooks[i].other = &runtime.metrics(1 - i);
        runtime.setTickHook(i, {&pullToOther, &hooks[i]});
    }
    const std::uint64_t before = gAllAllocations.load();
    const std::uint64_t servoBefore = gServoAllocations.load();
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 2);
    for (int i = 1; i <= 400; ++i) {
        if (i % 20 == 0) { // a move every 20 ms; re-indexed once it rests
            world.moveObject(scene.object(0).id, scene.object(0).center + Vec3(0, 0.0001 * i, 0),
                             Quat(1, 0, 0, 0));
        }
        if (i % 7 == 0) { // new effects from the control side, picked up by the next tick
            runtime.setEffects(i % 2, everyEffect(10.0 + i % 30));
            runtime.setEffectEnabled(1 - i % 2, i % 6, i % 3 != 0);
        }
        runtime.runUntil(t0 + static_cast<std::uint64_t>(i) * 1'000'000);
        runtime.maintain();
    }
    runtime.stop();
    const RunReport r = runtime.report();
    for (const DeviceReport& d : r.devices) {
        CHECK(d.ticks == 800);
        CHECK(d.fault.empty());
        CHECK(d.snapshotsSeen >= 20);
    }
    CHECK(world.buildsPublished() > 1);
    CHECK(hooks[0].calls.load() == 800);
    CHECK(hooks[1].calls.load() == 800);
    CHECK(gAllAllocations.load() > before); // the counter is live: the control side allocates
    CHECK(gServoAllocations.load() == servoBefore);
}

TEST_CASE("servo threads make no heap allocation while running, across snapshot updates",
          "[realtime]") {
    const Scene scene = makeDefaultScene();
    World world(scene, IndexSpec::parse(kDefaultIndexSpec));
    world.setRestDelay(std::chrono::milliseconds(5));
    std::vector<RuntimeDevice> devices;
    for (DeviceConfig c : defaultDeviceConfigs()) {
        c.rateHz = 2000;
        devices.push_back({makeDevice(c, scene), c, nullptr, {everyEffect(20.0), {}}});
    }
    RuntimeOptions opt;
    opt.realtime = false;
    // Each wake-up comes early, touches the tick's working set and spins to the deadline.
    opt.warmUpNs = GENERATE(std::uint64_t{0}, std::uint64_t{50'000});
    INFO("warm-up " << *opt.warmUpNs << " ns");
    Runtime runtime(world, std::move(devices), opt);
    PullToOther hooks[2];
    for (std::size_t i = 0; i < 2; ++i) {
        hooks[i].other = &runtime.metrics(1 - i);
        runtime.setTickHook(i, {&pullToOther, &hooks[i]});
    }
    const std::uint64_t before = gAllAllocations.load();
    const std::uint64_t servoBefore = gServoAllocations.load();
    runtime.start();
    // Updates until every servo thread has picked up a few of them (however fast it runs).
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    for (int i = 0; std::chrono::steady_clock::now() < until; ++i) {
        if (runtime.metrics(0).snapshotsSeen.load() >= 5 &&
            runtime.metrics(1).snapshotsSeen.load() >= 5) {
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        if (i % 10 == 0) {
            world.moveObject(scene.object(0).id, scene.object(0).center + Vec3(0, 0.0001 * i, 0),
                             Quat(1, 0, 0, 0));
        }
        runtime.setEffects(i % 2, everyEffect(10.0 + i % 30)); // while the servos run
        runtime.maintain();
    }
    runtime.stop();
    const RunReport r = runtime.report();
    for (const DeviceReport& d : r.devices) {
        CHECK(d.fault.empty());
        CHECK(d.snapshotsSeen >= 5); // a device sees snapshots only by ticking
    }
    CHECK(hooks[0].calls.load() > 0);
    CHECK(hooks[1].calls.load() > 0);
    CHECK(gAllAllocations.load() > before); // the counter is live: the control thread allocates
    CHECK(gServoAllocations.load() == servoBefore);
}

namespace {

/// Five simulated hands at 2 kHz (the default pair, then three more walking).
std::vector<DeviceConfig> fiveHands() {
    std::vector<DeviceConfig> configs = defaultDeviceConfigs();
    for (int i = 0; i < 3; ++i) {
        DeviceConfig c = configs[static_cast<std::size_t>(i % 2)];
        c.name = "walk" + std::to_string(i);
        c.transform.translation = Vec3(0.01 * (i - 1), 0.0, 0.01);
        std::get<SimConfig>(c.params).script = HandScript::Walk;
        std::get<SimConfig>(c.params).seed = 10 + static_cast<std::uint64_t>(i);
        configs.push_back(c);
    }
    for (DeviceConfig& c : configs) {
        c.rateHz = 2000;
    }
    return configs;
}

/// fiveHands() opened over `scene` with every effect, ready for a Runtime.
std::vector<RuntimeDevice> fiveHandDevices(const Scene& scene) {
    std::vector<RuntimeDevice> devices;
    for (const DeviceConfig& c : fiveHands()) {
        devices.push_back({makeDevice(c, scene), c, nullptr, {everyEffect(20.0), {}}});
    }
    return devices;
}

} // namespace

TEST_CASE("grouped servos make no heap allocation, across snapshot updates (step mode)",
          "[threads]") {
    const Scene scene = makeDefaultScene();
    ManualClock clock;
    World world(scene, IndexSpec::parse(kDefaultIndexSpec));
    world.useClock(clock);
    world.setRestDelay(std::chrono::milliseconds(5));
    std::vector<RuntimeDevice> devices = fiveHandDevices(scene);
    RuntimeOptions opt;
    opt.realtime = false;
    opt.devicesPerThread = 3; // a group of three and a group of two
    Runtime runtime(world, std::move(devices), opt);
    const std::uint64_t before = gAllAllocations.load();
    const std::uint64_t servoBefore = gServoAllocations.load();
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 5);
    for (int i = 1; i <= 300; ++i) {
        if (i % 20 == 0) {
            world.moveObject(scene.object(0).id, scene.object(0).center + Vec3(0, 0.0001 * i, 0),
                             Quat(1, 0, 0, 0));
        }
        if (i % 7 == 0) {
            runtime.setEffects(static_cast<std::size_t>(i % 5), everyEffect(10.0 + i % 30));
        }
        runtime.runUntil(t0 + static_cast<std::uint64_t>(i) * 1'000'000);
        runtime.maintain();
    }
    runtime.stop();
    for (const DeviceReport& d : runtime.report().devices) {
        CHECK(d.ticks == 600);
        CHECK(d.fault.empty());
        CHECK(d.snapshotsSeen >= 10);
    }
    CHECK(gAllAllocations.load() > before); // the counter is live: the control side allocates
    CHECK(gServoAllocations.load() == servoBefore);
}

TEST_CASE("grouped servo threads make no heap allocation while running", "[realtime]") {
    const Scene scene = makeDefaultScene();
    World world(scene, IndexSpec::parse(kDefaultIndexSpec));
    world.setRestDelay(std::chrono::milliseconds(5));
    std::vector<RuntimeDevice> devices = fiveHandDevices(scene);
    RuntimeOptions opt;
    opt.realtime = false;
    opt.devicesPerThread = 3;
    Runtime runtime(world, std::move(devices), opt);
    const std::uint64_t before = gAllAllocations.load();
    const std::uint64_t servoBefore = gServoAllocations.load();
    REQUIRE(runtime.start() == 5);
    const auto seenEnough = [&runtime] {
        for (std::size_t i = 0; i < runtime.deviceCount(); ++i) {
            if (runtime.metrics(i).snapshotsSeen.load() < 5) {
                return false;
            }
        }
        return true;
    };
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    for (int i = 0; std::chrono::steady_clock::now() < until && !seenEnough(); ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        if (i % 10 == 0) {
            world.moveObject(scene.object(0).id, scene.object(0).center + Vec3(0, 0.0001 * i, 0),
                             Quat(1, 0, 0, 0));
        }
        runtime.setEffects(static_cast<std::size_t>(i % 5), everyEffect(10.0 + i % 30));
        runtime.maintain();
    }
    runtime.stop();
    for (const DeviceReport& d : runtime.report().devices) {
        CHECK(d.fault.empty());
        CHECK(d.snapshotsSeen >= 5); // a device sees snapshots only by ticking
    }
    CHECK(gAllAllocations.load() > before);
    CHECK(gServoAllocations.load() == servoBefore);
}

TEST_CASE("the renderer makes no heap allocation with mesh candidates: triangle items, a moving "
          "mesh's slot, friction, the carry and a full near list") {
    Material m;
    m.stiffness = 1000.0;
    m.staticFriction = 0.6;
    m.dynamicFriction = 0.4;
    Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)},
                {makeMesh(1, Vec3(0.0), test::boxMesh(Vec3(0.03)), Quat(1, 0, 0, 0), m),
                 makeMesh(2, Vec3(0.1, 0, 0), test::gridMesh(0.01, 60), Quat(1, 0, 0, 0), m),
                 makeBox(3, Vec3(-0.1, 0, 0), Vec3(0.02), Quat(1, 0, 0, 0), m)});
    const std::vector<std::uint32_t> items = test::indexedItems(scene);
    const std::vector<std::uint32_t> slots{0, 1, 2};
    Scene moved = scene; // built before the counted loop: the test's own copy, not the servo's
    GodObjectRenderer r;
    r.reset(Vec3(0.0, 0.04, 0.0));
    const std::uint64_t before = gServoAllocations.load();
    hapto::rt::setInServoLoop(true);
    std::uint64_t nearListFull = 0;
    for (int i = 0; i < 600; ++i) {
        CandidateSet c;
        c.add(items);
        if (i >= 300) {
            c.add(slots); // the moving list: whole meshes by their slots
        }
        // Press into the cube's top, slide over its edge and vertex; then the grid, from far
        // above (its near list overflows), pressed and slid; the cube moves under the device.
        const double u = (i % 300) / 300.0;
        const Vec3 p = i < 150   ? Vec3(0.04 * u, 0.028, 0.04 * u)
                       : i < 300 ? Vec3(0.1 + 0.002 * u, 0.02 - 0.06 * u, 0.001)
                                 : Vec3(0.01 * u, 0.028, 0.0);
        if (i >= 300) {
            moved.setPose(0, Vec3(1e-5 * (i - 300), 0, 0), Quat(1, 0, 0, 0));
        }
        const RenderOutput o = r.update(i >= 300 ? moved : scene, c, p, Vec3(NAN), 1e-3);
        nearListFull += o.status == RenderStatus::NearListFull ? 1 : 0;
    }
    hapto::rt::setInServoLoop(false);
    CHECK(gServoAllocations.load() == before);
    CHECK(nearListFull > 0); // the fallback over the raw spans ran too
    CHECK(r.counters().ticks == 600);
}

TEST_CASE("servo ticks in contact with a dynamic body, torsional patches on, make no heap "
          "allocation (step mode, the runtime's dynamics step between them)") {
    // A 100 g box on a static floor under gravity; two simulated hands touch it from above
    // (press 1.5 N each) with 5 mm torsional patches: every tick places the body, splits the
    // reaction and hands back impulses and torsional budgets, and the runtime's dynamics step
    // takes both between the ticks.
    Material m;
    m.stiffness = 1000.0;
    m.staticFriction = 0.6;
    m.dynamicFriction = 0.4;
    SceneObject box = makeBox(1, Vec3(0.0, 0.02, 0.0), Vec3(0.02), Quat(1, 0, 0, 0), m);
    box.body.dynamic = true;
    box.body.massKg = 0.1;
    Scene scene(
        Aabb{Vec3(-0.2), Vec3(0.2)},
        {box, makeBox(2, Vec3(0.0, -0.01, 0.0), Vec3(0.1, 0.01, 0.1), Quat(1, 0, 0, 0), m)});
    ManualClock clock;
    World world(scene, IndexSpec::parse("brute"));
    world.useClock(clock);
    std::vector<RuntimeDevice> devices;
    for (int h = 0; h < 2; ++h) {
        DeviceConfig c = defaultDeviceConfigs()[static_cast<std::size_t>(h)];
        c.rateHz = 1000;
        SimConfig sim;
        sim.script = HandScript::Touch;
        sim.object = 1;
        sim.start = Vec3(h == 0 ? 0.01 : -0.01, 0.06, 0.005);
        c.params = sim;
        DeviceRendering rendering;
        rendering.renderer.torsionRadiusM = 0.005;
        devices.push_back({makeDevice(c, scene), c, nullptr, rendering});
    }
    RuntimeOptions opt;
    opt.realtime = false;
    Runtime runtime(world, std::move(devices), opt);
    REQUIRE(runtime.bodyPoses() != nullptr);
    const std::uint64_t servoBefore = gServoAllocations.load();
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 2);
    for (int i = 1; i <= 2000; ++i) {
        runtime.runUntil(t0 + static_cast<std::uint64_t>(i) * 1'000'000);
        runtime.maintain();
    }
    runtime.stop();
    const RunReport r = runtime.report();
    INFO("body at " << runtime.bodyPoses()->read(0).center.y << " m");
    for (const DeviceReport& d : r.devices) {
        INFO(d.name << ": " << d.contactTicks << " contact ticks of " << d.ticks);
        CHECK(d.fault.empty());
        CHECK(d.contactTicks > 100); // the hands pressed on the body
    }
    CHECK(gServoAllocations.load() == servoBefore);
}

TEST_CASE("servo threads make no heap allocation while a viewer follows the live view",
          "[realtime]") {
    const Scene scene = makeDefaultScene();
    World world(scene, IndexSpec::parse(kDefaultIndexSpec));
    world.setRestDelay(std::chrono::milliseconds(5));
    std::vector<RuntimeDevice> devices;
    for (DeviceConfig c : defaultDeviceConfigs()) {
        c.rateHz = 2000;
        devices.push_back({makeDevice(c, scene), c, nullptr});
    }
    RuntimeOptions opt;
    opt.realtime = false;
    Runtime runtime(world, std::move(devices), opt);
    ViewServer server;
    LiveFeed feed(runtime, server);
    server.setDocument("/scene.json", viewSceneJson(scene, feed.devices(), ViewMode::Live));
    const int port = server.start();
    const std::uint64_t servoBefore = gServoAllocations.load();
    runtime.start();
    feed.start();
    // A viewer on its own thread, reading frames as the page's EventSource does.
    std::atomic<int> frames{0};
    std::atomic<bool> done{false};
    std::thread viewer([&] {
        httplib::Client client("127.0.0.1", port);
        client.Get("/stream", [&](const char* data, std::size_t n) {
            frames.fetch_add(static_cast<int>(std::count(data, data + n, '\n')) / 2);
            return !done.load();
        });
    });
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    for (int i = 0; std::chrono::steady_clock::now() < until; ++i) {
        if (frames.load() >= 10 && runtime.metrics(0).snapshotsSeen.load() >= 5 &&
            runtime.metrics(1).snapshotsSeen.load() >= 5) {
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        if (i % 10 == 0) {
            world.moveObject(scene.object(0).id, scene.object(0).center + Vec3(0, 0.0001 * i, 0),
                             Quat(1, 0, 0, 0));
        }
        runtime.maintain();
        feed.updatePoses(world.current());
    }
    runtime.stop();
    done = true;
    feed.stop();
    server.stop();
    viewer.join();
    CHECK(frames.load() >= 10);
    for (const DeviceReport& d : runtime.report().devices) {
        CHECK(d.ticks > 0);
        CHECK(d.fault.empty());
    }
    CHECK(gServoAllocations.load() == servoBefore);
}
