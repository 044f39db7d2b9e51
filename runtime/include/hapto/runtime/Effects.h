#pragma once
/// Force effects on the servo path: one effect's force, and a device's fixed-capacity set.
///
/// Design note. An effect is a plain value (ForceEffect, ForceEffect.h; a device file carries
/// it, DeviceFile.h); a device's effects are an EffectSet, a fixed array of
/// kMaxEffectsPerDevice values and a count: trivially copyable, never allocating. The servo
/// thread owns one EffectSet inside its HapticTick and sums its force every tick after the
/// renderer and before the safety filter. The control thread never touches that copy: it
/// publishes a whole new set through a seqlock mailbox (Runtime::setEffects), and the servo
/// thread copies it in at its next tick (a cheap version check every tick, a copy only when
/// something changed). Neither side waits for the other. Cost per tick: one branch per effect
/// slot in use, a few multiply-adds each.

#include "hapto/core/Geometry.h"
#include "hapto/runtime/ForceEffect.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

namespace hapto {

/// The force (N, world frame) of `effect` at the device point `pointM` (m, world) moving at
/// `velocityMPerS` (m/s, world): zero when it is off or the point is outside its region;
/// otherwise a spring gives -k r, where r is the offset from the anchor (point), from the line
/// (its part across the direction) or from the plane (its part along the normal); a damper
/// -b v; a constant force its force. [servo]
Vec3 effectForceN(const ForceEffect& effect, const Vec3& pointM,
                  const Vec3& velocityMPerS) noexcept;

/// A device's force effects: up to kCapacity plain values in a fixed array. Trivially
/// copyable, so it crosses threads through a Mailbox.
class EffectSet {
public:
    /// Effects one set holds.
    static constexpr std::size_t kCapacity = kMaxEffectsPerDevice;

    /// No effect. [any thread]
    EffectSet() = default;
    /// The effects `effects`, in order. Throws std::invalid_argument naming the effect's index
    /// and field when there are more than kCapacity or one fails checkForceEffect(). [control]
    explicit EffectSet(std::span<const ForceEffect> effects);

    /// The effects, in order. [servo]
    std::span<const ForceEffect> effects() const noexcept { return {mEffects.data(), mCount}; }
    /// How many effects there are. [servo]
    std::size_t size() const noexcept { return mCount; }
    /// Turns effect `index` on or off; false when there is no such effect. [servo]
    bool setEnabled(std::size_t index, bool enabled) noexcept;
    /// The summed force (N, world) of every effect at `pointM` (m) moving at `velocityMPerS`
    /// (m/s), as effectForceN(). [servo]
    Vec3 forceN(const Vec3& pointM, const Vec3& velocityMPerS) const noexcept;

private:
    std::array<ForceEffect, kCapacity> mEffects{};
    std::uint32_t mCount = 0;
};
static_assert(std::is_trivially_copyable_v<EffectSet>);

} // namespace hapto
