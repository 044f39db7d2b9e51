// Timed servo sessions of simulated hands, medians, clear start points and output files.

#include "hapto/experiments/ExperimentSupport.h"

#include "hapto/io/OutputFile.h"

#include "hapto/index/SpatialIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/runtime/ServoStep.h"
#include "hapto/runtime/Session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <sys/utsname.h>
#include <thread>

namespace hapto::experiments {

std::string_view conditionName(Condition condition) {
    switch (condition) {
    case Condition::NoTouch:
        return "no touch";
    case Condition::Touch:
        return "touch";
    case Condition::Sliding:
        return "sliding";
    }
    return "?";
}

std::string_view conditionScript(Condition condition) {
    switch (condition) {
    case Condition::NoTouch:
        return "free";
    case Condition::Touch:
        return "touch";
    case Condition::Sliding:
        return "slide";
    }
    return "free";
}

// ---------------------------------------------------------------------------------------------
// WarmedSimDevice

WarmedSimDevice::WarmedSimDevice(const DeviceConfig& config, const Scene& planScene)
    : mConfig(config), mPlanScene(planScene), mSim(config, planScene) {}

DeviceStatus WarmedSimDevice::open() {
    if (mOpened) {
        return DeviceStatus::Ok;
    }
    const DeviceStatus st = mSim.open();
    mOpened = st == DeviceStatus::Ok;
    return st;
}

DeviceStatus WarmedSimDevice::read(DeviceState& state) noexcept {
    const DeviceStatus st = mSim.read(state);
    if (mPrimePending && st == DeviceStatus::Ok) {
        state.position = mPrimeDevice;
        mPrimePending = false;
    }
    return st;
}

double WarmedSimDevice::warmUp(double settleS, double maxS) {
    if (open() != DeviceStatus::Ok) {
        throw std::runtime_error("simulated hand '" + mConfig.name +
                                 "' did not open: " + mSim.errorMessage());
    }
    const HandScript script = mSim.simConfig().script;
    ScriptPhase measured;
    if (script == HandScript::Touch) {
        measured = ScriptPhase::Hold;
    } else if (script == HandScript::Slide) {
        measured = ScriptPhase::Slide;
    } else {
        return 0.0;
    }
    mReached = false;

    // A small index over the objects the plan passes near: the approach renders exactly as it
    // would against the whole scene (the renderer only ever looks at nearby objects).
    Aabb region = Aabb::empty();
    for (const ScriptKeyframe& k : mSim.script()->keyframes()) {
        region.expand(k.target);
    }
    region.min -= Vec3(0.03);
    region.max += Vec3(0.03);
    std::vector<SceneObject> near;
    for (const SceneObject& o : mPlanScene.objects()) {
        if (o.aabb().overlaps(region)) {
            near.push_back(o);
        }
    }
    // A mesh that reaches into the region brings all its triangles, most of them outside the
    // region's bounds (kept in the index's outside list, 4 B each); the build's memory estimate
    // counts every item as if placed, so at 10^7 triangles it would pass the default 1 GB
    // limit for an index that is in fact small. The limit here is the machine's, not a guard.
    World world(std::make_shared<const Scene>(region, std::move(near)),
                IndexSpec::octree(2, 0.005).withMaxMegabytes(1u << 20));

    // The servo's own step, on time at every deadline of a clock that moves only here.
    ManualClock clock;
    ServoStepShared shared;
    ServoStep step(RendererConfig{}, SafetyConfig{});
    const RuntimeOptions runtime;
    step.setTiming(static_cast<std::uint64_t>(std::llround(1e9 / mConfig.rateHz)),
                   runtime.missLimit, runtime.lateWakeupFraction, runtime.stallTimeoutNs);
    step.device = &mSim;
    step.transform = mConfig.transform; // the gimbal centre (no tool tip): the first reading
                                        // after warm-up puts the device there, at the proxy
    step.reader = world.registerReader();
    step.ports = shared.portsFor(world, &clock);
    step.start(clock.nowNs());
    double inPhaseS = 0.0, t = 0.0;
    for (; t < maxS; t += step.dtS) {
        clock.set(step.deadlineNs);
        if (!step.run(step.deadlineNs)) {
            throw std::runtime_error("simulated hand '" + mConfig.name +
                                     "' failed during warm-up: " + mSim.errorMessage());
        }
        if (mSim.phase() == measured) {
            inPhaseS += step.dtS;
            if (inPhaseS >= settleS) {
                mReached = true;
                break;
            }
        }
    }
    mPrimeDevice = mConfig.transform.positionToDevice(step.haptic.proxy());
    mPrimePending = true;
    world.unregisterReader(step.reader);
    return t;
}

// ---------------------------------------------------------------------------------------------
// Scenes and start points

Scene sceneNear(const Scene& scene, const Aabb& region) {
    std::vector<SceneObject> near;
    for (const SceneObject& o : scene.objects()) {
        if (o.aabb().overlaps(region)) {
            near.push_back(o);
        }
    }
    return Scene(scene.bounds(), std::move(near));
}

void requireClear(const Scene& scene, const Vec3& point, double marginM, std::string_view what) {
    for (const SceneObject& o : scene.objects()) {
        Aabb box = o.aabb();
        box.min -= Vec3(marginM);
        box.max += Vec3(marginM);
        if (o.contains(point) || box.contains(point)) {
            char text[256];
            std::snprintf(text, sizeof text,
                          "%.*s: start (%.4f, %.4f, %.4f) m is within %.1f mm of object %u",
                          static_cast<int>(what.size()), what.data(), point.x, point.y, point.z,
                          marginM * 1e3, o.id);
            throw std::logic_error(text);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Figures

std::string_view tailName(Tail tail) {
    return tail == Tail::P99 ? "p99" : "p99.9";
}

std::string verdictNote(Tail tail) {
    return tail == Tail::P99
               ? "Quick run: verdicts read p99 load, not p99.9 (a run of a few hundred ticks has "
                 "no p99.9 but its maximum, so one preempted tick would decide it)."
               : "Verdicts read p99.9 load.";
}

LoadFigures figuresOf(const DeviceReport& d, Tail tail) {
    LoadFigures f;
    f.tail = tail;
    const double periodNs = 1e9 / d.rateHz;
    f.meanPct = 100.0 * d.loadFraction.mean;
    f.p50Pct = 100.0 * d.loadFraction.p50;
    f.p99Pct = 100.0 * d.loadFraction.p99;
    f.p999Pct = 100.0 * d.loadFraction.p999;
    f.maxPct = 100.0 * d.loadFraction.max;
    f.tickNsP50 = d.loadFraction.p50 * periodNs;
    f.tickNsP999 = d.loadFraction.p999 * periodNs;
    f.tickNsMax = d.loadFraction.max * periodNs;
    f.ticks = static_cast<double>(d.ticks);
    f.missed = static_cast<double>(d.missedDeadlines);
    f.missedPct = d.ticks ? 100.0 * f.missed / f.ticks : 0.0;
    f.lateWakeups = static_cast<double>(d.lateWakeups);
    f.contactPct = d.ticks ? 100.0 * static_cast<double>(d.contactTicks) / f.ticks : 0.0;
    f.candidatesMean = d.candidatesMean;
    f.locateStepsMean = d.locateStepsMean;
    f.lateP999Us = d.latenessNs.p999 / 1e3;
    f.lateMaxUs = d.latenessNs.max / 1e3;
    f.realtime = d.realtime;
    f.fault = d.fault;
    return f;
}

double median(std::vector<double> values) {
    if (values.empty()) {
        return 0.0;
    }
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

LoadFigures medianOf(const std::vector<LoadFigures>& runs) {
    LoadFigures m;
    if (runs.empty()) {
        return m;
    }
    const auto med = [&](double LoadFigures::*field) {
        std::vector<double> v;
        for (const LoadFigures& r : runs) {
            v.push_back(r.*field);
        }
        return median(std::move(v));
    };
    for (double LoadFigures::*field :
         {&LoadFigures::meanPct, &LoadFigures::p50Pct, &LoadFigures::p99Pct, &LoadFigures::p999Pct,
          &LoadFigures::maxPct, &LoadFigures::tickNsP50, &LoadFigures::tickNsP999,
          &LoadFigures::tickNsMax, &LoadFigures::ticks, &LoadFigures::missed,
          &LoadFigures::missedPct, &LoadFigures::lateWakeups, &LoadFigures::contactPct,
          &LoadFigures::candidatesMean, &LoadFigures::locateStepsMean, &LoadFigures::lateP999Us,
          &LoadFigures::lateMaxUs}) {
        m.*field = med(field);
    }
    m.realtime = std::all_of(runs.begin(), runs.end(), [](auto& r) { return r.realtime; });
    m.tail = runs.front().tail;
    for (const LoadFigures& r : runs) {
        if (!r.fault.empty()) {
            m.fault = r.fault;
            break;
        }
    }
    return m;
}

std::string_view verdictName(Verdict verdict) {
    return verdict == Verdict::Design ? "design" : "load";
}

Verdict parseVerdict(const std::string& text, const std::string& option) {
    if (text == "design") {
        return Verdict::Design;
    }
    if (text == "load") {
        return Verdict::Load;
    }
    throw InputError(option + " '" + text +
                     "': expected design (p99.9 load < 100 % and <= 0.1 % deadlines missed) or "
                     "load (p99.9 load < 100 % only)");
}

// ---------------------------------------------------------------------------------------------
// Sessions

DeviceConfig simHand(const std::string& name, double rateHz, std::string_view script,
                     std::uint64_t seed, const Vec3& start) {
    DeviceConfig c;
    c.name = name;
    c.kind = DeviceKind::Sim;
    c.rateHz = rateHz;
    SimConfig sim;
    sim.script = parseHandScript(script).value(); // callers pass a known script
    sim.seed = seed;
    sim.start = start;
    c.params = sim;
    return c;
}

SessionResult runSession(World& world, const std::vector<HandPlan>& hands,
                         const ServoSettings& settings) {
    SessionResult result;
    std::vector<RuntimeDevice> devices;
    for (const HandPlan& h : hands) {
        auto device = std::make_unique<WarmedSimDevice>(h.config, *h.planScene);
        device->warmUp(settings.warmupSettleS);
        result.reached.push_back(device->reachedPhase());
        devices.push_back(RuntimeDevice{std::move(device), h.config, nullptr});
    }
    RuntimeOptions options;
    options.realtime = settings.realtime;
    options.reopenAfterNs = 0; // a fault spoils the measurement: the cell reports it
    Runtime runtime(world, std::move(devices), options);
    SessionOptions timed;
    timed.durationS = settings.durationS;
    Session session(runtime, timed);
    if (session.start() > 0 && settings.durationS > 0) { // 0: no limit to the driver
        session.run();
    }
    result.report = session.stop();
    return result;
}

namespace {

/// The tick probe's device: held at one point (with a 10 µm jitter over three readings, so the
/// tick is not the same every time) at rest; the force is dropped.
class ProbePointDevice final : public Device {
public:
    explicit ProbePointDevice(const Vec3& point) : mPoint(point) {}
    std::string_view name() const override { return "probe"; }
    DeviceKind kind() const override { return DeviceKind::Scripted; }
    DeviceCapabilities capabilities() const override { return {}; }
    DeviceStatus open() override { return DeviceStatus::Ok; }
    void close() override {}
    DeviceStatus read(DeviceState& state) noexcept override {
        const int i = mReads++;
        state.position = mPoint + Vec3(1e-5 * (i % 3), 1e-5 * ((i + 1) % 3), 0.0);
        state.velocity = Vec3(0.0);
        state.hasVelocity = true;
        return DeviceStatus::Ok;
    }
    DeviceStatus write(const Vec3&) noexcept override { return DeviceStatus::Ok; }
    std::string errorMessage() const override { return {}; }

private:
    Vec3 mPoint;
    int mReads = 0;
};

} // namespace

double probeTickSeconds(World& world, const Vec3& point, int runs) {
    // The servo's own step at 1 kHz, on time at every deadline of a clock that moves only here.
    ProbePointDevice device(point);
    ManualClock clock;
    ServoStepShared shared;
    ServoStep step(RendererConfig{}, SafetyConfig{});
    const RuntimeOptions runtime;
    step.setTiming(1'000'000, runtime.missLimit, runtime.lateWakeupFraction,
                   runtime.stallTimeoutNs);
    step.device = &device;
    step.reader = world.registerReader();
    step.ports = shared.portsFor(world, &clock);
    step.start(clock.nowNs());
    std::vector<double> seconds;
    for (int i = 0; i < runs; ++i) {
        clock.set(step.deadlineNs);
        const auto t0 = std::chrono::steady_clock::now();
        const bool ticked = step.run(step.deadlineNs);
        const auto t1 = std::chrono::steady_clock::now();
        if (!ticked) {
            break; // a non-finite point: what ran is the probe
        }
        seconds.push_back(std::chrono::duration<double>(t1 - t0).count());
    }
    world.unregisterReader(step.reader);
    return median(std::move(seconds));
}

// ---------------------------------------------------------------------------------------------
// Files and text

std::filesystem::path prepareOutDir(const std::string& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir)) {
        throw InputError("--out '" + dir + "': cannot create this folder (" + ec.message() +
                         "); pass a writable folder");
    }
    return std::filesystem::path(dir);
}

void writeText(const std::filesystem::path& path, const std::string& text) {
    writeFileAtomically(path, text);
}

std::string fmt(double value, int decimals) {
    char text[64];
    std::snprintf(text, sizeof text, "%.*f", decimals, value);
    return text;
}

std::string markdownTable(const std::vector<std::string>& header,
                          const std::vector<std::vector<std::string>>& rows) {
    std::vector<std::size_t> width(header.size(), 3);
    for (std::size_t i = 0; i < header.size(); ++i) {
        width[i] = std::max(width[i], header[i].size());
    }
    for (const auto& r : rows) {
        for (std::size_t i = 0; i < r.size() && i < width.size(); ++i) {
            width[i] = std::max(width[i], r[i].size());
        }
    }
    std::string out;
    const auto line = [&](const std::vector<std::string>& cells) {
        out += "|";
        for (std::size_t i = 0; i < width.size(); ++i) {
            const std::string cell = i < cells.size() ? cells[i] : "";
            out += " " + cell + std::string(width[i] - cell.size(), ' ') + " |";
        }
        out += "\n";
    };
    line(header);
    out += "|";
    for (const std::size_t w : width) {
        out += std::string(w + 2, '-') + "|";
    }
    out += "\n";
    for (const auto& r : rows) {
        line(r);
    }
    return out;
}

Json machineJson() {
    Json m;
    std::ifstream cpu("/proc/cpuinfo");
    std::string line;
    while (std::getline(cpu, line)) {
        if (line.rfind("model name", 0) == 0) {
            const std::size_t colon = line.find(':');
            m["cpu"] = colon == std::string::npos ? line : line.substr(colon + 2);
            break;
        }
    }
    m["hardware_threads"] = std::max(1u, std::thread::hardware_concurrency());
    std::ifstream loadavg("/proc/loadavg");
    double l1 = 0, l5 = 0, l15 = 0;
    if (loadavg >> l1 >> l5 >> l15) {
        m["load_average_1_5_15"] = {l1, l5, l15};
    }
    utsname u{};
    if (uname(&u) == 0) {
        m["kernel"] = std::string(u.sysname) + " " + u.release;
    }
    return m;
}

} // namespace hapto::experiments
