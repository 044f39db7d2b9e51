// Checks made on a session's arguments before any device starts.

#include "SessionChecks.h"

#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/runtime/Session.h"
#include "hapto/runtime/World.h"

#include <cstdio>
#include <filesystem>
#include <utility>
#include <variant>
#include <vector>

namespace hapto::cli {
namespace fs = std::filesystem;

void checkDeviceCount(std::size_t devices, const std::string& source) {
    if (devices > kMaxSessionDevices) {
        throw InputError((source.empty() ? std::string("the session") : "--devices " + source) +
                         ": " + std::to_string(devices) + " devices, but one session drives at " +
                         "most " + std::to_string(kMaxSessionDevices) +
                         " (one servo thread each); split them over several sessions");
    }
}

void checkSpinAgainstRates(double spinUs, std::span<const DeviceConfig> configs) {
    for (const DeviceConfig& c : configs) {
        const double periodUs = 1e6 / c.rateHz;
        if (spinUs > 0 && spinUs >= periodUs) {
            char text[256];
            std::snprintf(text, sizeof text,
                          "--spin-us %g: not shorter than the servo period of device '%s' "
                          "(%g us at %g Hz); spin less than the period, or run slower",
                          spinUs, c.name.c_str(), periodUs, c.rateHz);
            throw InputError(text);
        }
    }
}

void checkSessionFiles(const SessionPaths& paths, std::span<const DeviceConfig> configs) {
    // Every file the session reads.
    std::vector<std::pair<fs::path, std::string>> inputs;
    if (!paths.scene.empty()) {
        inputs.emplace_back(paths.scene, "--scene");
    }
    if (!paths.devices.empty()) {
        inputs.emplace_back(paths.devices, "--devices");
    }
    for (const DeviceConfig& c : configs) {
        if (const auto* replay = std::get_if<ReplayConfig>(&c.params)) {
            inputs.emplace_back(replay->trace, "the trace replay device '" + c.name + "' reads");
        }
    }
    const auto refuseInputs = [&](const fs::path& output, const std::string& option) {
        for (const auto& [input, what] : inputs) {
            refuseSameFile(output, option, input, what);
        }
    };
    if (!paths.report.empty()) {
        refuseInputs(paths.report, "--report");
        checkOutputFile(paths.report, "--report");
    }
    if (!paths.record.empty()) {
        checkOutputFolder(paths.record, "--record");
        for (const DeviceConfig& c : configs) {
            const fs::path trace = fs::path(paths.record) / (c.name + ".trace");
            const std::string option = "--record (device '" + c.name + "')";
            refuseInputs(trace, option);
            if (sameFile(trace, paths.report)) {
                throw InputError("--report " + paths.report + " is where --record writes device '" +
                                 c.name + "''s trace; give the report another name");
            }
            checkOutputKind(trace, option); // a folder, FIFO, socket or device there
        }
    }
}

void checkSteppable(std::span<const DeviceConfig> configs) {
    for (const DeviceConfig& c : configs) {
        if (!runsOnStepClock(c.kind)) {
            throw InputError("--stepped: device '" + c.name + "' is a " +
                             std::string(name(c.kind)) +
                             "; only simulated hands (sim) and replays run on the step clock (a "
                             "hardware device keeps real time: run it without --stepped)");
        }
    }
}

void checkBodyTraceFile(const SessionPaths& paths, std::span<const DeviceConfig> configs) {
    if (paths.record.empty()) {
        return;
    }
    const fs::path trace = fs::path(paths.record) / kBodyTraceFileName;
    const std::string option = std::string("--record (") + kBodyTraceFileName + ")";
    for (const DeviceConfig& c : configs) {
        if (c.name + ".trace" == kBodyTraceFileName) {
            throw InputError("--record " + paths.record + ": device '" + c.name +
                             "''s trace would be " + trace.string() +
                             ", where the dynamic bodies are recorded; rename the device");
        }
        if (const auto* replay = std::get_if<ReplayConfig>(&c.params)) {
            refuseSameFile(trace, option, replay->trace,
                           "the trace replay device '" + c.name + "' reads");
        }
    }
    if (!paths.scene.empty()) {
        refuseSameFile(trace, option, paths.scene, "--scene");
    }
    if (!paths.devices.empty()) {
        refuseSameFile(trace, option, paths.devices, "--devices");
    }
    if (sameFile(trace, paths.report)) {
        throw InputError("--report " + paths.report +
                         " is where --record writes the dynamic "
                         "bodies' trace; give the report another name");
    }
    checkOutputKind(trace, option);
}

} // namespace hapto::cli
