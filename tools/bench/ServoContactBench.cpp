// hapto_bench, servo-contact-dynamic: what a servo tick in contact with a moving dynamic body
// costs against the same tick in contact with a static object of the same shape (issue 37,
// Performance: at most +5 us p99.9, side by side).
//
// Two servo steps (ServoStep::run, everything a servo tick does: read, snapshot, locate,
// candidates, render, effects, safety, write, metrics), each over its own world: a 10 x 2 x
// 10 cm box at the origin, static in one, a dynamic 100 g box in the other. A held hand (a
// device that stays where it is put) presses 1 mm into the top face of each. The dynamic box
// slides under the hand, x = 2 cm sin(2 pi t / 4 s), its pose published into the step's
// BodyPoseTable once a tick at the tick's time, as a 1 kHz dynamics thread would (the
// impulses handed back are taken and dropped outside the timing: the dynamics step is
// dynamics-step/*'s business). Each iteration is one 1 ms instant: both ticks run, in
// alternating order, so both see the same machine; each tick is timed alone on the steady
// clock and on the thread's CPU clock (cpu_: the tick's own cost, without the time other
// processes held the core; it includes a clock_gettime call, ~0.3 us, in both). Counters:
// static_/dynamic_ p50, p99, p999, cpu_p50, cpu_p999 (us), the differences, and each step's
// fraction of ticks in contact (1: the comparison is of contact ticks).
//
// What this does not show: the seqlock read of a pose written by another core misses the
// cache (one line, ~0.1 us) once per dynamics step; here one thread writes and reads it.
//
//   hapto_bench --benchmark_filter='^servo-contact-dynamic' --benchmark_min_time=2
//               --benchmark_repetitions=5   (one line)

#include "hapto/core/Clock.h"
#include "hapto/experiments/TickBench.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/ServoStep.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/MassProperties.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <vector>

namespace hapto::bench {
namespace {

constexpr std::uint64_t kPeriodNs = 1'000'000; // servo and dynamics: 1 kHz
constexpr double kTopY = 0.01;                 // the box's top face (m)
constexpr double kPressM = 0.001;              // how far the hand is held below it (m)
constexpr double kSwingM = 0.02;               // the dynamic box's swing (m)
constexpr double kSwingPeriodS = 4.0;          // and its period (s)

/// A hand that stays where it is put (world = device frame).
class HeldHand final : public Device {
public:
    std::string_view name() const override { return "held"; }
    DeviceKind kind() const override { return DeviceKind::Scripted; }
    DeviceCapabilities capabilities() const override {
        return {"held bench hand", Aabb{Vec3(-1), Vec3(1)}, 100.0, 0.0, 1000.0, 0};
    }
    DeviceStatus open() override { return DeviceStatus::Ok; }
    void close() override {}
    DeviceStatus read(DeviceState& state) noexcept override {
        state = DeviceState{};
        state.position = at;
        state.hasVelocity = true;
        return DeviceStatus::Ok;
    }
    DeviceStatus write(const Vec3&) noexcept override { return DeviceStatus::Ok; }
    std::string errorMessage() const override { return {}; }

    Vec3 at{0.0, kTopY + 0.005, 0.0}; ///< Where it is (m).
};

Scene boxScene(bool dynamic) {
    SceneObject box =
        makeBox(0, Vec3(0.0), Vec3(0.05, kTopY, 0.05), Quat(1, 0, 0, 0), generatedMaterial());
    if (dynamic) {
        box.body.dynamic = true;
        fillMassProperties(box, 0.1, std::nullopt, std::nullopt);
    }
    Scene scene(Aabb{Vec3(-0.2), Vec3(0.2)}, {box});
    scene.setPhysics(ScenePhysics{});
    return scene;
}

/// One hand on one box, with its world and (for the dynamic box) its pose table.
struct Side {
    World world;
    BodyPoseTable table;
    HeldHand hand;
    ServoStepShared shared;
    ServoStep step;
    std::vector<double> us, cpuUs; // each kept tick's wall and thread CPU time (us)

