// grasp_with_mass: a two-handed grasp of a body that has mass. A 100 g cube rests on a floor
// (scene format 3: dynamic, mass, friction); two hands squeeze it from both sides, lift it by
// friction alone, carry it 10 cm onto a plinth, let go, grasp it again and drop it. A dynamics
// thread steps the cube at 1 kHz; each hand's servo thread renders it from its latest pose and
// hands the reaction of the force it sends back to the cube, so the hands feel its weight.
//
//   grasp_with_mass [--stepped] [DEVICES.json]
//
// --stepped runs the session on the runtime's step mode (simulated hands and replays only): the
// servo ticks, the dynamics steps and the control loop take turns on this thread, so every run
// gives the same result however busy the machine is, and the program checks that the cube was
// lifted by at least 3 cm and ended at rest. On the wall clock it checks only that every device
// was left at zero force.
//
// The lines between "README begins" and "README ends" are the README's physical grasp, byte
// for byte (a ctest checks that the two agree).

#include <hapto/devices/DeviceConfig.h>
#include <hapto/devices/DeviceFactory.h>
#include <hapto/index/DefaultIndex.h>
#include <hapto/index/IndexSpec.h>
#include <hapto/io/InputError.h>
#include <hapto/runtime/BodyPoses.h>
#include <hapto/runtime/DeviceFile.h>
#include <hapto/runtime/ManualClock.h>
#include <hapto/runtime/Runtime.h>
#include <hapto/runtime/Session.h>
#include <hapto/runtime/World.h>
#include <hapto/scenes/Generators.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

using namespace hapto;

int main(int argc, char** argv) try {
    // [--stepped] [DEVICES.json]: by default the grasp scripts' two simulated hands, 2 N each
    // (mu_s 0.6 x 4 N = 2.4 N of friction holds the cube's 0.98 N weight).
    const std::vector<std::string_view> args(argv + 1, argv + argc);
    const bool stepped = std::find(args.begin(), args.end(), "--stepped") != args.end();
    const auto file =
        std::find_if(args.begin(), args.end(), [](auto a) { return a != "--stepped"; });
    const std::vector<DeviceConfig> hands =
        file != args.end() ? loadDeviceFile(std::string(*file)).devices : graspHandConfigs();
    const bool steppable = std::all_of(hands.begin(), hands.end(), [](const DeviceConfig& h) {
        return runsOnStepClock(h.kind); // simulated hands and replays
    });
    if (hands.size() != 2 || (stepped && !steppable)) {
        throw InputError("two devices, please, and with --stepped simulated hands or replays");
    }
    ManualClock clock; // stepped: the session's time, for the world and the runtime
    SessionOptions options;
    options.durationS = 12.0; // the scripts take about 11 s; then the cube comes to rest
    options.controlPeriodNs = 1'000'000;
    options.steppedClock = stepped ? &clock : nullptr; // (the world moves no object here)
    double highestY = -1.0;                            // the cube's highest centre (m)
    BodyPose last;                                     // its newest pose

    // README begins
    const Scene scene = makeDynamicGraspScene(GraspObject::Box); // a 100 g cube, dynamic
    World world(scene, IndexSpec::parse(defaultIndexSpec(scene)));
    std::vector<RuntimeDevice> devices;
    for (const DeviceConfig& hand : hands) {
        devices.push_back({makeDevice(hand, scene), hand});
    }
    Runtime runtime(world, std::move(devices)); // a servo thread per hand, a dynamics thread
    Session session(runtime, options);
    session.start();
    session.run([&](double) {
        last = runtime.bodyPoses()->read(0); // the cube's pose and velocity, lock-free
        highestY = std::max(highestY, last.center.y);
        return true; // until options.durationS
    });
    const RunReport& report = session.stop(); // every device at zero force
    // README ends

    const double startY = scene.object(0).center.y;
    const double lastSpeed = glm::length(last.velocity);
    std::printf("cube: started at y = %.3f m, highest %.3f m, ended at %.3f m, %.4f m/s\n", startY,
                highestY, last.center.y, lastSpeed);
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
    const bool lifted = highestY - startY > 0.03;
    const bool atRest = lastSpeed < 1e-3;
    std::printf("%s, %s, %s\n", lifted ? "lifted by friction" : "NOT LIFTED",
                atRest ? "at rest at the end" : "STILL MOVING",
                zeroForce ? "every device at zero force" : "A DEVICE STILL HAS FORCE");
    return zeroForce && ((lifted && atRest) || !stepped) ? 0 : 1;
} catch (const InputError& e) {
    std::fprintf(stderr, "grasp_with_mass: %s\n", e.what());
    return 2;
}
