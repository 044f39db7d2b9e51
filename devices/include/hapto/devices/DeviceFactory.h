#pragma once
/// Makes a Device from its configuration.

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/scenes/Scene.h"

#include <memory>

namespace hapto {

/// The device a configuration describes, not yet opened: "sim" (SimDevice; keeps a reference
/// to `scene`, which must outlive its open()) or "replay" (ReplayDevice; loads its trace now).
/// Throws InputError for a bad configuration or trace, and for "falcon" and "phantom" until
/// their backends are wired in. [control]
std::unique_ptr<Device> makeDevice(const DeviceConfig& config, const Scene& scene);

} // namespace hapto
