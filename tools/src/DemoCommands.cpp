// `hapto demo grasp`: two simulated hands pick up, carry and put down an object, on the wall
// clock or (--stepped) on the step mode's.
//
// Design note. Two modes share the session (devices, world, runtime, view, recorders):
//   - physical (the default): the object is a dynamic body (scene format 3). Nothing here moves
//     it: the hands' grasp scripts squeeze it (press_n), the servo ticks hand the reaction of
//     their contact forces back to it, and the dynamics thread lifts it by friction alone,
//     carries it, sets it down on what is under it (the built-in scene's plinth), grasps it
//     again, lifts it GraspTimes::kDropHeightM and opens, so it falls and comes to rest. This
//     file only measures (PhysicalGrasp): the slip of the body relative to the hands' midpoint
//     while held, each hand's squeeze and the hands' vertical sum against m g over the carry
//     (no vertical acceleration there, so Newton's second law says they are equal), where it was
//     set down and where it rests, on what and how far above its top, and the dynamics' own
//     deepest penetration and energy gain (RunReport::dynamics).
//   - --kinematic: today's GraspController on a static object (it snaps the object to the
//     hands' midpoint and injects the weight), kept for side-by-side runs.
// Invariant: both modes end with runtime stop, which commands zero force to every device.

#include "Commands.h"
#include "LiveView.h"
#include "Options.h"
#include "SessionChecks.h"
#include "SessionRecorders.h"
#include "StopSignals.h"

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/experiments/GraspProbe.h"
#include "hapto/index/Cursor.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/runtime/GraspController.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/Session.h"
#include "hapto/scenes/Generators.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>

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
    bool stepped = false;   ///< --stepped: the session runs on the step mode's clock.
    bool kinematic = false; ///< --kinematic: the GraspController on a static object.
    std::string shape;      ///< --shape: the built-in physical scene's object ("" = box).
    std::string record;     ///< --record DIR: the devices' and the bodies' traces.
    ViewArgs view;
};

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

// Each device: what it felt while the object was held (`felt`), its load and verdict, and the
// force it was last sent (runtime.stop() commands zero to every one); printed, and as JSON.
nlohmann::json reportDevices(const RunReport& r, const Runtime& runtime, const Felt (&felt)[2]) {
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
    return devicesJson;
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
    const nlohmann::json devicesJson = reportDevices(r, runtime, felt);
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

// Where a body is: its centre of mass, its lowest point (y, m), the object under it (the
// highest whose top is at most 5 mm above that point, under the centre of mass) and the gap
// from that top to the lowest point (m; < 0: sunk in).
struct Placement {
    Vec3 centerOfMass{0.0};
    double lowestY = 0.0;
    std::optional<ObjectId> support;
    double gapM = 0.0;
};

// The lowest point of object `o` placed at `pose` (y, m): a box's lowest corner, a sphere's
// bottom, a mesh's lowest vertex.
double lowestY(const SceneObject& o, const BodyPose& pose) {
    if (o.shape == Shape::Sphere) {
        return pose.center.y - o.halfExtents.x;
    }
    double lowest = pose.center.y;
    const auto take = [&](const Vec3& local) {
        lowest = std::min(lowest, (pose.center + pose.rotation * local).y);
    };
    if (o.shape == Shape::Mesh && o.mesh) {
        for (const Vec3& v : o.mesh->vertices()) {
            take(v);
        }
        return lowest;
    }
    for (int c = 0; c < 8; ++c) {
        take(o.halfExtents * Vec3(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : -1));
    }
    return lowest;
}

Placement placementOf(const Scene& scene, std::uint32_t slot, const BodyPose& pose) {
    Placement p;
    p.centerOfMass = pose.centerOfMass;
    p.lowestY = lowestY(scene.object(slot), pose);
    double top = -INFINITY;
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        const Aabb box = scene.object(i).aabb();
        const Vec3& c = pose.centerOfMass;
        if (i != slot && c.x >= box.min.x && c.x <= box.max.x && c.z >= box.min.z &&
            c.z <= box.max.z && box.max.y <= p.lowestY + 0.005 && box.max.y > top) {
            top = box.max.y;
            p.support = scene.object(i).id;
        }
    }
    p.gapM = p.support ? p.lowestY - top : 0.0;
    return p;
}

