#include "hapto/devices/DeviceKind.h"

#include <array>
#include <utility>

namespace hapto {
namespace {

constexpr std::array<std::pair<DeviceKind, std::string_view>, 5> kKindNames = {{
    {DeviceKind::Sim, "sim"},
    {DeviceKind::Replay, "replay"},
    {DeviceKind::Falcon, "falcon"},
    {DeviceKind::Phantom, "phantom"},
    {DeviceKind::Scripted, "scripted"},
}};

} // namespace

std::string_view name(DeviceKind kind) noexcept {
    for (const auto& [k, n] : kKindNames) {
        if (k == kind) {
            return n;
        }
    }
    return "unknown";
}

std::optional<DeviceKind> parseDeviceKind(std::string_view text) noexcept {
    for (const auto& [k, n] : kKindNames) {
        if (n == text && k != DeviceKind::Scripted) {
            return k;
        }
    }
    return std::nullopt;
}

} // namespace hapto
