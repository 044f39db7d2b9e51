// The harness behind `hapto bench tick` (TickBench.h has the design note).

#include "hapto/experiments/TickBench.h"

#include "hapto/core/Clock.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/Runtime.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

namespace hapto::experiments {
namespace {

/// The bench's servo period (ns): a 1 kHz device, the walk's tick.
constexpr std::uint64_t kPeriodNs = 1'000'000;

constexpr std::array<const char*, 3> kModeNames{"hot", "sleep", "sleep+warm"};
/// The same sleep modes with a CPU wake-latency request held (--wake-latency-us).
constexpr std::array<const char*, 3> kHeldModeNames{"", "sleep+lat", "sleep+warm+lat"};

/// A run of `mode` over `world`: its device, and a step set up as the runtime sets up a 1 kHz
/// device with the default renderer and safety filter, without a watchdog.
std::unique_ptr<TickRun> makeRun(World& world, const Scene& scene, const TickBenchSettings& s,
                                 TickMode mode, bool held) {
    auto run = std::make_unique<TickRun>();
    run->mode = mode;
    run->holdLatency = held;
    std::unique_ptr<Device> inner;
    if (s.simDevice) {
        DeviceConfig c = defaultDeviceConfigs().front();
        c.name = "bench";
        inner = makeDevice(c, scene);
    }
    auto device = std::make_unique<WalkDevice>(s.walkIn, s.seed, std::move(inner), s.path);
    run->device = device.get();
    run->owned = std::move(device);
    if (run->owned->open() != DeviceStatus::Ok) {
        throw std::runtime_error(std::string("bench tick: the ") + (s.simDevice ? "sim" : "walk") +
                                 " device did not open: " + run->owned->errorMessage());
    }
    run->shared = std::make_unique<ServoStepShared>();
    run->step = std::make_unique<ServoStep>(RendererConfig{}, SafetyConfig{});
    ServoStep& step = *run->step;
    const RuntimeOptions runtime;
    // No watchdog: a run waits while the others take their turns.
    step.setTiming(kPeriodNs, runtime.missLimit, runtime.lateWakeupFraction, UINT64_MAX);
    step.device = run->owned.get();
    step.reader = world.registerReader();
    step.ports = run->shared->portsFor(world);
    if (!s.bodyPoses.empty()) {
        run->bodies = std::make_unique<BodyPoseTable>(1);
        step.ports.bodies = run->bodies.get();
    }
    step.start(rt::nowNs());
    for (std::vector<double>& stage : run->stageNs) {
        stage.assign(s.ticks, 0.0);
    }
    run->tickNs.assign(s.ticks, 0.0);
    run->forceN.assign(s.ticks, Vec3(0.0));
    run->gapM.assign(s.ticks, 0.0);
    run->counts.assign(s.ticks, TickCounts{});
    run->cpuNs.assign(s.cpuTime ? s.ticks : 0, 0.0);
    run->startLateNs.reserve(s.ticks); // filled in the sleep modes only
    return run;
}

/// What `tick` did; `before` is the previous tick's render (null for the first tick).
TickCounts countsOf(const TickOutput& tick, const RenderOutput* before) {
    const RenderOutput& r = tick.render;
    TickCounts c;
    c.candidates = r.objectsTested;
    c.solves = tick.solves;
    c.passes = r.iterations;
    c.extraLeaves = tick.extraLeaves;
    c.pullBacks = tick.pullBacks;
    c.contacts = r.contactCount;
    c.bodies = tick.bodiesPlaced;
    for (std::size_t i = 0; i < r.contactCount; ++i) {
        bool held = false;
        for (std::size_t j = 0; before != nullptr && j < before->contactCount; ++j) {
            const Contact& b = before->contacts[j];
            // The same item's same plane (a box's face; a triangle), to rounding.
            held = held || (b.slot == r.contacts[i].slot &&
                            glm::dot(b.normal, r.contacts[i].normal) > 1.0 - 1e-9);
        }
        c.facetsEntered += held ? 0 : 1;
    }
    return c;
}

/// Tick `at` of `run`, woken at `wakeNs` for the deadline `deadlineNs`: the servo's step with
/// a probe, then the samples and the hand held back.
void timedTick(TickRun& run, std::size_t at, std::uint64_t wakeNs, std::uint64_t deadlineNs,
               double pushM) {
    ServoStep& step = *run.step;
    step.deadlineNs = deadlineNs;
    if (!step.run(wakeNs, &run.probe)) {
        throw std::runtime_error(std::string("bench tick: the step faulted: ") +
                                 faultName(run.shared->metrics.fault.load()));
    }
    const ServoStepProbe& p = run.probe;
    std::uint64_t from = wakeNs;
    for (std::size_t s = 0; s < ServoStepProbe::kStages; ++s) {
        run.stageNs[s][at] = static_cast<double>(p.endNs[s] - from);
        from = p.endNs[s];
    }
    run.tickNs[at] = static_cast<double>(p.endNs.back() - wakeNs);
    run.forceN[at] = p.forceN;
    ++run.ticks;
    const TickOutput& tick = p.tick;
    run.locateSteps += tick.locateSteps;
    run.candidates += tick.render.objectsTested;
    run.contactTicks += tick.render.contactCount > 0 ? 1 : 0;
    run.solves += tick.solves;
    run.extraLeaves += tick.extraLeaves;
    run.pullBacks += tick.pullBacks;
    run.gapM[at] = glm::length(p.devicePointM - tick.render.proxy);
    const TickCounts c = countsOf(tick, at > 0 ? &run.lastRender : nullptr);
    run.counts[at] = c;
    run.passes += c.passes;
    run.multiContactTicks += c.contacts >= 2 ? 1 : 0;
    run.facetsEntered += c.facetsEntered;
    run.lastRender = tick.render;
    holdHandBack(run.device->walk(), p.devicePointM, tick.render.proxy, pushM);
}

/// Publishes tick `k`'s pose of the dynamic body, stamped now, and drops what the hand handed
/// back to it.
void publishBody(TickRun& run, std::size_t k, const TickBenchSettings& s) {
    if (!run.bodies) {
        return;
    }
    BodyPose pose = s.bodyPoses[k % s.bodyPoses.size()];
    pose.timeNs = rt::nowNs();
    pose.step = k + 1;
    run.bodies->publish(0, pose);
    Vec3 linear, angular;
    run.bodies->takeImpulse(0, linear, angular);
}

/// Runs `count` ticks of `run` from sample `at` on, started as its mode says.
void driveTicks(TickRun& run, std::size_t at, std::size_t count, const TickBenchSettings& s) {
    const auto sleepNs = static_cast<std::uint64_t>(s.sleepUs * 1000.0);
    const auto warmNs = static_cast<std::uint64_t>(s.warmUs * 1000.0);
    // Held for this block only (the request takes effect at the CPUs' next idle entry), so
    // the runs with and without it take turns like every other pair of runs.
    rt::WakeLatencyHold hold;
    if (run.holdLatency) {
        hold = rt::WakeLatencyHold(s.wakeLatencyUs);
        if (!hold.held()) {
            throw std::runtime_error("bench tick: --wake-latency-us: " + hold.note());
        }
    }
    for (std::size_t k = at; k < at + count; ++k) {
        publishBody(run, k, s);
        std::uint64_t wake = rt::nowNs();
        std::uint64_t deadline = wake;
        if (run.mode != TickMode::Hot) {
            deadline = wake + sleepNs;
            if (run.mode == TickMode::Warm) {
                // As the servo loop does with a warm-up: wake early, touch, spin to the deadline.
                rt::sleepUntilNs(deadline - warmNs, 0);
                run.kept += run.step->warm();
                run.warmOverruns += rt::nowNs() > deadline ? 1 : 0;
                spinUntilNs(deadline);
            } else {
                rt::sleepUntilNs(deadline, 0);
            }
            wake = rt::nowNs();
            if (run.startLateNs.size() < run.startLateNs.capacity()) {
                run.startLateNs.push_back(
                    static_cast<double>(wake > deadline ? wake - deadline : 0));
            }
        }
        const std::uint64_t cpu0 = s.cpuTime ? threadCpuNs() : 0;
        timedTick(run, k, wake, deadline, s.pushMm * 1e-3);
        if (s.cpuTime) {
            run.cpuNs[k] = static_cast<double>(threadCpuNs() - cpu0);
        }
    }
}

/// Runs every run in `order` for s.ticks ticks, in turns of kTickBlock ticks, each block
/// starting with the next run.
void driveInTurns(const std::vector<TickRun*>& order, const TickBenchSettings& s) {
    for (std::size_t done = 0, round = 0; done < s.ticks; ++round) {
        const std::size_t length = std::min(kTickBlock, s.ticks - done);
        for (std::size_t r = 0; r < order.size(); ++r) {
            driveTicks(*order[(r + round) % order.size()], done, length, s);
        }
        done += length;
    }
}

} // namespace

WalkDevice::WalkDevice(const Aabb& bounds, std::uint64_t seed, std::unique_ptr<Device> inner,
                       std::vector<Vec3> path)
    : mWalk(bounds, seed), mPath(std::move(path)), mInner(std::move(inner)) {}

DeviceStatus WalkDevice::open() {
    return mInner ? mInner->open() : DeviceStatus::Ok;
}

void WalkDevice::close() {
    if (mInner) {
        mInner->close();
    }
}

DeviceStatus WalkDevice::read(DeviceState& state) noexcept {
    const DeviceStatus st = mInner ? mInner->read(state) : DeviceStatus::Ok;
    // An inner hand was read; the walk or the path drives the tick.
    if (mPath.empty()) {
        state.position = mWalk.next();
    } else {
        state.position = mPath[mPathAt];
        mPathAt = mPathAt + 1 < mPath.size() ? mPathAt + 1 : 0;
    }
    state.hasVelocity = false;
    return st;
}

DeviceStatus WalkDevice::write(const Vec3& forceN) noexcept {
    mForceN = forceN;
    return mInner ? mInner->write(forceN) : DeviceStatus::Ok;
}

void WalkDevice::periodsSkipped(std::uint64_t periods) noexcept {
    if (mInner) {
        mInner->periodsSkipped(periods);
    }
}

std::string WalkDevice::errorMessage() const {
    return mInner ? mInner->errorMessage() : std::string();
}

void holdHandBack(HandWalk& hand, const Vec3& devicePointM, const Vec3& proxyM, double pushM) {
    const double gap = glm::length(devicePointM - proxyM);
    if (pushM > 0.0 && gap > pushM) {
        hand.holdBack(proxyM + (pushM / gap) * (devicePointM - proxyM));
    }
}

Aabb walkBox(const Aabb& bounds, double edgeM) {
    if (edgeM <= 0.0) {
        return bounds;
    }
    const Vec3 half(0.5 * edgeM);
    return {glm::max(bounds.min, bounds.center() - half),
            glm::min(bounds.max, bounds.center() + half)};
}

const char* modeName(const TickRun& run) {
    const auto m = static_cast<std::size_t>(run.mode);
    return run.holdLatency ? kHeldModeNames[m] : kModeNames[m];
}

void foldRepeat(TickRun& first, const TickRun& again) {
    for (std::size_t k = 0; k < first.ownNs.size(); ++k) {
        first.ownNs[k] = std::min(first.ownNs[k], again.tickNs[k]);
        first.workDiffered += first.counts[k] == again.counts[k] ? 0 : 1;
    }
}

std::vector<TickTarget> runTickBench(const Scene& scene, const TickBenchSettings& s) {
    if (s.repeats == 0) {
        throw std::invalid_argument("bench tick: repeats must be at least 1");
    }
    std::vector<std::pair<TickMode, bool>> modes;
    for (const TickMode m : s.modes) {
        modes.emplace_back(m, false);
    }
    if (modes.empty()) {
        modes = {{TickMode::Hot, false}, {TickMode::Sleep, false}, {TickMode::Warm, false}};
        if (s.wakeLatencyUs >= 0) {
            modes.insert(modes.end(), {{TickMode::Sleep, true}, {TickMode::Warm, true}});
        }
    }
    std::vector<TickTarget> targets;
    for (const IndexSpec& spec : s.indices) {
        TickTarget target;
        target.spec = spec;
        target.world = std::make_unique<World>(scene, spec);
        for (const auto& [mode, held] : modes) {
            target.runs.push_back(makeRun(*target.world, scene, s, mode, held));
        }
        targets.push_back(std::move(target));
    }
    // Every run walks the same seeded path; the runs take turns in blocks, each block starting
    // with a different one.
    rt::tightenTimerSlack();
    std::vector<TickRun*> order;
    for (TickTarget& t : targets) {
        for (auto& r : t.runs) {
            order.push_back(r.get());
        }
    }
    driveInTurns(order, s);
    if (s.repeats > 1) {
        for (TickRun* run : order) {
            run->ownNs = run->tickNs;
        }
    }
    for (std::size_t repeat = 1; repeat < s.repeats; ++repeat) {
        // Fresh devices and steps over the same worlds, in the same order: the same ticks.
        std::vector<std::unique_ptr<TickRun>> again;
        std::vector<TickRun*> againOrder;
        std::vector<World*> worlds;
        for (TickTarget& t : targets) {
            for (const auto& [mode, held] : modes) {
                again.push_back(makeRun(*t.world, scene, s, mode, held));
                againOrder.push_back(again.back().get());
                worlds.push_back(t.world.get());
            }
        }
        driveInTurns(againOrder, s);
        for (std::size_t r = 0; r < order.size(); ++r) {
            foldRepeat(*order[r], *again[r]);
            order[r]->kept += again[r]->kept;
            worlds[r]->unregisterReader(again[r]->step->reader);
        }
    }
    return targets;
}

double quantileOfSorted(const std::vector<double>& sorted, double q) {
    if (sorted.empty()) {
        return 0.0;
    }
    const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
    return sorted[std::clamp<std::size_t>(rank, 1, sorted.size()) - 1];
}

Quantiles quantilesOf(std::vector<double> ns) {
    Quantiles q;
    if (ns.empty()) {
        return q;
    }
    double sum = 0;
    for (const double x : ns) {
        sum += x;
    }
    q.mean = sum / static_cast<double>(ns.size());
    std::sort(ns.begin(), ns.end());
    q.max = ns.back();
    q.p50 = quantileOfSorted(ns, 0.5);
    q.p99 = quantileOfSorted(ns, 0.99);
    q.p999 = quantileOfSorted(ns, 0.999);
    return q;
}

TailWork tailWork(const std::vector<TickCounts>& counts, const std::vector<double>& ns, double q) {
    if (counts.size() != ns.size()) {
        throw std::invalid_argument("tailWork: " + std::to_string(counts.size()) +
                                    " ticks' counts against " + std::to_string(ns.size()) +
                                    " times");
    }
    if (!(q > 0.0 && q <= 1.0)) {
        throw std::invalid_argument("tailWork: the quantile must be in (0, 1] (got " +
                                    std::to_string(q) + ")");
    }
    TailWork w;
    if (ns.empty()) {
        return w;
    }
    std::vector<double> sorted = ns;
    std::sort(sorted.begin(), sorted.end());
    const double cut = quantileOfSorted(sorted, q);
    for (std::size_t i = 0; i < ns.size(); ++i) {
        if (ns[i] >= cut) {
            const TickCounts& c = counts[i];
            ++w.ticks;
            w.solvedAgain += c.solves > 1 ? 1.0 : 0.0;
            w.solves += c.solves;
            w.passes += c.passes;
            w.candidates += c.candidates;
            w.extraLeaves += c.extraLeaves;
        }
    }
    const double n = static_cast<double>(w.ticks);
    w.solvedAgain /= n;
    w.solves /= n;
    w.passes /= n;
    w.candidates /= n;
    w.extraLeaves /= n;
    return w;
}

} // namespace hapto::experiments