// What the physical grasp achieved, measured each control step on GraspTimes' timetable.
struct PhysicalGrasp {
    std::uint32_t slot = 0; // the body's scene slot
    std::size_t body = 0;   // its index in the runtime's BodyPoseTable
    double massKg = 0.0;
    double gravity = 9.81; // |g| (m/s^2)
    Placement start, setDown, dropFrom, rest;
    // Held (squeeze end to carry end): slip of the centre of mass against the hands' midpoint.
    experiments::GraspProbe probe{experiments::GraspProbeSettings{}};
    double liftM = 0.0; // highest rise of the centre of mass over its start while held
    // The carry (no vertical acceleration): the hands' vertical support against m g.
    Felt felt[2];
    double supportSumN = 0.0;
    double supportWorstN = 0.0; // largest |support - m g| in one control step
    std::uint64_t carrySamples = 0;
    double restSpeed = 0.0; // |v| at the end (m/s)
    double restSpinRadPerS = 0.0;
    bool dropped = false, setDownTaken = false;

    void observe(double t, const Scene& scene, const Runtime& runtime);
    bool atRest() const { return restSpeed < 1e-3 && restSpinRadPerS < 0.05; }
    // Held: the probe's verdict (final slip <= 10 mm) and lifted with the hands (90 % of 5 cm).
    bool held() const { return probe.figures().held && liftM > 0.9 * 0.05; }
    double maxSlipM() const { return probe.maxSlipM(); }
};

void PhysicalGrasp::observe(double t, const Scene& scene, const Runtime& runtime) {
    using G = GraspTimes;
    const BodyPose pose = runtime.bodyPoses()->read(body);
    ContactReport c[2];
    const bool hands = runtime.lastTick(0, c[0]) && runtime.lastTick(1, c[1]);
    if (hands && t >= G::kSqueezeEnd && t <= G::kCarryEnd) {
        if (const auto sample = experiments::graspSampleOf(runtime, body, 0, 1)) {
            if (!probe.begun()) {
                probe.begin(*sample);
            } else {
                probe.add(*sample);
            }
        }
        liftM = std::max(liftM, pose.centerOfMass.y - start.centerOfMass.y);
    }
    if (hands && t >= G::kLiftEnd + 0.2 && t <= G::kCarryEnd) {
        feel(runtime, felt);
        const double support = -(c[0].force.y + c[1].force.y);
        supportSumN += support;
        supportWorstN = std::max(supportWorstN, std::abs(support - massKg * gravity));
        ++carrySamples;
    }
    if (!setDownTaken && t >= G::kReleaseEnd) {
        setDownTaken = true;
        setDown = placementOf(scene, slot, pose);
        std::printf("  %6.3f s  set down   at (%.3f, %.3f, %.3f) m\n", t, pose.centerOfMass.x,
                    pose.centerOfMass.y, pose.centerOfMass.z);
    }
    if (!dropped && t >= G::kDropLiftEnd) {
        dropped = true;
        dropFrom = placementOf(scene, slot, pose);
        std::printf("  %6.3f s  dropped    from (%.3f, %.3f, %.3f) m\n", t, pose.centerOfMass.x,
                    pose.centerOfMass.y, pose.centerOfMass.z);
    }
    rest = placementOf(scene, slot, pose);
    restSpeed = glm::length(pose.velocity);
    restSpinRadPerS = glm::length(pose.angularVelocity);
}

nlohmann::json placementJson(const Placement& p) {
    return {{"center_of_mass", {p.centerOfMass.x, p.centerOfMass.y, p.centerOfMass.z}},
            {"lowest_y", p.lowestY},
            {"support_id", p.support ? nlohmann::json(*p.support) : nlohmann::json(nullptr)},
            {"gap_mm", 1000.0 * p.gapM}};
}

std::string placementText(const Placement& p) {
    char text[160];
    if (p.support) {
        std::snprintf(text, sizeof text,
                      "(%.3f, %.3f, %.3f) m on object %u (its lowest point %.3f mm %s its top)",
                      p.centerOfMass.x, p.centerOfMass.y, p.centerOfMass.z, *p.support,
                      1000.0 * std::abs(p.gapM), p.gapM >= 0 ? "above" : "below");
    } else {
        std::snprintf(text, sizeof text, "(%.3f, %.3f, %.3f) m on nothing", p.centerOfMass.x,
                      p.centerOfMass.y, p.centerOfMass.z);
    }
    return text;
}

