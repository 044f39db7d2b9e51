// `hapto view`: the view's page over a recorded session, with play, pause and a time slider;
// the devices' traces and, when the folder (or the list) has one, the dynamic bodies'
// (bodies.trace, told from a device trace by its magic).

#include "Commands.h"
#include "Options.h"
#include "StopSignals.h"

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/TraceReader.h"
#include "hapto/io/InputError.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/view/ViewDocuments.h"
#include "hapto/view/ViewServer.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <thread>

namespace hapto::cli {
namespace {

struct ViewCommandArgs {
    std::string scene;
    std::vector<std::string> traces;
    std::string devices;
    ViewArgs view;
    double durationS = 0;
};

// The trace files named: files as given, folders for their *.trace files (sorted by name).
std::vector<std::filesystem::path> traceFiles(const std::vector<std::string>& named) {
    std::vector<std::filesystem::path> files;
    for (const std::string& n : named) {
        std::error_code ec;
        if (std::filesystem::is_directory(n, ec)) {
            std::vector<std::filesystem::path> found;
            for (const auto& entry : std::filesystem::directory_iterator(n)) {
                if (entry.path().extension() == ".trace") {
                    found.push_back(entry.path());
                }
            }
            if (found.empty()) {
                throw InputError(n + ": no .trace files in this folder (see `hapto run --record`)");
            }
            std::sort(found.begin(), found.end());
            files.insert(files.end(), found.begin(), found.end());
        } else {
            files.emplace_back(n); // TraceReader refuses what is not a readable regular file
        }
    }
    return files;
}

// The body trace among `files`, taken out of them (at most one).
std::optional<BodyTrace> takeBodyTrace(std::vector<std::filesystem::path>& files) {
    std::optional<BodyTrace> bodies;
    for (auto it = files.begin(); it != files.end();) {
        if (!isBodyTrace(*it)) {
            ++it;
            continue;
        }
        if (bodies) {
            throw InputError(it->string() + ": a second body trace; give one session's traces");
        }
        bodies = readBodyTrace(*it);
        it = files.erase(it);
    }
    return bodies;
}

void runView(const ViewCommandArgs& a) {
    StopSignals signals; // before the server's threads start
    const Scene scene = loadSceneOrDefault(a.scene);
    // Each trace is placed in the world by the device of its name (from --devices, or the
    // default two hands); a trace of another name stays in its device frame.
    // Read whole, so a bad effect is refused here as in `hapto run`.
    const std::vector<DeviceConfig> configs =
        a.devices.empty() ? defaultDeviceConfigs() : loadDeviceFile(a.devices).devices;
    std::vector<ViewTrace> traces;
    std::vector<ViewDevice> devices;
    std::vector<std::filesystem::path> files = traceFiles(a.traces);
    const std::optional<BodyTrace> bodies = takeBodyTrace(files);
    for (const auto& file : files) {
        ViewTrace t;
        t.samples = TraceReader::load(file, &t.header);
        for (const DeviceConfig& c : configs) {
            if (c.name == t.header.name) {
                t.transform = c.transform;
            }
        }
        devices.push_back({t.header.name, t.header.rateHz});
        traces.push_back(std::move(t));
    }
    ViewServerOptions options;
    options.bindAddress = a.view.bindAddress;
    options.port = a.view.port;
    options.liveStream = false; // the page plays the recording: no stream to hold a place
    signals.endStartUp();       // a signal from now on stops the server in order
    ViewServer server(options);
    server.setDocument("/scene.json", viewSceneJson(scene, devices, ViewMode::Trace));
    server.setDocument("/trace.json",
                       viewTraceJson(scene, traces, 60.0, bodies ? &*bodies : nullptr));
    server.start();
    if (!isLoopbackAddress(a.view.bindAddress)) {
        std::fprintf(stderr,
                     "hapto view: warning: listening on %s, not on this machine only: anyone "
                     "who can reach port %d can watch this recording\n",
                     a.view.bindAddress.c_str(), server.port());
    }
    std::fprintf(stderr, "hapto view: %zu trace(s)%s on %s%s\n", traces.size(),
                 bodies ? " and the dynamic bodies" : "", server.url().c_str(),
                 a.durationS > 0 ? "" : " (Ctrl-C to stop)");
    std::fflush(stderr);
    const auto start = std::chrono::steady_clock::now();
    while (!signals.requested() &&
           (a.durationS <= 0 || std::chrono::steady_clock::now() - start <
                                    std::chrono::duration<double>(a.durationS))) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    server.stop();
}

} // namespace

void addViewCommands(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "view", "Serve the 3-D view over a recorded session (traces from `hapto run --record`) "
                "with play, pause and a time slider, in the browser at the address it prints");
    setExamples(cmd, {"hapto view --trace traces   # after hapto run --record traces",
                      "hapto view --trace traces/left.trace --scene scene.json --view-port 0"});
    auto a = std::make_shared<ViewCommandArgs>();
    cmd->add_option("--scene", a->scene, "Scene file (default: the embedded default scene)");
    cmd->add_option("--trace", a->traces, "Trace folder (its *.trace files) or trace files")
        ->required()
        ->expected(1, -1);
    cmd->add_option("--devices", a->devices,
                    "Device configuration placing each trace's device in the world, by name "
                    "(default: the default two hands)");
    addViewPortOption(cmd, a->view);
    addRenamedOption(cmd, "--port", "--view-port PORT", "as in run and demo grasp");
    addViewBindOption(cmd, a->view);
    cmd->add_option("--duration", a->durationS, "Serve this long (s); 0 serves until Ctrl-C")
        ->capture_default_str()
        ->check(finiteRange(0, 1e8));
    cmd->callback([a] { runView(*a); });
}

} // namespace hapto::cli
