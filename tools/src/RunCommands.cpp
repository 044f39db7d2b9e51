// `hapto run`: a session of D devices over one shared world, reporting each device's load,
// and the dynamics thread's when the scene has dynamic bodies (then D may be 0: --no-devices).
// --stepped runs the same session on the step mode's clock, as fast as the CPU allows, with
// byte-identical results run after run.

#include "Commands.h"
#include "LiveLines.h"
#include "LiveView.h"
#include "Options.h"
#include "SessionChecks.h"
#include "SessionRecorders.h"
#include "StopSignals.h"

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/devices/TraceRecorder.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/Session.h"

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <unistd.h>

namespace hapto::cli {
namespace {

struct RunArgs {
    std::string scene;
    std::string devices;
    std::string index; ///< Empty: defaultIndexSpec(scene).
    std::uint64_t maxIndexMb = IndexSpec::kDefaultMaxMegabytes;
    double rateHz = 0;
    double durationS = 5;
    std::string report;
    std::string record;
    bool realtime = true;
    double spinUs = 0;
    double warmUs = -1; ///< < 0: unset, the runtime chooses (RuntimeOptions::warmUpNs)
    int missLimit = 3;
    std::size_t devicesPerThread = 1;
    std::int32_t wakeLatencyUs = -1;
    double reopenMs = static_cast<double>(RuntimeOptions{}.reopenAfterNs) / 1e6;
    bool quiet = false;
    bool noDevices = false; ///< --no-devices: only the dynamics runs.
    bool stepped = false;   ///< --stepped: the session runs on the step mode's clock.
    ViewArgs view;
};

// The dynamics thread's row and each body's figures.
void printDynamics(const DynamicsReport& d) {
    std::printf("%-10s %-7s %6.0fHz %9llu %7.2f%% %7.2f%% %7.2f%% %7.1f%% %7llu %7llu %6s %s\n",
                "dynamics", "bodies", d.rateHz, static_cast<unsigned long long>(d.steps),
                100 * d.loadFraction.mean, 100 * d.loadFraction.p50, 100 * d.loadFraction.p999,
                100 * d.loadFraction.max, static_cast<unsigned long long>(d.missedDeadlines),
                static_cast<unsigned long long>(d.lateWakeups), "-",
                d.stable ? "stable" : "UNSTABLE");
    if (!d.fault.empty()) {
        std::printf("  dynamics: %.3f s: FAULT %s\n", d.faultS, d.fault.c_str());
    }
    std::printf("  dynamics: step p50 %.1f us, p99.9 %.1f us\n", d.stepNs.p50 / 1000.0,
                d.stepNs.p999 / 1000.0);
    for (const BodyReport& b : d.bodies) {
        std::printf("  body %u: deepest penetration %.3g mm, largest energy gain %.3g J%s\n", b.id,
                    b.deepestPenetrationM * 1000.0, b.largestEnergyGainJ,
                    b.stopped ? ", STOPPED (non-finite state)" : "");
    }
}

void printSummary(const RunReport& r) {
    std::printf("\n%-10s %-7s %8s %9s %8s %8s %8s %8s %7s %7s %6s %s\n", "device", "kind", "rate",
                "ticks", "load", "p50", "p99.9", "max", "missed", "late", "cand", "verdict");
    for (const DeviceReport& d : r.devices) {
        std::printf(
            "%-10s %-7s %6.0fHz %9llu %7.2f%% %7.2f%% %7.2f%% %7.1f%% %7llu %7llu %6.1f %s\n",
            d.name.c_str(), d.kind.c_str(), d.rateHz, static_cast<unsigned long long>(d.ticks),
            100 * d.loadFraction.mean, 100 * d.loadFraction.p50, 100 * d.loadFraction.p999,
            100 * d.loadFraction.max, static_cast<unsigned long long>(d.missedDeadlines),
            static_cast<unsigned long long>(d.lateWakeups), d.candidatesMean,
            d.fault.empty() ? (d.stable ? "stable" : "UNSTABLE") : ("FAULT " + d.fault).c_str());
        for (const std::string& e : d.events) {
            std::printf("  %s: %s\n", d.name.c_str(), e.c_str());
        }
        if (const std::string note = lateWakeupNote(d); !note.empty()) {
            std::printf("%s\n", wrapText("  " + d.name + ": " + note, kTextWidth - 4, 4).c_str());
        }
    }
    if (r.dynamics) {
        printDynamics(*r.dynamics);
    }
    std::printf(
        "total: load %.2f%% of one core summed over %zu devices, %.2f%% per core (%d cores); %s\n",
        100 * r.loadSum, r.devices.size(), 100 * r.loadPerCore, r.cores,
        r.stable ? "stable" : "NOT stable");
    if (r.warmUpNs > 0) {
        std::printf("warm-up: %g us before each deadline\n",
                    static_cast<double>(r.warmUpNs) / 1000.0);
    } else if (r.warmUpAutomatic) {
        std::printf("warm-up: off, as the servo threads share the cores or run in groups "
                    "(--warm-us warms per-device threads anyway)\n");
    }
    if (r.wakeLatencyUs >= 0) {
        std::printf("wake latency: idle CPUs held to %d us while the devices ran\n",
                    static_cast<int>(r.wakeLatencyUs));
    }
    if (!r.realtimeNote.empty()) {
        std::printf("note: %s\n", r.realtimeNote.c_str());
    }
}

// Gives replay devices their trace's transform, tool tip and rate (the rate unless --rate set
// one for all), then refuses, before anything starts, what cannot work: too many devices, a
// spin as long as a period, outputs that cannot be written or would overwrite an input.
// Throws InputError.
void prepareSession(const RunArgs& a, std::vector<DeviceConfig>& configs) {
    useTraceSettings(configs, !(a.rateHz > 0));
    if (a.stepped) {
        checkSteppable(configs);
        if (a.view.enabled) {
            // The view draws what the devices and bodies are now, at the wall clock's pace; a
            // stepped session is minutes of session time in seconds of CPU, then gone.
            throw InputError(
                "--view with --stepped: a stepped session runs on its own clock as fast as the "
                "CPU allows, not in real time, so a live view cannot follow it; record it "
                "(--record DIR) and replay it with 'hapto view --trace DIR', or drop --stepped");
        }
    }
    checkDeviceCount(configs.size(), a.devices);
    checkSpinAgainstRates(a.spinUs, configs);
    for (const DeviceConfig& c : configs) {
        const double periodUs = 1e6 / c.rateHz;
        if (a.warmUs > 0 && a.warmUs >= periodUs / 2) {
            char text[256];
            std::snprintf(text, sizeof text,
                          "--warm-us %g: not shorter than half the servo period of device '%s' "
                          "(%g us at %g Hz); warm up for less, or run slower",
                          a.warmUs, c.name.c_str(), periodUs, c.rateHz);
            throw InputError(text);
        }
    }
    checkSessionFiles({a.scene, a.devices, a.report, a.record}, configs);
    if (a.devicesPerThread > 1) {
        for (const DeviceConfig& c : configs) {
            if (c.kind != DeviceKind::Sim) {
                throw InputError("--devices-per-thread " + std::to_string(a.devicesPerThread) +
                                 ": device '" + c.name + "' in " + a.devices + " is " +
                                 std::string(name(c.kind)) +
                                 "; only simulated devices (kind sim) share a servo thread, a "
                                 "hardware or replay device gets its own");
            }
        }
    }
}

// The devices: none with --no-devices, else the --devices file's or the two default hands.
DeviceFile deviceFileFor(const RunArgs& a) {
    if (a.noDevices) {
        return DeviceFile{{}, {}};
    }
    return a.devices.empty() ? DeviceFile{defaultDeviceConfigs(), {}} : loadDeviceFile(a.devices);
}

// What can only be checked once the scene is loaded: --no-devices needs a dynamic body to run,
// and --record writes the bodies' trace beside the devices'. Throws InputError.
void checkAgainstScene(const RunArgs& a, const Scene& scene,
                       std::span<const DeviceConfig> configs) {
    if (!scene.hasDynamicBodies()) {
        if (a.noDevices) {
            throw InputError(
                "--no-devices: " +
                (a.scene.empty() ? std::string("the default scene") : "the scene " + a.scene) +
                " has no dynamic body (an object with \"dynamic\": true), so "
                "nothing would run; give a scene with one, or devices");
        }
        return;
    }
    checkBodyTraceFile({a.scene, a.devices, a.report, a.record}, configs);
}

RuntimeOptions runtimeOptionsFor(const RunArgs& a) {
    RuntimeOptions opt;
    opt.realtime = a.realtime && !a.stepped; // stepped, no servo thread runs
    opt.spinNs = static_cast<std::uint64_t>(a.spinUs * 1000);
    if (a.warmUs >= 0) {
        opt.warmUpNs = static_cast<std::uint64_t>(a.warmUs * 1000);
    }
    opt.missLimit = a.missLimit;
    opt.reopenAfterNs = static_cast<std::uint64_t>(a.reopenMs * 1e6);
    opt.devicesPerThread = a.devicesPerThread;
    opt.wakeLatencyUs = a.stepped ? -1 : a.wakeLatencyUs;
    return opt;
}

/// After the session stopped: writes --report, prints the summary, each device that faulted
/// and was not driven again (which makes the run a failure: 1) and a stop by signal.
int finishRun(const RunArgs& a, const RunReport& r, const StopSignals& signals) {
    if (!a.report.empty()) {
        writeFileAtomically(a.report, reportToJson(r));
    }
    printSummary(r);
    if (!a.report.empty()) {
        std::fprintf(stderr, "report written to %s\n", a.report.c_str());
    }
    int down = 0;
    for (const DeviceReport& d : r.devices) {
        if (!d.fault.empty()) {
            std::fprintf(stderr, "hapto run: %s faulted and was not recovered: %s\n",
                         d.name.c_str(), d.fault.c_str());
            ++down;
        }
    }
    if (signals.requested()) {
        std::fprintf(stderr, "hapto run: stopped by signal %d; zero force on every device\n",
                     signals.signalNumber());
    }
    return down > 0 ? 1 : 0;
}

int runSession(const RunArgs& a) {
    // First, before any thread starts (the index build's TBB workers included), so that every
    // thread inherits the blocked stop signals and only the signal thread takes them.
    // Until endStartUp() below, a signal ends the process at once: nothing is open or written.
    StopSignals signals;
    DeviceFile file = deviceFileFor(a);
    std::vector<DeviceConfig>& configs = file.devices;
    if (a.rateHz > 0) {
        for (DeviceConfig& c : configs) {
            c.rateHz = a.rateHz;
        }
    }
    prepareSession(a, configs); // the outputs are checked before the scene is loaded
    // One copy of the scene: the world's first snapshot shares it with the devices and the view.
    const auto shared = std::make_shared<const Scene>(loadSceneOrDefault(a.scene));
    const Scene& scene = *shared;
    checkAgainstScene(a, scene, configs);
    const IndexSpec spec = sessionIndexSpec(a.index, scene, a.maxIndexMb);
    ManualClock clock;         // --stepped: the session's time, for the world and the runtime
    World world(shared, spec); // the world is ready before any device, recording or view
    if (a.stepped) {
        world.useClock(clock);
    }
    signals.endStartUp();

    Recorders recorders;
    Runtime runtime(world, recordedDevices(file, scene, a.record, recorders), runtimeOptionsFor(a));
    recordBodies(runtime, a.record, recorders);
    // A second signal while the orderly stop below is under way (or blocked): zero force
    // now, from the signal thread, and exit. Stepped, this thread never blocks: it sees the
    // first signal, and the step mode's emergency stop belongs to it.
    if (!a.stepped) {
        signals.onSecondSignal([&runtime] { runtime.emergencyStop(); });
    }
    // The view binds before the devices open: a port in use fails the run before it starts.
    LiveView view(a.view, "hapto run", scene, runtime);

    const bool live = !a.quiet && isatty(STDERR_FILENO);
    char header[256];
    std::snprintf(header, sizeof header,
                  "hapto run: %zu devices, %u objects (%zu dynamic), index %s, %.1f s%s%s\n",
                  configs.size(), scene.size(), runtime.bodyIds().size(), spec.toString().c_str(),
                  a.durationS, a.durationS <= 0 ? " (until Ctrl-C)" : "",
                  a.stepped ? ", stepped" : "");
    SessionOptions options;
    options.durationS = a.durationS;
    options.steppedClock = a.stepped ? &clock : nullptr;
    options.stopRequested = [&signals] { return signals.requested(); };
    recorders.addTo(options);
    Session session(runtime, std::move(options));
    RunReport r;
    {
        // Everything for the terminal goes through its own thread while devices are driven: a
        // paused terminal blocks only that thread, never the session, its stop or its signals.
        LiveLines terminal(live ? &runtime : nullptr);
        terminal.say(header);
        // No device opened (of some): the recordings are abandoned, older traces stay.
        if (session.start() == 0 && !configs.empty()) {
            std::string why;
            for (const DeviceReport& d : runtime.report().devices) {
                why += "hapto run: " + d.name + ": " + d.fault + "\n";
            }
            if (recorders.bodies) {
                recorders.bodies->abandon(); // the run failed: an older bodies.trace stays
            }
            terminal.say(why + "hapto run: no device could be opened\n");
            return 1;
        }
        view.start();
        session.run([&](double) {
            view.update(world);
            return true;
        });
        r = session.stop(); // zero force on every device before anything else
        view.stop();
    }
    return finishRun(a, r, signals);
}

} // namespace

void addRunCommands(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "run", "Run a haptic session: one servo thread per device over one shared index, "
               "reporting each device's haptic load");
    auto a = std::make_shared<RunArgs>();
    cmd->add_option("--scene", a->scene, "Scene file (default: the embedded default scene)");
    cmd->add_option("--devices", a->devices,
                    "Device configuration file (default: two simulated hands, left and right)");
    addIndexOption(cmd, a->index);
    addMaxIndexMbOption(cmd, a->maxIndexMb);
    cmd->add_option("--rate", a->rateHz,
                    "Servo rate for every device (Hz; default: each device's own)")
        ->check(finiteRange(100, 100000));
    cmd->add_option("--duration", a->durationS, "Run time (s); 0 runs until Ctrl-C")
        ->capture_default_str()
        ->check(finiteRange(0, 1e8));
    cmd->add_option("--report", a->report, "Write the JSON report here");
    cmd->add_option("--record", a->record,
                    "Record every device's ticks into DIR/<name>.trace (see `hapto trace export`)");
    addRealtimeFlag(cmd, a->realtime, "");
    cmd->add_option("--spin-us", a->spinUs, "Spin this long before each deadline (us)")
        ->capture_default_str()
        ->check(finiteRange(0, 1000));
    cmd->add_option("--warm-us", a->warmUs,
                    "Wake this long before each deadline, touch the tick's working set and spin "
                    "to the deadline, so the tick starts warm; 0 = off (us; less than half the "
                    "period; default: 5 when each servo thread has a core of its own, else off; "
                    "docs/results/many-devices.md)")
        ->check(finiteRange(0, static_cast<double>(kMaxWarmUpNs) / 1000.0));
    cmd->add_option("--miss-limit", a->missLimit,
                    "K: after K missed deadlines in a row, command zero force until caught up")
        ->capture_default_str()
        ->check(finiteRange(1, 1000000));
    cmd->add_option("--reopen-ms", a->reopenMs,
                    "After a device fault (zero force at once), close the device and try to open "
                    "it again this often, then drive it again from zero force (ms); 0 = never")
        ->capture_default_str()
        ->check(finiteRange(0, 3600000));
    cmd->add_option("--devices-per-thread", a->devicesPerThread,
                    "Simulated devices only: run K devices on one servo thread, each with its own "
                    "deadline, load record and safety; 1 = one servo thread per device")
        ->capture_default_str()
        ->check(finiteRange(1, static_cast<double>(kMaxSessionDevices)));
    addWakeLatencyOption(cmd, a->wakeLatencyUs, "the devices run (unset: no request)");
    cmd->add_flag("--quiet", a->quiet, "No live lines on the terminal");
    cmd->add_flag("--no-devices", a->noDevices,
                  "Drive no device: only the scene's dynamic bodies run (the scene must have one)");
    cmd->add_flag("--stepped", a->stepped,
                  "Run on the step mode's clock, as fast as the CPU allows, the same every run "
                  "(simulated hands and replays only; real-time scheduling is not used)");
    addViewOptions(cmd, a->view);
    setExamples(cmd, {"hapto run --duration 10 --view",
                      "hapto run --scene scene.json --devices hands.json --report run.json",
                      "hapto run --record traces --duration 5   # then: hapto view --trace traces",
                      "hapto run --scene drop.json --no-devices --stepped --report drop-run.json"});
    cmd->callback([a] {
        if (a->noDevices && !a->devices.empty()) {
            throw InputError("--no-devices drives no device: give it or --devices " + a->devices +
                             ", not both");
        }
        const int rc = runSession(*a);
        if (rc != 0) {
            std::exit(rc);
        }
    });
}

} // namespace hapto::cli
