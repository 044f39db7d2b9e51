// two_hands: the smallest complete hapto application. Two devices (simulated hands here; a
// device file can name Falcons or PHANToMs instead) grasp a cube, lift it, carry it 10 cm and
// put it down, while hapto measures every servo tick. Each hand also feels the other through a
// virtual spring: a per-tick hook, called on each hand's servo thread.
//
//   two_hands [--stepped] [DEVICES.json]
//
// --stepped runs the same objects on the runtime's step mode: the servo ticks and the control
// loop take turns on this thread, one millisecond of a clock the program moves at a time, so
// every run gives the same result however busy the machine is (simulated hands and replays
// only). Stepped, the program checks the carry; on the wall clock, where the carry depends on
// the control loop keeping pace with the servo threads, it checks only that the session ran to
// its end and left every device at zero force.

#include <hapto/devices/DeviceConfig.h>
#include <hapto/devices/DeviceFactory.h>
#include <hapto/index/DefaultIndex.h>
#include <hapto/index/IndexSpec.h>
#include <hapto/io/InputError.h>
#include <hapto/runtime/DeviceFile.h>
#include <hapto/runtime/GraspController.h>
#include <hapto/runtime/ManualClock.h>
#include <hapto/runtime/Realtime.h>
#include <hapto/runtime/Runtime.h>
#include <hapto/runtime/Session.h>
#include <hapto/runtime/World.h>
#include <hapto/scenes/Generators.h>

#include <cstdio>
#include <string_view>

using namespace hapto;

// The virtual spring between the hands (a 10 cm bar of 5 N/m): each hand's hook reads the other
// hand's newest point from its live metrics (atomics) and pulls or pushes along the line
// between them. It runs on the servo thread every tick, so it only reads and computes: no
// allocation, lock, print or wait.
struct Coupling {
    const DeviceMetrics* other = nullptr; // the other hand
    double stiffnessNPerM = 5.0;
    double restLengthM = 0.10;
};

static Vec3 feelTheOtherHand(void* context, const TickHookArgs& tick) noexcept {
    const Coupling& c = *static_cast<const Coupling*>(context);
    if (c.other->ticks.load(std::memory_order_relaxed) == 0) {
        return Vec3(0.0); // the other hand has no point yet
    }
    const Vec3 there(c.other->positionM[0].load(std::memory_order_relaxed),
                     c.other->positionM[1].load(std::memory_order_relaxed),
                     c.other->positionM[2].load(std::memory_order_relaxed));
    const Vec3 d = there - tick.devicePointM;
    const double length = glm::length(d);
    if (length < 1e-9) {
        return Vec3(0.0);
    }
    return c.stiffnessNPerM * (length - c.restLengthM) * (d / length); // N, world
}