// After the physical session: held or not, slip, forces against m g, where it was set down and
// where it rests, the dynamics' figures, each device; the JSON report when asked for.
void reportPhysical(const DemoArgs& a, const Runtime& runtime, const PhysicalGrasp& g) {
    const RunReport r = runtime.report();
    const double weight = g.massKg * g.gravity;
    const double n = static_cast<double>(std::max<std::uint64_t>(1, g.carrySamples));
    const double support = g.supportSumN / n;
    std::printf("held: %s; lifted %.1f mm; slip against the hands while held: %.2f mm at most\n",
                g.held() ? "yes" : "no", 1000.0 * g.liftM, 1000.0 * g.maxSlipM());
    std::printf("carrying: the hands hold up %.3f N (mean; worst step off by %.3f N), its weight "
                "m g = %.3f N (%.1f g)\n",
                support, g.supportWorstN, weight, 1000.0 * g.massKg);
    std::printf("set down at %s\n", placementText(g.setDown).c_str());
    std::printf("dropped from %.1f mm above it; came to rest at %s (%s, %.2f mm/s)\n",
                1000.0 * g.dropFrom.gapM, placementText(g.rest).c_str(),
                g.atRest() ? "at rest" : "still moving", 1000.0 * g.restSpeed);
    nlohmann::json dynamics;
    if (r.dynamics && !r.dynamics->bodies.empty()) {
        const auto& d = *r.dynamics;
        const BodyReport& b = d.bodies.at(g.body);
        std::printf("dynamics: deepest penetration %.3f mm, largest energy gain %.3g J, %s\n",
                    1000.0 * b.deepestPenetrationM, b.largestEnergyGainJ,
                    d.stable ? "stable" : "NOT stable");
        dynamics = {{"steps", d.steps},
                    {"deepest_penetration_mm", 1000.0 * b.deepestPenetrationM},
                    {"largest_energy_gain_j", b.largestEnergyGainJ},
                    {"stable", d.stable}};
    }
    const nlohmann::json devicesJson = reportDevices(r, runtime, g.felt);
    if (a.report.empty()) {
        return;
    }
    const nlohmann::json report{{"mode", "physical"},
                                {"object_id", a.object},
                                {"clock", a.stepped ? "stepped" : "wall"},
                                {"mass_kg", g.massKg},
                                {"weight_n", weight},
                                {"held", g.held()},
                                {"lift_mm", 1000.0 * g.liftM},
                                {"slip_max_mm", 1000.0 * g.maxSlipM()},
                                {"carry_support_mean_n", support},
                                {"carry_support_worst_error_n", g.supportWorstN},
                                {"start", placementJson(g.start)},
                                {"set_down", placementJson(g.setDown)},
                                {"drop_from", placementJson(g.dropFrom)},
                                {"rest", placementJson(g.rest)},
                                {"at_rest", g.atRest()},
                                {"rest_speed_m_per_s", g.restSpeed},
                                {"dynamics", dynamics},
                                {"devices", devicesJson}};
    writeFileAtomically(a.report, report.dump(2) + "\n");
    std::printf("report written to %s\n", a.report.c_str());
}

// The refusals that need no file: each names the options and what to give instead.
void checkDemoArgs(const DemoArgs& a) {
    if (a.stepped && a.realtime) {
        throw InputError("--stepped runs the session on this thread, not on real-time servo "
                         "threads: give --stepped or --realtime, not both");
    }
    if (a.stepped && a.view.enabled) {
        throw InputError("--stepped --view: a stepped session runs faster than real time, and the "
                         "view shows it on the wall clock; record it and replay that instead "
                         "(--stepped --record DIR, then hapto view --trace DIR)");
    }
    if (!a.shape.empty() && !parseGraspObject(a.shape)) {
        throw InputError("--shape '" + a.shape + "': expected box, sphere or mesh");
    }
    if (!a.shape.empty() && (a.kinematic || !a.scene.empty())) {
        throw InputError(
            std::string("--shape chooses the object of the built-in physical scene; ") +
            (a.kinematic ? "--kinematic grasps the built-in scene's box"
                         : "with --scene the scene's own object is grasped"));
    }
}

