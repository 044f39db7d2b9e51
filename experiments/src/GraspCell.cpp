// One cell of `hapto experiment grasp`: the scene, the two hands, the stepped session and its
// measurement (design note in GraspCell.h).

#include "hapto/experiments/GraspCell.h"

#include "hapto/core/Clock.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/devices/SimScript.h"
#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/experiments/Table.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/MassProperties.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace hapto::experiments {
namespace {

constexpr ObjectId kFloorId = 1;
constexpr ObjectId kBoxId = 2;
constexpr double kHandStartGapM = 0.05; // each hand starts this far outside the box's side (m)
constexpr double kSlipOnsetM = 0.001;   // slip onset: issue 37's 1 mm bound for a held body

/// A simulated hand that notes the stepping thread's CPU time at its read() when `stamp` is
/// 0 (the first read after the driver cleared it). Forwards everything to a SimDevice.
class StampedHand final : public Device {
public:
    StampedHand(const DeviceConfig& config, const Scene& scene, std::uint64_t& stamp)
        : mSim(config, scene), mStamp(stamp) {}
    std::string_view name() const override { return mSim.name(); }
    DeviceKind kind() const override { return mSim.kind(); }
    DeviceCapabilities capabilities() const override { return mSim.capabilities(); }
    DeviceStatus open() override { return mSim.open(); }
    void close() override { mSim.close(); }
    DeviceStatus read(DeviceState& state) noexcept override {
        if (mStamp == 0) {
            mStamp = threadCpuNs();
        }
        return mSim.read(state);
    }
    DeviceStatus write(const Vec3& forceN) noexcept override { return mSim.write(forceN); }
    void periodsSkipped(std::uint64_t periods) noexcept override { mSim.periodsSkipped(periods); }
    std::string errorMessage() const override { return mSim.errorMessage(); }

private:
    SimDevice mSim;
    std::uint64_t& mStamp;
};

/// The floor (static, top at y = 0) and the box resting on it.
Scene graspScene(const GraspCellSpec& spec) {
    Material m;
    m.stiffness = spec.stiffnessNPerM;
    m.staticFriction = spec.staticFriction;
    m.dynamicFriction = spec.dynamicFriction;
    std::vector<SceneObject> objects;
    objects.push_back(
        makeBox(kFloorId, Vec3(0.0, -0.01, 0.0), Vec3(0.25, 0.01, 0.15), Quat(1, 0, 0, 0), m));
    const double h = spec.halfExtentM;
    SceneObject box = makeBox(kBoxId, Vec3(0.0, h, 0.0), Vec3(h), Quat(1, 0, 0, 0), m);
    box.body.dynamic = true;
    fillMassProperties(box, spec.massKg, std::nullopt, std::nullopt);
    objects.push_back(std::move(box));
    Scene scene(Aabb{Vec3(-0.3, -0.05, -0.2), Vec3(0.3, 0.3, 0.2)}, std::move(objects));
    ScenePhysics physics;
    physics.rateHz = spec.dynamicsRateHz;
    scene.setPhysics(physics);
    return scene;
}

DeviceConfig graspHand(const GraspCellSpec& spec, int side) {
    const double x = side * (spec.halfExtentM + kHandStartGapM);
    DeviceConfig c = simHand(side < 0 ? "left" : "right", spec.servoRateHz,
                             side < 0 ? "grasp-left" : "grasp-right",
                             spec.seed + (side < 0 ? 0u : 1u), Vec3(x, spec.halfExtentM, 0.0));
    SimConfig& sim = std::get<SimConfig>(c.params);
    sim.object = kBoxId;
    sim.pressForceN = spec.squeezeN;
    return c;
}

std::uint64_t periodNs(double rateHz) {
    return static_cast<std::uint64_t>(std::llround(1e9 / rateHz));
}

/// The stepped session: clock, world, runtime, the CPU stamp the hands write.
struct GraspRig {
    ManualClock clock;
    World world;
    std::uint64_t stamp = 0;
    std::unique_ptr<Runtime> runtime;

