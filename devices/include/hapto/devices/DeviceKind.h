#pragma once
/// DeviceKind: the closed set of device kinds, parsed once from a configuration file's "kind".

#include <cstdint>
#include <optional>
#include <string_view>

namespace hapto {

/// What drives a device: the configuration file's `"kind"`.
enum class DeviceKind : std::uint8_t {
    Sim,      ///< "sim": a simulated hand (SimDevice).
    Replay,   ///< "replay": playback of a recorded trace (ReplayDevice).
    Falcon,   ///< "falcon": a Novint Falcon over libusb (FalconDevice).
    Phantom,  ///< "phantom": a PHANToM or Touch through OpenHaptics (PhantomDevice).
    Scripted, ///< "scripted": a device the embedding program makes itself (the tests' scripted
              ///< devices); never read from a file, never made by makeDevice.
};

/// The kind's name as a file spells it ("sim", "replay", "falcon", "phantom", "scripted").
/// [any thread]
std::string_view name(DeviceKind kind) noexcept;

/// The kind a configuration file names; nullopt for anything else, "scripted" included.
/// [any thread]
std::optional<DeviceKind> parseDeviceKind(std::string_view text) noexcept;

} // namespace hapto
