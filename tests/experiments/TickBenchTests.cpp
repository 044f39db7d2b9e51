// The harness behind `hapto bench tick` (experiments/TickBench.h) runs the servo's own step:
// along the same walk its forces and metrics are a stepped Runtime's, bit for bit; the
// experiments' warmed hand is primed by that step too. Behaviour
// only: nothing here depends on how fast anything runs (the bench's hot mode sets each tick's
// deadline to its wake-up, so a tick misses only if it takes a whole period, three times in a
// row before any force changes).

#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/experiments/TickBench.h"
#include "hapto/runtime/Runtime.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <vector>

using namespace hapto;
using namespace hapto::experiments;

namespace {

/// 27 cubes of 2 cm, 4 cm apart, in a 14 cm box: a walk over it touches several.
Scene cubeGrid() {
    std::vector<SceneObject> objects;
    ObjectId id = 0;
    for (int x = -1; x <= 1; ++x) {
        for (int y = -1; y <= 1; ++y) {
            for (int z = -1; z <= 1; ++z) {
                objects.push_back(makeBox(id++, 0.04 * Vec3(x, y, z), Vec3(0.01)));
            }
        }
    }
    return Scene(Aabb{Vec3(-0.07), Vec3(0.07)}, std::move(objects));
}

} // namespace

TEST_CASE("bench tick runs the servo's step: its forces and metrics are a stepped Runtime's",
          "[threads]") {
    const Scene scene = cubeGrid();
    const IndexSpec spec = IndexSpec::parse("octree:2:0.005");
    TickBenchSettings s;
    s.indices = {spec};
    s.ticks = 1500;
    s.seed = 11;
    s.modes = {TickMode::Hot};
    // Reaching past the index's bounds, so some ticks are outside them (a servo counts those).
    s.walkIn = Aabb{Vec3(-0.075), Vec3(0.075)};
    s.pushMm = 2.0;
    const std::vector<TickTarget> bench = runTickBench(scene, s);
    REQUIRE(bench.size() == 1);
    REQUIRE(bench[0].runs.size() == 1);
    const TickRun& run = *bench[0].runs[0];
    REQUIRE(run.ticks == s.ticks);

    // The same walk through a stepped Runtime: a 1 kHz device with the default renderer and
    // safety filter, the hand held back from the proxy the same way after each tick.
    World world(scene, spec);
    auto device = std::make_unique<WalkDevice>(s.walkIn, s.seed);
    WalkDevice& walk = *device;
    RuntimeDevice rd;
    rd.device = std::move(device);
    rd.config.name = "walk";
    rd.config.rateHz = 1000.0;
    std::vector<RuntimeDevice> devices;
    devices.push_back(std::move(rd));
    RuntimeOptions options;
    options.realtime = false;
    Runtime runtime(world, std::move(devices), options);
    ManualClock clock;
    const std::uint64_t t0 = clock.nowNs();
    REQUIRE(runtime.startStepped(clock) == 1);
    std::size_t differing = 0, pushing = 0;
    for (std::size_t k = 0; k < s.ticks; ++k) {
        runtime.runUntil(t0 + (k + 1) * 1'000'000);
        ContactReport last;
        REQUIRE(runtime.lastTick(0, last));
        REQUIRE(last.tick == k);
        const Vec3& b = run.forceN[k];
        differing += (b.x != last.force.x || b.y != last.force.y || b.z != last.force.z) ? 1 : 0;
        pushing += glm::length(last.force) > 0.1 ? 1 : 0;
        holdHandBack(walk.walk(), last.devicePoint, last.proxy, s.pushMm * 1e-3);
    }
    CHECK(differing == 0);
    CHECK(pushing > 20); // the walk touched the cubes: the forces compared are not all zero

    const DeviceMetrics& a = run.shared->metrics;
    const DeviceMetrics& b = runtime.metrics(0);
    CHECK(a.ticks.load() == b.ticks.load());
    CHECK(a.contactTicks.load() == b.contactTicks.load());
    CHECK(a.outsideTicks.load() == b.outsideTicks.load());
    CHECK(a.outsideTicks.load() > 0);
    CHECK(a.locateStepsSum.load() == b.locateStepsSum.load());
    CHECK(a.candidatesSum.load() == b.candidatesSum.load());
    CHECK(a.zeroedForMisses.load() == b.zeroedForMisses.load());
    runtime.stop();
}