    GraspRig(const GraspCellSpec& spec, Scene scene)
        : world(std::move(scene), IndexSpec::parse(kDefaultIndexSpec)) {
        world.useClock(clock);
        const Scene& planScene = *world.current().scene;
        std::vector<RuntimeDevice> devices;
        for (const int side : {-1, 1}) {
            const DeviceConfig c = graspHand(spec, side);
            devices.push_back({std::make_unique<StampedHand>(c, planScene, stamp), c, nullptr});
        }
        RuntimeOptions options;
        options.realtime = false;
        runtime = std::make_unique<Runtime>(world, std::move(devices), options);
    }
};

/// The two windows: slip from the squeeze's end, the force while lifted (from the lift's end).
struct Probes {
    GraspProbe slip;
    GraspProbe force;
};

/// Feeds the probe; returns the squeeze (N) of the sample that began its window, else none.
std::optional<double> sample(const Runtime& rt, GraspProbe& probe) {
    if (const std::optional<GraspSample> s = graspSampleOf(rt, 0, 0, 1)) {
        if (!probe.begun()) {
            probe.begin(*s);
            return 0.5 * (s->forceBN.x - s->forceAN.x); // left (A) is pushed to -x, right to +x
        } else {
            probe.add(*s);
        }
    }
    return std::nullopt;
}

/// Drives the rig to kCarryEnd, measuring; fills `result` but the report's figures.
void drive(GraspRig& rig, const GraspCellSpec& spec, Probes& probes, GraspCellResult& result) {
    Runtime& rt = *rig.runtime;
    const std::uint64_t t0 = rig.clock.nowNs();
    const std::uint64_t inc = std::min(periodNs(spec.servoRateHz), periodNs(spec.dynamicsRateHz));
    const auto at = [&](double s) {
        return t0 + static_cast<std::uint64_t>(std::llround(s * 1e9));
    };
    const std::uint64_t begin = at(GraspTimes::kSqueezeEnd), lifted = at(GraspTimes::kLiftEnd);
    const std::uint64_t end = at(GraspTimes::kCarryEnd);
    const std::uint64_t maintainNs = 5'000'000;
    std::uint64_t nextMaintain = t0 + maintainNs;
    for (std::uint64_t t = t0 + inc; t <= end; t += inc) {
        const std::uint64_t dynamicsDue = rt.nextDynamicsDeadlineNs();
        rig.stamp = 0;
        const std::uint64_t c0 = threadCpuNs();
        rt.runUntil(t);
        if (dynamicsDue > t) {
            continue; // no step in this increment
        }
        const std::uint64_t c1 = rig.stamp != 0 ? rig.stamp : threadCpuNs();
        result.stepCpuNs.push_back(static_cast<double>(c1 - c0));
        if (t >= nextMaintain) {
            rt.maintain();
            nextMaintain += maintainNs;
        }
        if (t >= begin) {
            if (const std::optional<double> squeeze = sample(rt, probes.slip)) {
                result.squeezeFeltN = *squeeze;
            }
            if (result.slipOnsetS < 0.0 && probes.slip.maxSlipM() > kSlipOnsetM) {
                result.slipOnsetS = static_cast<double>(t - t0) * 1e-9;
            }
        }
        if (t >= lifted) {
            (void)sample(rt, probes.force);
        }
    }
}

void checkPositive(double v, const char* what) {
    if (!std::isfinite(v) || !(v > 0.0)) {
        throw std::invalid_argument(std::string("grasp cell: ") + what +
                                    " must be finite and > 0, got " + csvNumber(v));
    }
}

} // namespace

