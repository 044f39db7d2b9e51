// Proves the servo path never allocates: this binary replaces the global operator new and
// counts every allocation made inside a servo loop (a servo thread's, or a step-mode tick).

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
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
std::atomic<std::uint64_t> gServoAllocations{0};
std::atomic<std::uint64_t> gAllAllocations{0};

// Every form of operator new comes here (plain, array, nothrow, over-aligned), so nothing a
// servo thread allocates escapes the count, and every delete frees what its new allocated.
void* counted(std::size_t n, std::size_t align = 0) noexcept {
    gAllAllocations.fetch_add(1, std::memory_order_relaxed);
    if (hapto::rt::inServoLoop()) {
        gServoAllocations.fetch_add(1, std::memory_order_relaxed);
    }
    n = n ? n : 1;
    if (align > alignof(std::max_align_t)) {
        return std::aligned_alloc(align, (n + align - 1) / align * align);
    }
    return std::malloc(n);
}
void* countedOrThrow(std::size_t n, std::size_t align = 0) {
    if (void* p = counted(n, align)) {
        return p;
    }
    throw std::bad_alloc();
}
} // namespace

void* operator new(std::size_t n) {
    return countedOrThrow(n);
}
void* operator new[](std::size_t n) {
    return countedOrThrow(n);
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
    return counted(n);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
    return counted(n);
}
void* operator new(std::size_t n, std::align_val_t a) {
    return countedOrThrow(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a) {
    return countedOrThrow(n, static_cast<std::size_t>(a));
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    return counted(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    return counted(n, static_cast<std::size_t>(a));
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
    std::free(p);
}

using namespace hapto;

TEST_CASE("the servo tick makes no heap allocation, across snapshot updates (step mode)") {
    const Scene scene = makeDefaultScene();
    const std::string spec =
        GENERATE(std::string("octree:2:0.005"), std::string("grid:5"), std::string("brute"));
    INFO(spec);
    ManualClock clock;
    World world(scene, IndexSpec::parse(spec));
    world.useClock(clock);
    world.setRestDelay(std::chrono::milliseconds(5));
    std::vector<RuntimeDevice> devices;
    for (DeviceConfig c : defaultDeviceConfigs()) {
        c.rateHz = 2000;
        devices.push_back({makeDevice(c, scene), c, nullptr});
    }
    RuntimeOptions opt;
    opt.realtime = false;
    Runtime runtime(world, std::move(devices), opt);
    const std::uint64_t before = gAllAllocations.load();
    const std::uint64_t servoBefore = gServoAllocations.load();
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 2);
    for (int i = 1; i <= 400; ++i) {
        if (i % 20 == 0) { // a move every 20 ms; re-indexed once it rests
            world.moveObject(scene.object(0).id, scene.object(0).center + Vec3(0, 0.0001 * i, 0),
                             Quat(1, 0, 0, 0));
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
    CHECK(gAllAllocations.load() > before); // the counter is live: the control side allocates
    CHECK(gServoAllocations.load() == servoBefore);
}

TEST_CASE("servo threads make no heap allocation while running, across snapshot updates",
          "[realtime]") {
    const Scene scene = makeDefaultScene();
    World world(scene, IndexSpec::parse("octree:2:0.005"));
    world.setRestDelay(std::chrono::milliseconds(5));
    std::vector<RuntimeDevice> devices;
    for (DeviceConfig c : defaultDeviceConfigs()) {
        c.rateHz = 2000;
        devices.push_back({makeDevice(c, scene), c, nullptr});
    }
    RuntimeOptions opt;
    opt.realtime = false;
    Runtime runtime(world, std::move(devices), opt);
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
        runtime.maintain();
    }
    runtime.stop();
    const RunReport r = runtime.report();
    for (const DeviceReport& d : r.devices) {
        CHECK(d.ticks > 0);
        CHECK(d.fault.empty());
        CHECK(d.snapshotsSeen >= 5);
    }
    CHECK(gAllAllocations.load() > before); // the counter is live: the control thread allocates
    CHECK(gServoAllocations.load() == servoBefore);
}

TEST_CASE("servo threads make no heap allocation while a viewer follows the live view",
          "[realtime]") {
    const Scene scene = makeDefaultScene();
    World world(scene, IndexSpec::parse("octree:2:0.005"));
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
