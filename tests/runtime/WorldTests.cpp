#include "hapto/index/Cursor.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <thread>
#include <vector>

using namespace hapto;

namespace {

Scene twoBoxes() {
    return Scene(Aabb{Vec3(-0.125), Vec3(0.125)}, {makeBox(10, Vec3(-0.05, 0, 0), Vec3(0.01)),
                                                   makeBox(20, Vec3(0.05, 0, 0), Vec3(0.01))});
}

bool candidatesHold(const SpatialIndex& index, const Vec3& p, std::uint32_t slot) {
    Cursor c(index);
    const auto r = c.locate(p);
    return std::find(r.candidates.begin(), r.candidates.end(), slot) != r.candidates.end();
}

} // namespace

TEST_CASE("a moved object is on the brute-force path at once and back in the index at rest",
          "[threads]") {
    World world(twoBoxes(), IndexSpec::parse("octree:1:0.005"));
    world.setRestDelay(std::chrono::nanoseconds(0));
    const std::uint64_t v1 = world.current().version;
    const std::uint32_t slot = *world.current().scene->slotOf(10);
    REQUIRE(candidatesHold(*world.current().index, Vec3(-0.05, 0, 0), slot));

    world.moveObject(10, Vec3(-0.05, -0.09, 0), Quat(1, 0, 0, 0));
    const WorldSnapshot& moved = world.current();
    CHECK(moved.version > v1);
    CHECK(moved.scene->object(slot).center == Vec3(-0.05, -0.09, 0));
    CHECK(std::find(moved.moving.begin(), moved.moving.end(), slot) != moved.moving.end());
    CHECK(world.isMoving(10));

    world.settle();
    const WorldSnapshot& rested = world.current();
    CHECK_FALSE(world.isMoving(10));
    CHECK(rested.moving.empty());
    // The new place is in another octant from the old one, so no leaf holds both.
    CHECK(candidatesHold(*rested.index, Vec3(-0.05, -0.09, 0), slot));
    CHECK_FALSE(candidatesHold(*rested.index, Vec3(-0.05, 0.005, 0.005), slot));
    CHECK(world.buildsPublished() == 2);
}

TEST_CASE("added objects are felt at once, removed ones vanish with their rebuild", "[threads]") {
    World world(twoBoxes(), IndexSpec::parse("grid:4"));
    world.setRestDelay(std::chrono::nanoseconds(0));
    world.addObject(makeSphere(30, Vec3(0, 0.05, 0), 0.01));
    const auto slot = world.current().scene->slotOf(30);
    REQUIRE(slot.has_value());
    CHECK(world.current().moving == std::vector<std::uint32_t>{*slot});

    world.removeObject(10);
    CHECK(world.current().scene->slotOf(10).has_value()); // not yet: waits for its build
    world.settle();
    const WorldSnapshot& s = world.current();
    CHECK_FALSE(s.scene->slotOf(10).has_value());
    REQUIRE(s.scene->slotOf(30).has_value());
    CHECK(candidatesHold(*s.index, Vec3(0, 0.05, 0), *s.scene->slotOf(30)));
    CHECK(candidatesHold(*s.index, Vec3(0.05, 0, 0), *s.scene->slotOf(20)));
    CHECK(s.moving.empty());
    CHECK_THROWS(world.removeObject(10));
    CHECK_THROWS(world.moveObject(999, Vec3(0), Quat(1, 0, 0, 0)));
}

TEST_CASE("a world serves any number of readers, and a reader given back is reused") {
    World world(twoBoxes(), IndexSpec::parse("brute"));
    std::vector<SnapshotReader*> readers;
    for (int i = 0; i < 200; ++i) { // far past the old fixed cap of 64
        readers.push_back(world.registerReader());
        REQUIRE(readers.back() != nullptr);
    }
    std::vector<SnapshotReader*> sorted = readers;
    std::sort(sorted.begin(), sorted.end());
    CHECK(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end()); // all distinct
    CHECK(world.readerCount() == 200);
    // Every one of them holds back reclamation while it holds a snapshot.
    const WorldSnapshot& held = world.acquire(*readers[150]);
    world.moveObject(20, Vec3(0.06, 0, 0), Quat(1, 0, 0, 0));
    world.maintain();
    CHECK(world.retiredCount() == 1);
    CHECK(world.acquire(*readers[150]).version > held.version);
    world.maintain();
    CHECK(world.retiredCount() == 0);
    world.unregisterReader(readers[7]);
    CHECK(world.registerReader() == readers[7]); // reused, no growth
    CHECK(world.readerCount() == 200);
    for (SnapshotReader* r : readers) {
        world.unregisterReader(r);
    }
}

