#pragma once
/// The dynamic bodies one servo tick renders: each near body placed at its pose read from the
/// BodyPoseTable and extrapolated to the tick's time, as the god-object renderer sees it.
///
/// Design note. The scene in a snapshot is immutable and shared by every thread, and its pose
/// of a dynamic object is the one it was loaded (or last indexed) at: stale. A tick therefore
/// places the dynamic bodies near the tool itself, in this fixed-size set (no allocation): for
/// each, its render copy (RenderBody) at the extrapolated pose, the pose as SceneObject spells
/// it, and the motion the reaction and the coupling damping need. The renderer reads a dynamic
/// object's pose only from here; an item of a dynamic object that the static index lists (its
/// stale place) is skipped, and a dynamic object that is not in the set is not near this tick.
/// Invariants: the entries' slots are distinct dynamic object slots of the snapshot's scene;
/// `slots` lists the first `count` of them in entry order (the candidate span).

#include "hapto/core/Geometry.h"
#include "hapto/scenes/Scene.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace hapto {

/// The dynamic bodies placed for one tick (world frame). [servo] (one per haptic tick)
struct DynamicBodySet {
    /// Bodies one tick can place near the tool; farther ones beyond it are not rendered that
    /// tick (HapticTick counts none). Only awake bodies take places: a body asleep in the
    /// snapshot's index is rendered from the index (WorldSnapshot::rest), so a scene may hold
    /// any number of sleeping bodies near the tool.
    static constexpr std::size_t kMaxBodies = 16;

    /// One placed body.
    struct Entry {
        std::uint32_t slot = 0; ///< The scene object's slot.
        std::uint32_t body = 0; ///< Its body in the BodyPoseTable (i-th dynamic object).
        RenderBody render;      ///< The render copy at the placed pose.
        /// The render copy where the same motion had it one servo period before: a proxy
        /// outside it and inside `render` was run into by the body (pushed out, not passed).
        RenderBody previous;
        Vec3 center{0.0};          ///< The placed SceneObject::center (m).
        Quat rotation{1, 0, 0, 0}; ///< The placed rotation (unit).
        Vec3 centerOfMass{0.0};    ///< The placed centre of mass (m).
        Vec3 velocity{0.0};        ///< Of the centre of mass (m/s).
        Vec3 angularVelocity{0.0}; ///< (rad/s).
        double massKg = 0.0;       ///< The body's mass (kg).

        /// The velocity of the body's material point at `p` (m/s, world). [any thread]
        Vec3 pointVelocity(const Vec3& p) const noexcept {
            return velocity + glm::cross(angularVelocity, p - centerOfMass);
        }
    };

    std::array<Entry, kMaxBodies> entries{};       ///< The first `count` are placed.
    std::array<std::uint32_t, kMaxBodies> slots{}; ///< Their slots, as a candidate span.
    std::uint32_t count = 0;                       ///< Bodies placed this tick.
    /// The scene has dynamic objects: their items found in the static index are skipped.
    bool active = false;

    /// The placed entry of a slot, or null. [servo]
    const Entry* find(std::uint32_t slot) const noexcept {
        for (std::uint32_t i = 0; i < count; ++i) {
            if (entries[i].slot == slot) {
                return &entries[i];
            }
        }
        return nullptr;
    }
    /// The placed slots, as a candidate span. [servo]
    std::span<const std::uint32_t> slotSpan() const noexcept {
        return std::span<const std::uint32_t>(slots.data(), count);
    }
    /// Forgets every body (`active` too). [servo]
    void clear() noexcept {
        count = 0;
        active = false;
    }
};

} // namespace hapto
