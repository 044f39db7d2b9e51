// `hapto demo grasp`: two simulated hands pick up, carry and put down an object, on the wall
// clock or (--stepped) on the step mode's.

#include "Commands.h"
#include "LiveView.h"
#include "Options.h"
#include "SessionChecks.h"
#include "StopSignals.h"

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/index/Cursor.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/runtime/GraspController.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/Session.h"
#include "hapto/scenes/Generators.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>

namespace hapto::cli {
namespace {

struct DemoArgs {
    std::string scene;
    std::string devices;
    std::string report;
    std::string index; ///< Empty: defaultIndexSpec(scene).
    std::uint64_t maxIndexMb = IndexSpec::kDefaultMaxMegabytes;
    ObjectId object = 0;
    bool realtime = false;
    bool stepped = false; ///< --stepped: the session runs on the step mode's clock.
    ViewArgs view;
};

// Two simulated hands for the grasp scene: left starts at the -x side, right at the +x side,
// both above the floor, in clear space.
std::vector<DeviceConfig> graspHands(ObjectId object) {
    std::vector<DeviceConfig> hands(2);
    const char* names[2] = {"left", "right"};
    const HandScript scripts[2] = {HandScript::GraspLeft, HandScript::GraspRight};
    const Vec3 starts[2] = {Vec3(-0.12, -0.04, 0.0), Vec3(0.04, -0.04, 0.0)};
    for (int i = 0; i < 2; ++i) {
        hands[i].name = names[i];
        hands[i].kind = DeviceKind::Sim;
        hands[i].transform.translation = starts[i];
        SimConfig sim;
        sim.script = scripts[i];
        sim.seed = static_cast<std::uint64_t>(i + 1);
        sim.object = object;
        sim.pressForceN = 2.0;
        hands[i].params = sim;
    }
    return hands;
}

// --stepped runs only devices whose time the session gives them: simulated hands and replays
// (a Falcon or PHANToM would be read as fast as the machine goes, not at its rate).
void checkSteppable(const std::vector<DeviceConfig>& configs) {
    for (const DeviceConfig& c : configs) {
        if (!runsOnStepClock(c.kind)) {
            throw InputError("--stepped: device '" + c.name + "' is a " +
                             std::string(name(c.kind)) +
                             "; only simulated hands (sim) and replays run on the step clock");
        }
    }
}

// Per device: what the hand felt while the object was held.
struct Felt {
    double maxForceN = 0;
    double squeezeSumN = 0; // force along the grasp axis, into the object
    double verticalSumN = 0;
    std::uint64_t samples = 0;
};

// While the object is held: what each hand feels, the grasp axis from left to right.
void feel(const Runtime& runtime, Felt (&felt)[2]) {
    ContactReport c[2];
    if (!runtime.lastTick(0, c[0]) || !runtime.lastTick(1, c[1])) {
        return;
    }
    const Vec3 axis = glm::normalize(c[1].devicePoint - c[0].devicePoint);
    for (int i = 0; i < 2; ++i) {
        const double sign = i == 0 ? -1.0 : 1.0; // left is pushed to -axis
        felt[i].maxForceN = std::max(felt[i].maxForceN, glm::length(c[i].force));
        felt[i].squeezeSumN += sign * glm::dot(c[i].force, axis);
        felt[i].verticalSumN += c[i].force.y;
        ++felt[i].samples;
    }
}

// After the session: where the object ended, whether the rebuilt index finds it there, what
// each hand felt, the force each device was left with; the JSON report when asked for.
void reportDemo(const DemoArgs& a, const Scene& scene, const World& world, const Runtime& runtime,
                const GraspController& grasp, const Felt (&felt)[2], const Vec3& startPosition) {
    const Vec3 endPosition =
        world.current().scene->object(*world.current().scene->slotOf(a.object)).center;
    const RunReport r = runtime.report();
    std::printf("grasped %zu time(s), %llu control steps; object moved (%.3f, %.3f, %.3f) m to "
                "(%.3f, %.3f, %.3f) m; back in the index: %s\n",
                grasp.graspStarts().size(), static_cast<unsigned long long>(grasp.graspedSteps()),
                endPosition.x - startPosition.x, endPosition.y - startPosition.y,
                endPosition.z - startPosition.z, endPosition.x, endPosition.y, endPosition.z,
                world.isMoving(a.object) ? "no" : "yes");
    // Ask the rebuilt index: the object must be found where it is now, not where it was. A box
    // or sphere is asked at its centre (its own item spans it); a mesh, indexed by its
    // triangles only, at the centroid of its first triangle: the leaf holding a closed mesh's
    // centre (or a torus's hole) need hold none of its triangles.
    Vec3 probe(0.0); // in the object's own frame
    if (const SceneObject& o = scene.object(*scene.slotOf(a.object));
        o.shape == Shape::Mesh && o.mesh) {
        const auto c = o.mesh->corners(0);
        probe = (c[0] + c[1] + c[2]) / 3.0;
    }
    const auto probeOf = [&](const Scene& s) {
        const SceneObject& o = s.object(*s.slotOf(a.object));
        return o.center + o.rotation * probe;
    };
    const auto foundAt = [&](const Vec3& p) {
        const WorldSnapshot& s = world.current();
        Cursor cursor(*s.index);
        const std::uint32_t slot = *s.scene->slotOf(a.object);
        const LocateResult r = cursor.locate(p);
        // A mesh is indexed by its triangles: any of them names it.
        return std::any_of(r.candidates.begin(), r.candidates.end(),
                           [&](std::uint32_t item) { return s.scene->objectSlotOf(item) == slot; });
    };
    const bool foundNew = foundAt(probeOf(*world.current().scene));
    const bool moved = glm::length(endPosition - startPosition) > 1e-6;
    const bool foundOld = moved ? foundAt(probeOf(scene)) : foundNew; // one place if it stayed
    if (moved) {
        std::printf("weight %.3f N (%.1f g); the index finds it at its new place: %s, at its "
                    "old place: %s\n",
                    grasp.massKg() * 9.81, grasp.massKg() * 1000, foundNew ? "yes" : "no",
                    foundOld ? "yes" : "no");
    } else {
        std::printf("weight %.3f N (%.1f g); it did not move; the index finds it there: %s\n",
                    grasp.massKg() * 9.81, grasp.massKg() * 1000, foundNew ? "yes" : "no");
    }
    // The force each device was last sent (N): runtime.stop() commands zero to every one.
    double endForceN[2] = {0.0, 0.0};
    for (int i = 0; i < 2; ++i) {
        ContactReport last;
        if (runtime.lastTick(i, last)) {
            endForceN[i] = glm::length(last.force);
        }
    }
    std::printf("force at the end: %s %.3f N, %s %.3f N\n", r.devices[0].name.c_str(), endForceN[0],
                r.devices[1].name.c_str(), endForceN[1]);
    nlohmann::json devicesJson = nlohmann::json::array();
    for (int i = 0; i < 2; ++i) {
        const DeviceReport& d = r.devices[i];
        const double n = static_cast<double>(std::max<std::uint64_t>(1, felt[i].samples));
        std::printf("  %-6s squeeze %.2f N, vertical %.2f N while held, max |F| %.2f N; load "
                    "p50 %.1f%% p99.9 %.1f%%, %s\n",
                    d.name.c_str(), felt[i].squeezeSumN / n, felt[i].verticalSumN / n,
                    felt[i].maxForceN, 100 * d.loadFraction.p50, 100 * d.loadFraction.p999,
                    d.fault.empty() ? (d.stable ? "stable" : "UNSTABLE") : d.fault.c_str());
        if (const std::string note = lateWakeupNote(d); !note.empty()) {
            std::printf("         %s\n", wrapText(note, kTextWidth - 9, 9).c_str());
        }
        devicesJson.push_back({{"name", d.name},
                               {"ticks", d.ticks},
                               {"squeeze_mean_n", felt[i].squeezeSumN / n},
                               {"vertical_mean_n", felt[i].verticalSumN / n},
                               {"max_force_n", felt[i].maxForceN},
                               {"load",
                                {{"p50", d.loadFraction.p50},
                                 {"p999", d.loadFraction.p999},
                                 {"max", d.loadFraction.max}}},
                               {"stable", d.stable},
                               {"fault", d.fault},
                               {"end_force_n", endForceN[i]}});
    }
    if (!a.report.empty()) {
        nlohmann::json path = nlohmann::json::array();
        for (const GraspPathPoint& p : grasp.path()) {
            path.push_back({{"t_s", p.timeS},
                            {"state", p.state == GraspState::Grasped   ? "grasped"
                                      : p.state == GraspState::Falling ? "falling"
                                                                       : "rest"},
                            {"position", {p.position.x, p.position.y, p.position.z}}});
        }
        const nlohmann::json report{
            {"object_id", a.object},
            {"clock", a.stepped ? "stepped" : "wall"},
            {"grasped_ticks", grasp.graspedSteps()},
            {"grasp_starts_s", grasp.graspStarts()},
            {"grasp_ends_s", grasp.graspEnds()},
            {"start_position", {startPosition.x, startPosition.y, startPosition.z}},
            {"end_position", {endPosition.x, endPosition.y, endPosition.z}},
            {"mass_kg", grasp.massKg()},
            {"back_in_index", !world.isMoving(a.object)},
            {"index_finds_it_at_end", foundNew},
            {"index_finds_it_at_start", foundOld},
            {"path", path},
            {"devices", devicesJson}};
        writeFileAtomically(a.report, report.dump(2) + "\n");
        std::printf("report written to %s\n", a.report.c_str());
    }
}

int runDemo(const DemoArgs& a) {
    StopSignals signals; // before any thread starts; see `hapto run`
    DeviceFile file =
        a.devices.empty() ? DeviceFile{graspHands(a.object), {}} : loadDeviceFile(a.devices);
    std::vector<DeviceConfig>& configs = file.devices;
    if (configs.size() != 2) {
        throw InputError(a.devices +
                         ": the grasp demo takes exactly two devices (left, right), got " +
                         std::to_string(configs.size()));
    }
    useTraceSettings(configs);
    if (a.stepped) {
        checkSteppable(configs);
    }
    checkSessionFiles({a.scene, a.devices, a.report, ""}, configs); // before the scene loads
    // One copy of the scene: the world's first snapshot shares it with the hands and the view.
    const auto shared = std::make_shared<const Scene>(
        a.scene.empty() ? makeGraspScene() : loadSceneOrDefault(a.scene));
    const Scene& scene = *shared;
    if (!scene.slotOf(a.object)) {
        throw InputError("--object: the scene has no object with id " + std::to_string(a.object));
    }
    ManualClock clock; // --stepped: the session's time, for the world and the runtime
    World world(shared, sessionIndexSpec(a.index, scene, a.maxIndexMb));
    if (a.stepped) {
        world.useClock(clock);
    }
    signals.endStartUp(); // a signal from now on stops the demo in order
    std::vector<RuntimeDevice> devices;
    std::vector<SimDevice*> sims;
    for (std::size_t i = 0; i < configs.size(); ++i) {
        const DeviceConfig& c = configs[i];
        RuntimeDevice rd{makeDevice(c, scene), c, nullptr, file.renderingOf(i)};
        sims.push_back(dynamic_cast<SimDevice*>(rd.device.get()));
        devices.push_back(std::move(rd));
    }
    RuntimeOptions options;
    options.realtime = a.realtime;
    Runtime runtime(world, std::move(devices), options);
    GraspController grasp(world, runtime, 0, 1);
    if (!a.stepped) { // stepped, this thread never blocks: it sees the first signal
        signals.onSecondSignal([&runtime] { runtime.emergencyStop(); });
    }
    LiveView view(a.view, "hapto demo grasp", scene, runtime);

    const Vec3 startPosition = scene.object(*scene.slotOf(a.object)).center;
    std::printf(
        "hapto demo grasp: object %u at (%.3f, %.3f, %.3f) m, %u objects, devices %s + %s\n",
        a.object, startPosition.x, startPosition.y, startPosition.z, scene.size(),
        configs[0].name.c_str(), configs[1].name.c_str());
    // A control step every millisecond: on the wall clock it sleeps while the servo threads run
    // on their own; stepped (--stepped), it first runs the servo ticks due in its millisecond
    // on this thread, so the session's outcome is the same every run however busy the machine
    // is.
    SessionOptions control;
    control.controlPeriodNs = 1'000'000;
    control.steppedClock = a.stepped ? &clock : nullptr;
    control.stopRequested = [&signals] { return signals.requested(); };
    Session session(runtime, std::move(control));
    if (session.start() != 2) {
        session.stop();
        throw std::runtime_error(
            "a device could not be opened: " + runtime.report().devices[0].fault + " " +
            runtime.report().devices[1].fault);
    }

    view.start();
    // Until both scripts are done (simulated hands) or 12 s of session time, plus a second to
    // settle.
    Felt felt[2];
    GraspState last = GraspState::Idle;
    session.run([&](double t) {
        grasp.step(0.001);
        view.update(world);
        if (grasp.state() != last) {
            const auto& p = grasp.path().back();
            std::printf("  %6.3f s  %-8s object at (%.3f, %.3f, %.3f) m\n", p.timeS,
                        grasp.state() == GraspState::Grasped   ? "grasped"
                        : grasp.state() == GraspState::Falling ? "released"
                                                               : "at rest",
                        p.position.x, p.position.y, p.position.z);
            last = grasp.state();
        }
        if (grasp.state() == GraspState::Grasped) {
            feel(runtime, felt);
        }
        // The servo threads own the scripts: read the phase they publish.
        const bool scriptsDone = sims[0] && sims[1] &&
                                 sims[0]->publishedPhase() == ScriptPhase::Done &&
                                 sims[1]->publishedPhase() == ScriptPhase::Done;
        return !((scriptsDone && grasp.state() == GraspState::Idle && t > 1.0) || t > 12.0);
    });
    session.stop();
    view.stop();
    world.setRestDelay(std::chrono::nanoseconds(0));
    world.settle();

    reportDemo(a, scene, world, runtime, grasp, felt, startPosition);
    return 0;
}

} // namespace

void addDemoCommands(CLI::App& app) {
    auto* demo = app.add_subcommand("demo", "Scripted demonstrations");
    demo->require_subcommand(1);
    setExamples(demo, {"hapto demo grasp --view"});
    auto* cmd = demo->add_subcommand(
        "grasp", "Two simulated hands approach an object from both sides, squeeze, lift it 5 cm, "
                 "carry it 10 cm sideways, put it down and let go (about 9 s)");
    auto a = std::make_shared<DemoArgs>();
    cmd->add_option("--scene", a->scene, "Scene file (default: the built-in grasp scene, y up)");
    cmd->add_option("--devices", a->devices,
                    "Two-device configuration (default: simulated hands with the grasp-left / "
                    "grasp-right scripts)");
    cmd->add_option("--object", a->object, "Id of the object to grasp")
        ->capture_default_str()
        ->check(finiteRange(0, kMaxObjectId));
    addIndexOption(cmd, a->index);
    addMaxIndexMbOption(cmd, a->maxIndexMb);
    cmd->add_option("--report", a->report, "Write a JSON report here");
    addRealtimeFlag(cmd, a->realtime, "the demo shares the machine");
    addViewOptions(cmd, a->view);
    cmd->add_flag("--stepped", a->stepped,
                  "Run the session on the step mode's clock, not the wall clock: the servo ticks "
                  "and the control loop take turns on one thread, a millisecond of session time "
                  "at a time, as fast as the machine goes, so every run gives the same result "
                  "however busy the machine is (simulated hands and replays only; not with "
                  "--realtime)");
    setExamples(cmd, {"hapto demo grasp --view",
                      "hapto demo grasp --scene grasp.json --object 3 --report grasp.json",
                      "hapto demo grasp --stepped --report grasp.json"});
    cmd->callback([a] {
        if (a->stepped && a->realtime) {
            throw InputError("--stepped runs the session on this thread, not on real-time servo "
                             "threads: give --stepped or --realtime, not both");
        }
        runDemo(*a);
    });
}

} // namespace hapto::cli