TEST_CASE("a snapshot a reader holds is not freed until the reader moves on") {
    World world(twoBoxes(), IndexSpec::parse("brute"));
    SnapshotReader* reader = world.registerReader();
    REQUIRE(reader != nullptr);
    const WorldSnapshot& held = world.acquire(*reader);
    world.moveObject(20, Vec3(0.06, 0, 0), Quat(1, 0, 0, 0));
    world.maintain();
    CHECK(world.retiredCount() == 1);
    CHECK(held.scene->object(1).center == Vec3(0.05, 0, 0)); // still readable
    const WorldSnapshot& fresh = world.acquire(*reader);
    CHECK(fresh.version > held.version);
    world.maintain();
    CHECK(world.retiredCount() == 0);
    world.unregisterReader(reader);
}

TEST_CASE("8 servo-like threads read while the control thread publishes: versions only grow",
          "[threads]") {
    RandomOptions opt;
    opt.count = 300;
    opt.seed = 4;
    World world(makeRandomScene(opt), IndexSpec::parse(kDefaultIndexSpec));
    world.setRestDelay(std::chrono::milliseconds(1));
    std::atomic<bool> stop{false};
    std::atomic<int> failures{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 8; ++t) {
        threads.emplace_back([&, t] {
            SnapshotReader* r = world.registerReader();
            if (!r) {
                ++failures;
                return;
            }
            Cursor cursor;
            std::uint64_t version = 0;
            double x = -0.1 + 0.02 * t;
            while (!stop.load()) {
                const WorldSnapshot& s = world.acquire(*r);
                if (s.version < version) {
                    ++failures;
                }
                if (s.version != version) {
                    cursor.reset(*s.index);
                    version = s.version;
                }
                x = x > 0.1 ? -0.1 : x + 0.0005;
                const auto res = cursor.locate(Vec3(x, 0.01 * t - 0.04, 0));
                for (std::uint32_t slot : res.candidates) {
                    if (slot >= s.scene->size()) {
                        ++failures;
                    }
                }
            }
            world.unregisterReader(r);
        });
    }
    for (int i = 0; i < 300; ++i) {
        world.moveObject(static_cast<ObjectId>(i % 50), Vec3(0.001 * i - 0.1, 0.05, 0),
                         Quat(1, 0, 0, 0));
        if (i % 20 == 0) {
            world.addObject(
                makeSphere(static_cast<ObjectId>(1000 + i), Vec3(0, -0.05, 0.001 * i), 0.005));
        }
        if (i % 50 == 49) {
            world.removeObject(static_cast<ObjectId>(100 + i / 50));
        }
        world.maintain();
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    stop = true;
    for (auto& th : threads) {
        th.join();
    }
    world.settle();
    CHECK(failures == 0);
    CHECK(world.retiredCount() == 0);
    CHECK(world.current().moving.empty());
    CHECK(world.current().scene->size() == 300 + 15 - 6);
}

TEST_CASE("on a ManualClock an object goes back into the index exactly one rest delay after its "
          "last move, built inline by maintain()") {
    ManualClock clock;
    World world(twoBoxes(), IndexSpec::parse("octree:1:0.005"));
    world.useClock(clock);
    world.setRestDelay(std::chrono::milliseconds(100));
    const std::uint32_t slot = *world.current().scene->slotOf(10);
    world.moveObject(10, Vec3(-0.05, -0.09, 0), Quat(1, 0, 0, 0));
    clock.advance(60'000'000);
    world.moveObject(10, Vec3(-0.05, -0.08, 0), Quat(1, 0, 0, 0)); // moved again at 60 ms
    clock.advance(99'999'999);
    world.maintain();
    CHECK(world.isMoving(10)); // 1 ns short of resting
    CHECK(world.buildsPublished() == 1);
    clock.advance(1);
    world.maintain(); // rested: built and published in this call
    CHECK_FALSE(world.isMoving(10));
    CHECK(world.buildsPublished() == 2);
    const WorldSnapshot& s = world.current();
    CHECK(s.moving.empty());
    CHECK(candidatesHold(*s.index, Vec3(-0.05, -0.08, 0), slot));

    // A removal is published by the next maintain(), whatever the clock.
    world.removeObject(20);
    CHECK(world.current().scene->slotOf(20).has_value());
    world.maintain();
    CHECK_FALSE(world.current().scene->slotOf(20).has_value());
    CHECK(world.buildsPublished() == 3);
}