// The scene: the file, else the built-in one of the mode; the grasped object must be dynamic
// for the physical grasp and static for the kinematic controller.
std::shared_ptr<const Scene> demoScene(const DemoArgs& a) {
    auto scene = std::make_shared<const Scene>(
        !a.scene.empty() ? loadSceneOrDefault(a.scene)
        : a.kinematic
            ? makeGraspScene()
            : makeDynamicGraspScene(
                  parseGraspObject(a.shape.empty() ? "box" : a.shape).value_or(GraspObject::Box)));
    const auto slot = scene->slotOf(a.object);
    if (!slot) {
        throw InputError("--object: the scene has no object with id " + std::to_string(a.object));
    }
    const bool dynamic = scene->object(*slot).body.dynamic;
    if (!a.kinematic && !dynamic) {
        throw InputError("--object " + std::to_string(a.object) + ": object " +
                         std::to_string(a.object) + " of " + a.scene +
                         " is static; the physical grasp lifts a body with mass (give it "
                         "\"dynamic\": true and \"mass_kg\", scene version 3), or run --kinematic");
    }
    if (a.kinematic && dynamic) {
        throw InputError("--kinematic --object " + std::to_string(a.object) +
                         ": the object is dynamic (it has mass); the kinematic controller moves "
                         "static objects only: run without --kinematic");
    }
    return scene;
}

// The physical grasp's control loop: measures each millisecond until the body has rested
// after the drop (a second at least; at most 4 s after the hands open).
void physicalLoop(Session& session, LiveView& view, const World& world, const Scene& scene,
                  const Runtime& runtime, PhysicalGrasp& grasp) {
    session.run([&](double t) {
        view.update(world);
        grasp.observe(t, scene, runtime);
        const double after = t - GraspTimes::kDropEnd;
        return !((after > 1.0 && grasp.atRest()) || after > 4.0);
    });
}

// The kinematic controller's control loop (the GraspController moves the object).
void kinematicLoop(Session& session, LiveView& view, World& world, Runtime& runtime,
                   GraspController& grasp, const std::vector<SimDevice*>& sims, Felt (&felt)[2]) {
    GraspState last = GraspState::Idle;
    // Until both scripts are done (simulated hands) or 12 s of session time, plus a second to
    // settle.
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
}

// The physical grasp's measure, its start taken from the runtime's first published pose.
PhysicalGrasp physicalGrasp(const Scene& scene, const Runtime& runtime, ObjectId object) {
    PhysicalGrasp g;
    g.slot = *scene.slotOf(object);
    const auto ids = runtime.bodyIds();
    g.body = static_cast<std::size_t>(std::find(ids.begin(), ids.end(), object) - ids.begin());
    g.massKg = scene.object(g.slot).body.massKg;
    g.gravity = glm::length(scene.physics().gravity);
    experiments::GraspProbeSettings settings;
    settings.massKg = g.massKg;
    settings.gravityMPerS2 = g.gravity;
    settings.up = -scene.physics().gravity / g.gravity;
    g.probe = experiments::GraspProbe(settings);
    g.start = placementOf(scene, g.slot, runtime.bodyPoses()->read(g.body));
    return g;
}