TEST_CASE("bench tick stamps every stage of the step in order", "[threads]") {
    TickBenchSettings s;
    s.indices = {IndexSpec::parse("octree:2:0.005")};
    s.ticks = 300;
    s.modes = {TickMode::Hot};
    const Scene scene = cubeGrid();
    s.walkIn = walkBox(scene.bounds(), 0.0);
    const std::vector<TickTarget> bench = runTickBench(scene, s);
    const TickRun& run = *bench[0].runs[0];
    for (std::size_t k = 0; k < s.ticks; ++k) {
        double sum = 0.0;
        for (const std::vector<double>& stage : run.stageNs) {
            REQUIRE(stage[k] >= 0.0);
            sum += stage[k];
        }
        REQUIRE(sum == run.tickNs[k]); // the stages tile the tick, wake-up to the metrics' end
    }
    CHECK(run.shared->metrics.ticks.load() == s.ticks);
}

TEST_CASE("bench tick's repeats do the same ticks again, with an own time for every tick",
          "[threads]") {
    const Scene scene = cubeGrid();
    TickBenchSettings s;
    s.indices = {IndexSpec::parse("octree:2:0.005"), IndexSpec::parse("grid:4")};
    s.ticks = 700; // past two blocks of kTickBlock, so the runs take turns
    s.seed = 5;
    s.modes = {TickMode::Hot};
    s.walkIn = walkBox(scene.bounds(), 0.0);
    s.pushMm = 2.0; // the hand is held back from the proxy: each repeat follows its own forces

    SECTION("one run: no own times") {
        const std::vector<TickTarget> bench = runTickBench(scene, s);
        CHECK(bench[0].runs[0]->ownNs.empty());
        CHECK(bench[0].runs[0]->workDiffered == 0);
    }
    SECTION("three repeats: the same work every time, an own time for every tick") {
        // (How the repeats fold into each tick's least time is the next test's, on made-up
        // times: nothing here reads what the clock said.)
        s.repeats = 3;
        const std::vector<TickTarget> bench = runTickBench(scene, s);
        for (const TickTarget& target : bench) {
            const TickRun& run = *target.runs[0];
            REQUIRE(run.ownNs.size() == s.ticks);
            CHECK(run.ticks == s.ticks); // the samples and sums are the first repeat's
            // The step is deterministic: the same walk does the same work on every repeat.
            CHECK(run.workDiffered == 0);
            std::size_t touching = 0;
            for (std::size_t k = 0; k < s.ticks; ++k) {
                touching += run.counts[k].contacts > 0 ? 1 : 0;
            }
            CHECK(touching > 20); // the work compared is not all free space
        }
    }
    SECTION("no repeat at all is refused") {
        s.repeats = 0;
        CHECK_THROWS_AS(runTickBench(scene, s), std::invalid_argument);
    }
}

TEST_CASE("a repeat folds in as each tick's least time, and work that differs is counted") {
    TickRun first, again;
    first.tickNs = {500, 900, 700, 300};
    first.ownNs = first.tickNs;
    first.counts.assign(4, TickCounts{});
    again.tickNs = {600, 400, 700, 100};
    again.counts = first.counts;
    foldRepeat(first, again);
    CHECK(first.ownNs == std::vector<double>{500, 400, 700, 100});
    CHECK(first.tickNs == std::vector<double>{500, 900, 700, 300}); // the first repeat's samples
    CHECK(first.workDiffered == 0);
    again.tickNs = {450, 450, 450, 450};
    again.counts[1].candidates = 3;
    again.counts[3].solves = 2;
    foldRepeat(first, again);
    CHECK(first.ownNs == std::vector<double>{450, 400, 450, 100});
    CHECK(first.workDiffered == 2);
}