    Side(bool dynamic, ManualClock& clock)
        : world(boxScene(dynamic), IndexSpec::parse(kDefaultIndexSpec)), table(dynamic ? 1 : 0),
          step(RendererConfig{}, SafetyConfig{}) {
        world.useClock(clock);
        step.setTiming(kPeriodNs, 3, 0.1, std::numeric_limits<std::uint64_t>::max());
        step.device = &hand;
        step.reader = world.registerReader();
        step.ports = shared.portsFor(world, &clock);
        step.ports.bodies = dynamic ? &table : nullptr;
        us.reserve(1 << 22);
        cpuUs.reserve(1 << 22);
    }
    /// Publishes the box's pose at `tNs` (s since the start `t`), as the dynamics would.
    void publish(std::uint64_t tNs, double t, std::uint64_t stepNo) {
        if (table.size() == 0) {
            return;
        }
        const double w = 2 * std::numbers::pi / kSwingPeriodS;
        BodyPose p;
        p.center = Vec3(kSwingM * std::sin(w * t), 0.0, 0.0);
        p.centerOfMass = p.center;
        p.velocity = Vec3(kSwingM * w * std::cos(w * t), 0.0, 0.0);
        p.timeNs = tNs;
        p.step = stepNo;
        table.publish(0, p);
        Vec3 linear, angular;
        table.takeImpulse(0, linear, angular); // the dynamics' business, not the servo's
    }
    /// One timed tick at `tNs`.
    void tick(std::uint64_t tNs, bool keep) {
        const std::uint64_t c0 = threadCpuNs();
        const auto t0 = std::chrono::steady_clock::now();
        (void)step.run(tNs);
        const auto t1 = std::chrono::steady_clock::now();
        const std::uint64_t c1 = threadCpuNs();
        if (keep && us.size() < us.capacity()) {
            us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
            cpuUs.push_back(1e-3 * static_cast<double>(c1 - c0));
        }
    }
};

void report(benchmark::State& state, const char* prefix, Side& side) {
    const std::string p(prefix);
    const auto ticks = static_cast<double>(side.shared.metrics.ticks.load());
    state.counters[p + "contact"] =
        ticks > 0 ? static_cast<double>(side.shared.metrics.contactTicks.load()) / ticks : 0.0;
    const experiments::Quantiles q = experiments::quantilesOf(std::move(side.us));
    state.counters[p + "p50_us"] = q.p50;
    state.counters[p + "p99_us"] = q.p99;
    state.counters[p + "p999_us"] = q.p999;
    const experiments::Quantiles cpu = experiments::quantilesOf(std::move(side.cpuUs));
    state.counters[p + "cpu_p50_us"] = cpu.p50;
    state.counters[p + "cpu_p999_us"] = cpu.p999;
}

void servoContact(benchmark::State& state) {
    ManualClock clock;
    auto still = std::make_unique<Side>(false, clock);
    auto moving = std::make_unique<Side>(true, clock);
    std::uint64_t t = clock.nowNs();
    const std::uint64_t t0 = t;
    still->step.start(t);
    moving->step.start(t);
    std::uint64_t k = 0;
    const auto instant = [&](bool keep) {
        t += kPeriodNs;
        ++k;
        clock.set(t);
        moving->publish(t, static_cast<double>(t - t0) * 1e-9, k);
        Side& a = (k % 2 == 0) ? *still : *moving;
        Side& b = (k % 2 == 0) ? *moving : *still;
        a.tick(t, keep);
        clock.set(t);
        b.tick(t, keep);
    };
    for (int i = 0; i < 200; ++i) { // the hands come down onto the tops, 0.1 mm a tick
        const double y = std::max(kTopY - kPressM, kTopY + 0.005 - 1e-4 * i);
        still->hand.at.y = y;
        moving->hand.at.y = y;
        instant(false);
    }
    still->shared.metrics.ticks.store(0);
    still->shared.metrics.contactTicks.store(0);
    moving->shared.metrics.ticks.store(0);
    moving->shared.metrics.contactTicks.store(0);
    for (auto _ : state) {
        const auto s0 = std::chrono::steady_clock::now();
        instant(true);
        state.SetIterationTime(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - s0).count());
    }
    report(state, "static_", *still);
    report(state, "dynamic_", *moving);
    state.counters["delta_p50_us"] =
        state.counters["dynamic_p50_us"] - state.counters["static_p50_us"];
    state.counters["delta_p999_us"] =
        state.counters["dynamic_p999_us"] - state.counters["static_p999_us"];
    state.counters["delta_cpu_p999_us"] =
        state.counters["dynamic_cpu_p999_us"] - state.counters["static_cpu_p999_us"];
}

const bool gRegistered = [] {
    benchmark::RegisterBenchmark("servo-contact-dynamic", servoContact)
        ->UseManualTime()
        ->Unit(benchmark::kMicrosecond);
    return true;
}();

} // namespace
} // namespace hapto::bench