int runDemo(const DemoArgs& a) {
    checkDemoArgs(a);
    StopSignals signals; // before any thread starts; see `hapto run`
    DeviceFile file =
        a.devices.empty() ? DeviceFile{graspHandConfigs(a.object), {}} : loadDeviceFile(a.devices);
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
    const SessionPaths paths{a.scene, a.devices, a.report, a.record};
    checkSessionFiles(paths, configs); // before the scene loads
    // One copy of the scene: the world's first snapshot shares it with the hands and the view.
    const std::shared_ptr<const Scene> shared = demoScene(a);
    const Scene& scene = *shared;
    if (scene.hasDynamicBodies()) {
        checkBodyTraceFile(paths, configs);
    }
    ManualClock clock; // --stepped: the session's time, for the world and the runtime
    World world(shared, sessionIndexSpec(a.index, scene, a.maxIndexMb));
    if (a.stepped) {
        world.useClock(clock);
    }
    signals.endStartUp(); // a signal from now on stops the demo in order
    Recorders recorders;
    std::vector<RuntimeDevice> devices = recordedDevices(file, scene, a.record, recorders);
    std::vector<SimDevice*> sims;
    for (const RuntimeDevice& rd : devices) {
        sims.push_back(dynamic_cast<SimDevice*>(rd.device.get()));
    }
    RuntimeOptions options;
    options.realtime = a.realtime;
    Runtime runtime(world, std::move(devices), options);
    recordBodies(runtime, a.record, recorders);
    std::optional<GraspController> grasp;
    if (a.kinematic) {
        grasp.emplace(world, runtime, 0, 1);
    }
    if (!a.stepped) { // stepped, this thread never blocks: it sees the first signal
        signals.onSecondSignal([&runtime] { runtime.emergencyStop(); });
    }
    LiveView view(a.view, "hapto demo grasp", scene, runtime);

    const Vec3 startPosition = scene.object(*scene.slotOf(a.object)).center;
    std::printf("hapto demo grasp%s: object %u at (%.3f, %.3f, %.3f) m, %u objects, devices %s + "
                "%s\n",
                a.kinematic ? " --kinematic" : "", a.object, startPosition.x, startPosition.y,
                startPosition.z, scene.size(), configs[0].name.c_str(), configs[1].name.c_str());
    // A control step every millisecond: on the wall clock it sleeps while the servo threads run
    // on their own; stepped (--stepped), it first runs the servo ticks (and the dynamics steps)
    // due in its millisecond on this thread, so the session's outcome is the same every run
    // however busy the machine is.
    SessionOptions control;
    control.controlPeriodNs = 1'000'000;
    control.steppedClock = a.stepped ? &clock : nullptr;
    control.stopRequested = [&signals] { return signals.requested(); };
    recorders.addTo(control);
    Session session(runtime, std::move(control));
    if (session.start() != 2) {
        if (recorders.bodies) {
            recorders.bodies->abandon(); // the demo failed: an older bodies.trace stays
        }
        session.stop();
        throw std::runtime_error(
            "a device could not be opened: " + runtime.report().devices[0].fault + " " +
            runtime.report().devices[1].fault);
    }

    view.start();
    if (a.kinematic) {
        Felt felt[2];
        kinematicLoop(session, view, world, runtime, *grasp, sims, felt);
        session.stop();
        view.stop();
        world.setRestDelay(std::chrono::nanoseconds(0));
        world.settle();
        reportDemo(a, scene, world, runtime, *grasp, felt, startPosition);
        return 0;
    }
    PhysicalGrasp measured = physicalGrasp(scene, runtime, a.object);
    physicalLoop(session, view, world, scene, runtime, measured);
    session.stop();
    view.stop();
    reportPhysical(a, runtime, measured);
    return 0;
}

} // namespace

void addDemoCommands(CLI::App& app) {
    auto* demo = app.add_subcommand("demo", "Scripted demonstrations");
    demo->require_subcommand(1);
    setExamples(demo, {"hapto demo grasp --view"});
    auto* cmd = demo->add_subcommand(
        "grasp", "Two simulated hands approach an object with mass from both sides, squeeze, lift "
                 "it 5 cm by friction alone, carry it 10 cm sideways, set it down on a plinth, let "
                 "go, then lift it 4 cm again and open so it drops and comes to rest (about 12 s; "
                 "--kinematic: the kinematic controller, about 9 s)");
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
    cmd->add_option("--record", a->record,
                    "Record each hand's ticks into DIR/<name>.trace and the dynamic bodies into "
                    "DIR/bodies.trace (see `hapto trace export`, `hapto view --trace DIR`)");
    cmd->add_flag("--kinematic", a->kinematic,
                  "The kinematic controller instead of the physics: the object (static) "
                  "snaps to the hands' midpoint while they squeeze it, each hand feels half its "
                  "weight injected, and it drops straight down when let go");
    cmd->add_option("--shape", a->shape,
                    "The built-in physical scene's object: box (default), sphere or mesh (a closed "
                    "28-triangle octagonal prism)");
    addRealtimeFlag(cmd, a->realtime, "the demo shares the machine");
    addViewOptions(cmd, a->view);
    cmd->add_flag("--stepped", a->stepped,
                  "Run the session on the step mode's clock, not the wall clock: the servo ticks "
                  "and the control loop take turns on one thread, a millisecond of session time "
                  "at a time, as fast as the machine goes, so every run gives the same result "
                  "however busy the machine is (simulated hands and replays only; not with "
                  "--realtime nor --view)");
    setExamples(cmd, {"hapto demo grasp --view", "hapto demo grasp --shape sphere --view",
                      "hapto demo grasp --stepped --record traces --report grasp.json",
                      "hapto demo grasp --kinematic --scene grasp.json --object 3"});
    cmd->callback([a] { runDemo(*a); });
}

} // namespace hapto::cli