TEST_CASE("the tail's work is the mean of the counts of the ticks at or above the quantile") {
    // 2 000 ticks of times 0..1999 ns in a shuffled order: the nearest-rank p99.9 is the
    // 1 998th smallest, 1997 ns, so the tail is the three ticks of 1997, 1998 and 1999 ns.
    std::vector<double> ns(2000);
    std::vector<TickCounts> counts(2000);
    for (std::size_t i = 0; i < ns.size(); ++i) {
        ns[i] = static_cast<double>((i * 7) % 2000); // 7 and 2000 coprime: a permutation
        counts[i].solves = 1;
        counts[i].passes = 1;
        counts[i].candidates = 1;
    }
    const auto setTick = [&](double time, std::uint8_t solves, std::uint8_t passes,
                             std::uint32_t candidates, std::uint8_t extra) {
        const auto at =
            static_cast<std::size_t>(std::find(ns.begin(), ns.end(), time) - ns.begin());
        counts[at] = TickCounts{candidates, solves, passes, extra};
    };
    setTick(1997, 2, 4, 10, 1);
    setTick(1998, 1, 5, 20, 2);
    setTick(1999, 3, 6, 30, 3);
    setTick(1996, 9, 9, 99, 9); // just below the cut: not in the tail
    const TailWork w = tailWork(counts, ns, 0.999);
    CHECK(w.ticks == 3);
    CHECK(w.solvedAgain == Approx(2.0 / 3.0));
    CHECK(w.solves == Approx(2.0));
    CHECK(w.passes == Approx(5.0));
    CHECK(w.candidates == Approx(20.0));
    CHECK(w.extraLeaves == Approx(2.0));

    // Ties at the cut are all in the tail; no ticks, no tail; bad input is refused.
    const TailWork flat = tailWork(counts, std::vector<double>(2000, 5.0), 0.999);
    CHECK(flat.ticks == 2000);
    CHECK(tailWork({}, {}, 0.999).ticks == 0);
    CHECK_THROWS_AS(tailWork(counts, std::vector<double>(3, 1.0), 0.999), std::invalid_argument);
    CHECK_THROWS_AS(tailWork(counts, ns, 0.0), std::invalid_argument);
    CHECK_THROWS_AS(tailWork(counts, ns, std::nan("")), std::invalid_argument);
}

TEST_CASE("a warmed simulated hand is primed by the servo's step and starts on the surface",
          "[threads]") {
    const Scene scene = cubeGrid();
    WarmedSimDevice hand(simHand("h", 1000.0, "touch", 3, Vec3(0.0, 0.0, 0.025)), scene);
    CHECK(hand.warmUp(0.1) > 0.0);
    CHECK(hand.reachedPhase());
    // The first reading is the primed proxy: pressed onto a cube, inside none (1 µm slack).
    DeviceState s;
    REQUIRE(hand.read(s) == DeviceStatus::Ok);
    double nearest = 1.0;
    for (const SceneObject& o : scene.objects()) {
        const Vec3 d = glm::abs(s.position - o.aabb().center()); // a cube of half edge 1 cm
        CHECK(std::max({d.x, d.y, d.z}) > 0.01 - 1e-6);
        nearest = std::min(nearest, glm::length(glm::max(d - Vec3(0.01), Vec3(0.0))));
    }
    CHECK(nearest < 1e-3);
    hand.close();
}

TEST_CASE("the experiments' tick probe runs the servo's step and gives its reader back",
          "[threads]") {
    World world(cubeGrid(), IndexSpec::parse("octree:2:0.005"));
    const std::size_t readers = world.readerCount();
    // On a cube's face, so the probe renders a contact.
    CHECK(probeTickSeconds(world, Vec3(0.0, 0.0, 0.0105), 25) > 0.0);
    SnapshotReader* again = world.registerReader(); // the probe's slot, free again
    CHECK(world.readerCount() == std::max<std::size_t>(readers, 1));
    world.unregisterReader(again);
}
