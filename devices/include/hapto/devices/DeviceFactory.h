#pragma once
/// Makes a Device from its configuration.

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/scenes/Scene.h"

#include <memory>

namespace hapto {

/// The device a configuration describes, not yet opened: "sim" (SimDevice; keeps a reference
/// to `scene`, which must outlive its open()), "replay" (ReplayDevice; loads its trace now),
/// "falcon" (FalconDevice, over libusb) or "phantom" (PhantomDevice; OpenHaptics' libHD is
/// loaded by its open(), so a missing driver or device is reported there, not here). Throws
/// InputError for a bad configuration or trace, and for a kind only a program makes
/// ("scripted"). [control]
std::unique_ptr<Device> makeDevice(const DeviceConfig& config, const Scene& scene);

} // namespace hapto