int main(int argc, char** argv) try {
    bool stepped = false;
    const char* deviceFile = nullptr;
    for (int i = 1; i < argc; ++i) {
        if (std::string_view(argv[i]) == "--stepped") {
            stepped = true;
        } else {
            deviceFile = argv[i];
        }
    }

    // 1. The scene (metres, y up) and the world: one index (the library's default for this
    //    scene), shared by every servo thread.
    //    Stepped, the world's time is the program's clock too.
    const Scene scene = makeGraspScene();
    ManualClock clock;
    World world(scene, IndexSpec::parse(defaultIndexSpec(scene)));
    if (stepped) {
        world.useClock(clock);
    }

    // 2. The devices, from a file (with their force effects and renderer settings) or in code.
    const DeviceFile file =
        deviceFile ? loadDeviceFile(deviceFile) : DeviceFile{graspHandConfigs(), {}}; // 2 N each
    const std::vector<DeviceConfig>& configs = file.devices;
    if (configs.size() != 2) {
        throw InputError(std::string(deviceFile) + ": two devices, please (left and right hands)");
    }
    std::vector<RuntimeDevice> devices;
    for (std::size_t i = 0; i < configs.size(); ++i) {
        const DeviceConfig& config = configs[i];
        if (stepped && !runsOnStepClock(config.kind)) {
            throw InputError("--stepped: device '" + config.name + "' keeps real time");
        }
        devices.push_back({makeDevice(config, scene), config, nullptr, file.renderingOf(i)});
    }

    // 3. One servo thread per device; grasping runs here, on the control thread, which must
    //    keep pace with the hands: give it real-time priority too (below the servo threads'
    //    80) when the process may; it runs anyway when it may not. Stepped, there is no
    //    thread but this one and nothing to keep pace with.
    if (!stepped) {
        const rt::RealtimeGrant grant = rt::makeCurrentThreadRealtime(70, -1);
        if (!grant.note.empty()) {
            std::fprintf(stderr, "two_hands: %s\n", grant.note.c_str());
        }
    }
    Runtime runtime(world, std::move(devices));
    // The hooks are registered before start(); their contexts outlive the runtime's threads.
    Coupling leftFeelsRight{&runtime.metrics(1)}, rightFeelsLeft{&runtime.metrics(0)};
    runtime.setTickHook(0, {&feelTheOtherHand, &leftFeelsRight});
    runtime.setTickHook(1, {&feelTheOtherHand, &rightFeelsLeft});
    GraspController grasp(world, runtime, 0, 1);

    // 4. The session: a control step every millisecond grasps, carries, releases (the watchdog
    //    runs on the runtime's own thread). On the wall clock a step sleeps while the servo
    //    threads run; stepped, it first runs the servo ticks due in its millisecond. The grasp
    //    scripts take about 9 s of device time: 9500 ticks of the first device.
    SessionOptions options;
    options.controlPeriodNs = 1'000'000;
    options.steppedClock = stepped ? &clock : nullptr;
    Session session(runtime, options);
    if (session.start() != configs.size()) {
        std::fprintf(stderr, "two_hands: a device did not open\n");
        return 1;
    }
    const Vec3 start = scene.object(0).center;
    session.run([&](double) {
        grasp.step(0.001); // grasp, carry, release, fall
        return runtime.metrics(0).ticks.load() < 9500;
    });
    const bool ranToTheEnd = runtime.metrics(0).ticks.load() >= 9500;
    const RunReport& report = session.stop(); // every device at zero force

    // 5. What happened.
    const WorldSnapshot& now = world.current();
    const Vec3 end = now.scene->object(*now.scene->slotOf(0)).center;
    std::printf("cube moved from (%.3f, %.3f, %.3f) to (%.3f, %.3f, %.3f) m, held for %llu ms\n",
                start.x, start.y, start.z, end.x, end.y, end.z,
                static_cast<unsigned long long>(grasp.graspedSteps()));
    for (const DeviceReport& d : report.devices) {
        std::printf("%-6s %llu ticks, load p50 %.2f%%, p99.9 %.2f%%\n", d.name.c_str(),
                    static_cast<unsigned long long>(d.ticks), 100 * d.loadFraction.p50,
                    100 * d.loadFraction.p999);
    }
    bool zeroForce = true; // the force each device was last sent
    for (std::size_t i = 0; i < runtime.deviceCount(); ++i) {
        ContactReport last;
        zeroForce = zeroForce && (!runtime.lastTick(i, last) || last.force == Vec3(0.0));
    }
    const bool carried = grasp.graspStarts().size() == 1 && std::abs(end.x - start.x - 0.10) < 0.01;
    std::printf("%s, %s\n", ranToTheEnd ? "ran to the end" : "STOPPED EARLY",
                zeroForce ? "every device at zero force" : "A DEVICE STILL HAS FORCE");
    return ranToTheEnd && zeroForce && (carried || !stepped) ? 0 : 1;
} catch (const InputError& e) {
    std::fprintf(stderr, "two_hands: %s\n", e.what());
    return 2;
}
