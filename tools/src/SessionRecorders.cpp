// The recorders of `--record DIR` (see SessionRecorders.h).

#include "SessionRecorders.h"

#include "hapto/devices/DeviceFactory.h"

#include <chrono>
#include <filesystem>

namespace hapto::cli {

std::unique_ptr<TraceRecorder> recorderFor(const DeviceConfig& c, const std::string& folder) {
    TraceHeader header;
    header.rateHz = c.rateHz;
    header.kind = std::string(name(c.kind));
    header.name = c.name;
    header.transform = c.transform;
    header.toolTipM = c.toolTipM;
    header.maxForceN = c.maxForceN;
    header.startUnixNs =
        static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                       std::chrono::system_clock::now().time_since_epoch())
                                       .count());
    return std::make_unique<TraceRecorder>(std::filesystem::path(folder) / (c.name + ".trace"),
                                           header);
}

void Recorders::addTo(SessionOptions& options) const {
    for (const auto& rec : devices) {
        options.recorders.push_back(rec.get());
    }
    options.bodyRecorder = bodies.get();
}

std::vector<RuntimeDevice> recordedDevices(const DeviceFile& file, const Scene& scene,
                                           const std::string& folder, Recorders& recorders) {
    if (!folder.empty()) {
        std::filesystem::create_directories(folder);
    }
    std::vector<RuntimeDevice> devices;
    for (std::size_t i = 0; i < file.devices.size(); ++i) {
        const DeviceConfig& c = file.devices[i];
        RuntimeDevice rd{makeDevice(c, scene), c, nullptr, file.renderingOf(i)};
        if (!folder.empty()) {
            recorders.devices.push_back(recorderFor(c, folder));
            rd.recorder = recorders.devices.back().get();
        }
        devices.push_back(std::move(rd));
    }
    return devices;
}

void recordBodies(const Runtime& runtime, const std::string& folder, Recorders& recorders) {
    if (!folder.empty() && runtime.hasDynamics()) {
        recorders.bodies =
            std::make_unique<BodyTraceRecorder>(std::filesystem::path(folder) / kBodyTraceFileName,
                                                runtime.bodyIds(), runtime.dynamicsRateHz());
    }
}

} // namespace hapto::cli
