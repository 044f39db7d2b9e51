// `hapto soak`: the command over hapto::experiments' soak (experiments/src/Soak.cpp): options,
// the stop signals, the input checks.

#include "Commands.h"
#include "Options.h"
#include "SessionChecks.h"
#include "StopSignals.h"

#include "hapto/experiments/Soak.h"
#include "hapto/runtime/Runtime.h"

#include <cstdio>
#include <cstdlib>
#include <memory>

namespace hapto::cli {
namespace {

/// The soak's options and the scene file they run over.
struct SoakArgs : experiments::SoakOptions {
    std::string scene; ///< Scene file; empty: the embedded default scene.
};

int runSoakCommand(const SoakArgs& a) {
    StopSignals signals; // before any thread starts; see `hapto run`
    experiments::checkSoakOptions(a);
    checkSessionFiles({a.scene, "", a.report, ""}, {});
    auto scene = std::make_shared<const Scene>(loadSceneOrDefault(a.scene));
    SoakArgs options = a;
    if (options.index.empty()) {
        options.index = defaultIndexSpec(*scene);
    }
    signals.endStartUp(); // the soak's own start-up stops in order
    experiments::SoakControl control;
    control.stopRequested = [&signals] { return signals.requested(); };
    control.onRuntime = [&signals](Runtime& runtime) {
        signals.onSecondSignal([&runtime] { runtime.emergencyStop(); });
    };
    return experiments::runSoak(std::move(scene), options, control);
}

} // namespace

void addSoakCommands(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "soak", "Run simulated hands for a long time over a changing world with faults injected "
                "on a schedule; report tick-rate drift, memory growth and misses. Exit 0 when "
                "every fault was handled and memory stayed flat, 1 otherwise (and when "
                "interrupted: no verdict); 2 for bad arguments, such as a soak too short to "
                "reach its first fault");
    setExamples(cmd, {"hapto soak --duration 600 --report soak.json",
                      "hapto soak --duration 20 --hands 3 --fault-every 1"});
    auto a = std::make_shared<SoakArgs>();
    auto* duration = cmd->add_option("--duration", a->durationS, "How long to run (s)")
                         ->capture_default_str()
                         ->check(finiteRange(1.2, 6e6));
    auto minutes = std::make_shared<double>(0.0);
    auto* minutesOpt =
        cmd->add_option("--minutes", *minutes,
                        "Deprecated: how long to run in minutes (use --duration, in seconds)")
            ->check(finiteRange(0.02, 100000))
            ->excludes(duration);
    cmd->add_option("--hands", a->devices, "How many simulated hands")
        ->type_name("N")
        ->capture_default_str()
        ->check(finiteRange(1, 32));
    addRenamedOption(cmd, "--devices", "--hands N",
                     "--devices names a device file in run, demo grasp and view");
    cmd->add_option("--rate", a->rateHz, "Servo rate of every hand (Hz)")
        ->capture_default_str()
        ->check(finiteRange(100, 100000));
    cmd->add_option("--scene", a->scene, "Scene file (default: the embedded default scene)");
    a->index.clear(); // not given: defaultIndexSpec over the scene
    addIndexOption(cmd, a->index);
    addMaxIndexMbOption(cmd, a->maxIndexMb);
    cmd->add_option("--fault-every", a->faultEveryS,
                    "Inject a fault every this many seconds (s), into the hands in turn: "
                    "disconnect (0.5 s), stall of 0.4 watchdog timeouts (a miss, not a fault), "
                    "non-finite sample, stall of 3 watchdog timeouts, read error")
        ->capture_default_str()
        ->check(finiteRange(0.1, 1e6));
    cmd->add_option("--window", a->windowS, "Report rate, drift, misses and memory per window (s)")
        ->capture_default_str()
        ->check(finiteRange(0.5, 1e6));
    cmd->add_option("--watchdog-ms", a->watchdogMs,
                    "No tick for this long faults a device (ms); stalls are sized from it")
        ->capture_default_str()
        ->check(finiteRange(5, 10000));
    cmd->add_option("--reopen-ms", a->reopenMs,
                    "Retry opening a faulted device this often (ms; hapto run's default)")
        ->capture_default_str()
        ->check(finiteRange(1, 60000));
    cmd->add_option("--memory-tolerance", a->memoryToleranceMiB,
                    "Resident memory may grow this much: median of the last third of the "
                    "windows against the first third, the first window left out (MiB)")
        ->capture_default_str()
        ->check(finiteRange(0, 1e6));
    cmd->add_option("--report", a->report, "Write the JSON soak report here");
    addRealtimeFlag(cmd, a->realtime, "");
    cmd->callback([a, minutes, minutesOpt] {
        if (minutesOpt->count() > 0) {
            a->durationS = *minutes * 60.0;
        }
        char given[64];
        std::snprintf(given, sizeof given, "%s %g",
                      minutesOpt->count() > 0 ? "--minutes" : "--duration",
                      minutesOpt->count() > 0 ? *minutes : a->durationS);
        a->durationOption = given;
        const int rc = runSoakCommand(*a);
        if (rc != 0) {
            std::exit(rc);
        }
    });
}

} // namespace hapto::cli
