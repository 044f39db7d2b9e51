#include "hapto/devices/HandScript.h"

#include <array>
#include <utility>

namespace hapto {
namespace {

constexpr std::array<std::pair<HandScript, std::string_view>, 6> kScriptNames = {{
    {HandScript::Free, "free"},
    {HandScript::Touch, "touch"},
    {HandScript::Slide, "slide"},
    {HandScript::Walk, "walk"},
    {HandScript::GraspLeft, "grasp-left"},
    {HandScript::GraspRight, "grasp-right"},
}};

} // namespace

std::string_view name(HandScript script) noexcept {
    for (const auto& [s, n] : kScriptNames) {
        if (s == script) {
            return n;
        }
    }
    return "unknown";
}

std::optional<HandScript> parseHandScript(std::string_view text) noexcept {
    for (const auto& [s, n] : kScriptNames) {
        if (n == text) {
            return s;
        }
    }
    return std::nullopt;
}

} // namespace hapto
