#pragma once
/// A device file (`--devices D.json`) read whole: each device's own configuration
/// (hapto::devices) and what the runtime renders for it besides the scene, its force effects and
/// renderer settings (the entries' `effects` and `renderer`, read here).

#include "hapto/devices/DeviceConfig.h"
#include "hapto/runtime/ForceEffect.h"
#include "hapto/runtime/RendererSettings.h"

#include <cstddef>
#include <filesystem>
#include <string_view>
#include <vector>

namespace hapto {

/// What the runtime renders for one device besides the scene (RuntimeDevice::rendering).
struct DeviceRendering {
    /// Force effects from the first tick on, at most kMaxEffectsPerDevice, each passing
    /// checkForceEffect(). JSON `effects`.
    std::vector<ForceEffect> effects;
    /// The device's own renderer settings. JSON `renderer`.
    RendererSettings renderer;
};

/// A device file's devices in file order, and what the runtime renders for each.
struct DeviceFile {
    std::vector<DeviceConfig> devices;      ///< Each device's own configuration.
    std::vector<DeviceRendering> rendering; ///< devices[i]'s at index i; a missing one is none.

    /// devices[i]'s rendering; none (no effect, the runtime's renderer) past the end of
    /// `rendering`, as in a DeviceFile made in code from devices alone. [control]
    DeviceRendering renderingOf(std::size_t i) const {
        return i < rendering.size() ? rendering[i] : DeviceRendering{};
    }
};

/// Loads a device configuration file (format "hapto-devices", README.md "Device configuration
/// files"): loadDeviceConfigFile() with each entry's `effects` and `renderer` read too. Throws
/// InputError naming the file and the JSON path (e.g. `devices[1].effects[0].type`). [control]
DeviceFile loadDeviceFile(const std::filesystem::path& path);
/// Parses device configuration JSON as loadDeviceFile() does; `sourceName` names it in
/// messages. Throws InputError. [control]
DeviceFile parseDeviceFile(std::string_view text, std::string_view sourceName);

} // namespace hapto
