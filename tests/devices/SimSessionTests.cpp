// A simulated hand pressing through the runtime in step mode: what the hand feels is the god
// object's force, k (proxy - device), and a touch settles at press_n on a box or a closed mesh
// of any stiffness (issue 35, item 2: it settled at press_n k / (k + 300), the hand's spring in
// series with the surface).

#include "TestMeshes.h"

#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/World.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <vector>

using namespace hapto;

namespace {

// One object at the origin with surface stiffness `stiffnessNPerM`: a 4 cm box, or a closed
// icosphere mesh of radius 2 cm (1280 triangles).
Scene oneObject(bool mesh, double stiffnessNPerM) {
    Material m;
    m.stiffness = stiffnessNPerM;
    const SceneObject o =
        mesh ? makeMesh(0, Vec3(0.0), test::makeIcosphere(3, 0.02), Quat(1, 0, 0, 0), m)
             : makeBox(0, Vec3(0.0), Vec3(0.02), Quat(1, 0, 0, 0), m);
    return Scene({Vec3(-0.1), Vec3(0.1)}, {o});
}

// The force (N, world) the runtime sent a touching hand, one per millisecond over the last
// second of `seconds` of a step-mode session, the hand starting 5 cm out along +x.
std::vector<Vec3> pressedForces(const Scene& scene, double pressN, double seconds) {
    DeviceConfig c;
    c.name = "hand";
    c.kind = DeviceKind::Sim;
    SimConfig sim;
    sim.script = HandScript::Touch;
    sim.start = Vec3(0.05, 0.0, 0.0);
    sim.object = 0;
    sim.pressForceN = pressN;
    c.params = sim;
    ManualClock clock;
    World world(scene, IndexSpec::parse(kDefaultIndexSpec));
    world.useClock(clock);
    std::vector<RuntimeDevice> devices;
    devices.push_back({makeDevice(c, scene), c, nullptr});
    RuntimeOptions options;
    options.realtime = false;
    Runtime runtime(world, std::move(devices), options);
    REQUIRE(runtime.startStepped(clock) == 1);
    const std::uint64_t t0 = clock.nowNs();
    std::vector<Vec3> forces;
    for (int ms = 1; ms <= static_cast<int>(seconds * 1000); ++ms) {
        runtime.runUntil(t0 + static_cast<std::uint64_t>(ms) * 1'000'000);
        ContactReport r;
        if (ms > static_cast<int>(seconds * 1000) - 1000 && runtime.lastTick(0, r)) {
            forces.push_back(r.force);
        }
    }
    CHECK(runtime.report().devices[0].faults == 0);
    runtime.stop();
    return forces;
}

} // namespace

TEST_CASE("sim touch through the runtime: the steady force is press_n on boxes and meshes of "
          "800, 1000 and 3000 N/m",
          "[threads]") {
    for (const bool mesh : {false, true}) {
        for (const double k : {800.0, 1000.0, 3000.0}) {
            for (const double pressN : {1.5, 3.0}) {
                INFO((mesh ? "mesh" : "box") << ", " << k << " N/m, press_n " << pressN << " N");
                const std::vector<Vec3> forces = pressedForces(oneObject(mesh, k), pressN, 6.0);
                REQUIRE(forces.size() == 1000);
                // Along +x (the touched face's normal), within 2 % tick by tick: the readings'
                // 10 um quantum and 2 um noise make k x 12 um of ripple (0.036 N at 3000 N/m).
                double sum = 0.0;
                for (const Vec3& f : forces) {
                    CHECK(f.x == Approx(pressN).epsilon(0.02));
                    CHECK(std::abs(f.y) + std::abs(f.z) < 0.02 * pressN);
                    sum += f.x;
                }
                CHECK(sum / 1000.0 == Approx(pressN).epsilon(0.005)); // and on average, 0.5 %
            }
        }
    }
}

TEST_CASE("sim touch through the runtime: the same session gives the same forces, tick for tick",
          "[threads]") {
    const Scene scene = oneObject(true, 1000.0);
    CHECK(pressedForces(scene, 1.5, 3.0) == pressedForces(scene, 1.5, 3.0));
}
