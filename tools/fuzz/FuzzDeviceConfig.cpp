// libFuzzer target: the device configuration loader, the runtime's effects and renderer fields
// included. Any input loads or is refused with an
// InputError; nothing else may escape, crash, hang or leak.

#include "hapto/io/InputError.h"
#include "hapto/runtime/DeviceFile.h"

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        const hapto::DeviceFile file = hapto::parseDeviceFile(
            std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.json");
        for (const hapto::DeviceConfig& c : file.devices) {
            // What loaded is what the runtime relies on.
            if (c.name.empty() || !(c.rateHz >= 100.0 && c.rateHz <= 100000.0) ||
                !(c.transform.scale > 0.0) || !(c.maxForceN >= 0.0)) {
                __builtin_trap();
            }
        }
    } catch (const hapto::InputError&) {
    }
    return 0;
}
