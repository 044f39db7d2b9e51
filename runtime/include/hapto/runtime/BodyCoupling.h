#pragma once
/// One haptic tick's side of the coupling to the dynamic bodies: where it reads their poses,
/// the bodies it placed near the tool, and the reaction it owes them until the force is sent.
///
/// Design note. A tick (HapticTick) places the dynamic bodies near the tool from the
/// BodyPoseTable (place()), renders them, splits the part of the sent force the contacts exert
/// among its <= 3 contact planes (split()) and, once the device was sent that force, hands each
/// touched body the reaction of its share (handBack()): -share x dt at the contact point. The
/// shares wait here between split() and handBack(); handBack() empties them, so nothing is
/// handed back twice and a tick whose force was not sent hands back nothing.
///
/// Invariants: nothing here allocates after construction, locks or throws outside the
/// constructor; the shares sum to the contact part of the force the hand is sent.

#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/DynamicBodySet.h"
#include "hapto/runtime/RenderOutput.h"
#include "hapto/runtime/World.h"

#include <array>
#include <cstdint>

namespace hapto {

/// One tick's coupling to the dynamic bodies. [servo] (one per haptic tick, used by the thread
/// that ticks)
class BodyCoupling {
public:
    /// The next place() reads the bodies from `table` (null: none), extrapolated to `nowNs`
    /// (the table's clock). [servo]
    void use(BodyPoseTable* table, std::uint64_t nowNs) noexcept {
        mTable = table;
        mNowNs = nowNs;
    }
    /// Places the snapshot's dynamic bodies whose bounding sphere comes within `reachM` (m) of
    /// the device point `p` or the proxy, at their table poses extrapolated to the time use()
    /// gave, and where the same motion had them `dtS` before; forgets the shares. Returns
    /// false when no body could be placed (no table, or no dynamic object). [servo]
    bool place(const WorldSnapshot& snapshot, const Vec3& p, const Vec3& proxy, double reachM,
               double dtS) noexcept;
    /// Splits `felt` (N), the part of the force to send that the contacts of `render` exert,
    /// among the contact planes, keeps the placed bodies' shares for handBack() and adds them
    /// to `reactionN`. [servo]
    void split(const Scene& scene, const RenderOutput& render, const Vec3& felt,
               Vec3& reactionN) noexcept;
    /// The force split() saw was sent: hands each share's body its reaction (-share x `dtS`
    /// N s at the contact point, linear and about its centre of mass) through the table, once
    /// (a second call adds nothing). Returns false when the table refused one (not finite, out of
    /// range). [servo]
    bool handBack(double dtS) noexcept;

    /// The bodies the last place() placed. [servo]
    const DynamicBodySet& bodies() const noexcept { return mPlaced; }

private:
    /// A dynamic body's share of the last tick's force, waiting for handBack().
    struct Share {
        std::uint32_t body = 0; ///< Its body in the table.
        Vec3 forceN{0.0};       ///< The share the hand is sent (N).
        Vec3 armM{0.0};         ///< The contact point from the body's centre of mass (m).
    };

    BodyPoseTable* mTable = nullptr; ///< The dynamic bodies' poses and impulses, or none.
    std::uint64_t mNowNs = 0;        ///< The time the next place() places them at (ns).
    DynamicBodySet mPlaced;          ///< The bodies placed this tick.
    std::array<Share, 3> mShares{};  ///< The first mShareCount wait for handBack().
    std::uint8_t mShareCount = 0;
};

} // namespace hapto
