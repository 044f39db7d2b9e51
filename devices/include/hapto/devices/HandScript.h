#pragma once
/// HandScript: the closed set of simulated-hand scripts, parsed once from `"sim": {"script"}`.

#include <cstdint>
#include <optional>
#include <string_view>

namespace hapto {

/// What a simulated hand does (SimConfig::script; planned by SimScript).
enum class HandScript : std::uint8_t {
    Free,       ///< "free": moves through free space near objects, touching none.
    Touch,      ///< "touch": presses still on a surface.
    Slide,      ///< "slide": presses while sliding along a surface.
    Walk,       ///< "walk": random hops through the scene.
    GraspLeft,  ///< "grasp-left": the left finger of a two-hand grasp.
    GraspRight, ///< "grasp-right": the right finger of a two-hand grasp.
};

/// The script's name as a file spells it ("free", "touch", ..., "grasp-right"). [any thread]
std::string_view name(HandScript script) noexcept;

/// The script a file or an option names; nullopt for anything else. [any thread]
std::optional<HandScript> parseHandScript(std::string_view text) noexcept;

} // namespace hapto
