// The recorders of `--record DIR` (see SessionRecorders.h).

#include "SessionRecorders.h"

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

} // namespace hapto::cli
