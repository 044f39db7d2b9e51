// Built by the install test (InstallTest.cmake) with README's pkg-config line against an
// installed hapto, then run. It reaches into every library but the view (the install test
// builds the view's program with hapto-view.pc) and so into every dependency a static hapto
// needs on the link line: a scene file's loaders, the octree's build (TBB), the device factory
// (libusb for the Falcon, the loader of OpenHaptics' libHD), the runtime and the experiments'
// tables. It runs one simulated hand in step mode for 0.2 s and prints the force it is left
// with (zero after stop()).
//
//   PkgConfigApp [SCENE.json]   the grasp scene when no file is given

#include <hapto/devices/DeviceConfig.h>
#include <hapto/devices/DeviceFactory.h>
#include <hapto/experiments/Table.h>
#include <hapto/index/IndexSpec.h>
#include <hapto/runtime/ManualClock.h>
#include <hapto/runtime/Runtime.h>
#include <hapto/runtime/World.h>
#include <hapto/scenes/Generators.h>
#include <hapto/scenes/SceneFile.h>

#include <cstdio>
#include <vector>

using namespace hapto;
using hapto::experiments::csvNumber;

int main(int argc, char** argv) {
    const Scene scene = argc > 1 ? loadSceneFile(argv[1]) : makeGraspScene();
    ManualClock clock;
    World world(scene, IndexSpec::parse("octree:2:0.005"));
    world.useClock(clock);
    DeviceConfig hand;
    hand.name = "hand";
    hand.kind = DeviceKind::Sim;
    std::vector<RuntimeDevice> devices;
    devices.push_back({makeDevice(hand, scene), hand, nullptr});
    RuntimeOptions options;
    options.realtime = false;
    Runtime runtime(world, std::move(devices), options);
    if (runtime.startStepped(clock) != 1) {
        std::fprintf(stderr, "PkgConfigApp: the simulated hand did not open\n");
        return 1;
    }
    runtime.runUntil(clock.nowNs() + 200'000'000);
    runtime.stop();
    ContactReport last;
    const bool ticked = runtime.lastTick(0, last);
    std::printf("%llu ticks, force at the end %s N\n",
                static_cast<unsigned long long>(runtime.metrics(0).ticks.load()),
                csvNumber(glm::length(last.force)).c_str());
    return ticked && last.force == Vec3(0.0) ? 0 : 1;
}
