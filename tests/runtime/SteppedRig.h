#pragma once
// The runtime tests' stepped session: `count` scripted devices over the cube scene
// (CubeScene.h), device i pressing into the cube at x = 0.004 i - 0.01, driven by a
// ManualClock in the runtime's step mode (Runtime::startStepped / runUntil).

#include "CubeScene.h"
#include "ScriptedDevice.h"

#include "hapto/devices/TraceRecorder.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/Runtime.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace hapto::test {

struct SteppedRig {
    ManualClock clock;
    World world;
    std::vector<ScriptedDevice*> devices;
    std::unique_ptr<Runtime> runtime;
    std::uint64_t t0 = 0; // the session's start

    /// `setup` may change device i before the session opens; device i records into
    /// recorders[i] when there is one. Step mode: options.realtime is turned off.
    SteppedRig(int count, double rateHz, std::function<void(int, ScriptedDevice&)> setup = {},
               RuntimeOptions options = {}, Scene scene = cubeScene(),
               std::vector<TraceRecorder*> recorders = {})
        : world(std::move(scene), IndexSpec::parse(kDefaultIndexSpec)) {
        world.useClock(clock);
        std::vector<RuntimeDevice> rds;
        for (int i = 0; i < count; ++i) {
            auto d = std::make_unique<ScriptedDevice>("d" + std::to_string(i),
                                                      pressIntoCube(0.004 * i - 0.01));
            d->useClock(&clock);
            if (setup) {
                setup(i, *d);
            }
            devices.push_back(d.get());
            rds.push_back(
                {std::move(d), scriptedConfig(i, rateHz),
                 static_cast<std::size_t>(i) < recorders.size() ? recorders[i] : nullptr});
        }
        options.realtime = false;
        runtime = std::make_unique<Runtime>(world, std::move(rds), options);
    }
    /// Starts the stepped session; returns the devices that opened.
    std::size_t start() {
        t0 = clock.nowNs();
        return runtime->startStepped(clock);
    }
    /// Runs every device on its deadlines until t0 + ms.
    void runTo(double ms) { runtime->runUntil(t0 + static_cast<std::uint64_t>(ms * 1'000'000)); }
    DeviceReport report(std::size_t i) const { return runtime->report().devices.at(i); }
    /// The force device i last wrote (N).
    Vec3 force(std::size_t i) const {
        const DeviceMetrics& m = runtime->metrics(i);
        return {m.forceN[0].load(), m.forceN[1].load(), m.forceN[2].load()};
    }
};

} // namespace hapto::test