void checkGraspCellSpec(const GraspCellSpec& spec) {
    if (!std::isfinite(spec.squeezeN) || spec.squeezeN < 0.0) {
        throw std::invalid_argument("grasp cell: squeeze_n must be finite and >= 0, got " +
                                    csvNumber(spec.squeezeN));
    }
    checkPositive(spec.massKg, "mass_kg");
    checkPositive(spec.stiffnessNPerM, "stiffness_n_per_m");
    checkPositive(spec.servoRateHz, "servo_rate_hz");
    checkPositive(spec.dynamicsRateHz, "dynamics_rate_hz");
    checkPositive(spec.staticFriction, "static_friction");
    checkPositive(spec.dynamicFriction, "dynamic_friction");
    checkPositive(spec.halfExtentM, "half_extent_m");
    const double ps = 1e9 / spec.servoRateHz, pd = 1e9 / spec.dynamicsRateHz;
    const double inc = std::min(ps, pd);
    for (const double p : {ps, pd}) {
        if (p != std::round(p) || std::fmod(p, std::round(inc)) != 0.0) {
            throw std::invalid_argument(
                "grasp cell: the servo and dynamics periods must be whole nanoseconds and "
                "multiples of the shorter (e.g. 500, 1000, 2000, 4000, 8000 Hz), got " +
                csvNumber(spec.servoRateHz) + " and " + csvNumber(spec.dynamicsRateHz) + " Hz");
        }
    }
}

double graspElasticSlipM(const GraspCellSpec& spec, double gravityMPerS2) {
    return spec.massKg * gravityMPerS2 / (2.0 * spec.stiffnessNPerM);
}

double graspHoldMargin(const GraspCellSpec& spec, double gravityMPerS2) {
    return spec.staticFriction * 2.0 * spec.squeezeN / (spec.massKg * gravityMPerS2);
}

GraspCellResult runGraspCell(const GraspCellSpec& spec) {
    checkGraspCellSpec(spec);
    GraspRig rig(spec, graspScene(spec));
    Runtime& rt = *rig.runtime;
    if (rt.startStepped(rig.clock) != 2) {
        throw std::runtime_error("grasp cell: a simulated hand did not open");
    }
    GraspProbeSettings ps;
    ps.massKg = spec.massKg;
    ps.gravityMPerS2 = 9.81; // ScenePhysics' default gravity, the scene's
    Probes probes{GraspProbe(ps), GraspProbe(ps)};
    GraspCellResult result;
    drive(rig, spec, probes, result);
    result.grasp = probes.slip.figures();
    const GraspFigures force = probes.force.figures();
    result.grasp.forceErrorMedian = force.forceErrorMedian;
    result.grasp.forceErrorWorst = force.forceErrorWorst;
    result.liftM = rt.bodyPoses()->read(0).centerOfMass.y - spec.halfExtentM;
    rt.stop();
    const RunReport report = rt.report();
    if (report.dynamics && !report.dynamics->bodies.empty()) {
        result.deepestPenetrationM = report.dynamics->bodies[0].deepestPenetrationM;
        result.largestEnergyGainJ = report.dynamics->bodies[0].largestEnergyGainJ;
        result.dynamicsSteps = report.dynamics->steps;
    }
    result.stable = report.stable;
    for (const DeviceReport& d : report.devices) {
        result.zeroedForMisses += d.zeroedForMisses;
    }
    return result;
}

bool sameGraspFigures(const GraspCellResult& a, const GraspCellResult& b) {
    const GraspFigures &x = a.grasp, &y = b.grasp;
    return x.maxSlipM == y.maxSlipM && x.finalSlipM == y.finalSlipM &&
           x.forceErrorMedian == y.forceErrorMedian && x.forceErrorWorst == y.forceErrorWorst &&
           x.samples == y.samples && x.nonFinite == y.nonFinite && x.held == y.held &&
           a.deepestPenetrationM == b.deepestPenetrationM &&
           a.largestEnergyGainJ == b.largestEnergyGainJ && a.liftM == b.liftM &&
           a.squeezeFeltN == b.squeezeFeltN && a.slipOnsetS == b.slipOnsetS &&
           a.dynamicsSteps == b.dynamicsSteps && a.stable == b.stable &&
           a.zeroedForMisses == b.zeroedForMisses && a.stepCpuNs.size() == b.stepCpuNs.size();
}

} // namespace hapto::experiments
