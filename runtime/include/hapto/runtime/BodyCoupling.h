#pragma once
/// One haptic tick's side of the coupling to the dynamic bodies: where it reads their poses,
/// the bodies it placed near the tool, and the reaction it owes them until the force is sent.
///
/// Design note. A tick (HapticTick) places the dynamic bodies near the tool from the
/// BodyPoseTable (place()), renders them, splits the part of the sent force the contacts exert
/// among its <= 3 contact planes (split()) and, once the device was sent that force, hands each
/// touched body the reaction of its share (handBack()): -share x dt at the contact point, and a
/// torsional-friction budget about the contact normal (the soft-finger patch, below). The
/// shares wait here between split() and handBack(); handBack() empties them, so nothing is
/// handed back twice and a tick whose force was not sent hands back nothing.
///
/// Torsional friction (soft-finger contact). A point contact transmits no moment, so two hands
/// pressing a body cannot stop it turning about the line between them. A real fingertip or
/// tool tip touches over a patch, which resists spin about the contact normal up to a Coulomb
/// moment mu |Fn| r: the "soft finger" contact of grasp analysis (Salisbury; Mason and
/// Salisbury, "Robot Hands and the Mechanics of Manipulation", MIT Press 1985), Bullet's
/// spinning friction (btContactSolverInfo / btCollisionObject::m_spinningFriction, a torque
/// limit proportional to the normal impulse). `r` is the patch's effective torsional radius:
/// for a uniform pressure p = Fn / (pi a^2) over a disc of radius a, the friction moment is
/// int_0^a mu p rho (2 pi rho) d rho = 2/3 mu Fn a, so r = 2a/3. The hand is a 3-DOF point: it
/// feels no moment; only the body is acted on. The tick does not apply the moment itself: each
/// sent tick adds the budget mu |Fn| r dt (N m s) about the normal n to the body's record in
/// the table as the sign-free tensor budget * n n^T, and the dynamics step spends it
/// (Dynamics::applyHandTorsion): an angular impulse that stops the body's spin about each axis,
/// clamped to the budget. The step knows the inertia, so the stop is exact at any mass and can
/// only take kinetic energy away; a torque computed here from the spin would be a viscous
/// coupling, unstable for light bodies at the servo's period.
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

/// The largest torsional-friction radius a device may set (m): 5 cm, beyond any fingertip pad
/// or tool tip (the radius is an effective one, 2/3 of a uniform disc's) and larger than the
/// bodies the hands hold here.
inline constexpr double kMaxTorsionRadiusM = 0.05;

/// One tick's coupling to the dynamic bodies. [servo] (one per haptic tick, used by the thread
/// that ticks)
class BodyCoupling {
public:
    /// A coupling whose hand has a contact patch of effective torsional radius `torsionRadiusM`
    /// (m, 0..kMaxTorsionRadiusM; 0: a point contact, no torsional friction). Throws
    /// std::invalid_argument otherwise. [control]
    explicit BodyCoupling(double torsionRadiusM = 0.0);

    /// The next place() reads the bodies from `table` (null: none), extrapolated to `nowNs`
    /// (the table's clock). [servo]
    void use(BodyPoseTable* table, std::uint64_t nowNs) noexcept {
        mTable = table;
        mNowNs = nowNs;
    }
    /// Places the snapshot's dynamic bodies whose bounding sphere comes within `reachM` (m) of
    /// the device point `p` or the proxy, at their table poses extrapolated to the time use()
    /// gave, and where the same motion had them `dtS` before; forgets the shares. A body the
    /// snapshot holds at rest in its index (WorldSnapshot::rest) is left to the index while
    /// the table shows it asleep at that pose, and placed wherever it is otherwise (awake, or
    /// asleep elsewhere: its index copy is stale). Returns false when no body could be placed
    /// (no table, or no dynamic object). [servo]
    bool place(const WorldSnapshot& snapshot, const Vec3& p, const Vec3& proxy, double reachM,
               double dtS) noexcept;
    /// Splits `felt` (N), the part of the force to send that the contacts of `render` exert,
    /// among the contact planes, keeps the shares of the placed bodies and of the bodies
    /// `snapshot` renders from its index at rest for handBack() and adds them to
    /// `reactionN`. [servo]
    void split(const WorldSnapshot& snapshot, const RenderOutput& render, const Vec3& felt,
               Vec3& reactionN) noexcept;
    /// The force split() saw was sent: hands each share's body its reaction (-share x `dtS`
    /// N s at the contact point, linear and about its centre of mass) and its torsional budget
    /// (mu |Fn| r dtS N m s about the contact normal) through the table, once (a second call
    /// adds nothing). Returns false when the table refused one (not finite, out of
    /// range). [servo]
    bool handBack(double dtS) noexcept;

    /// The bodies the last place() placed. [servo]
    const DynamicBodySet& bodies() const noexcept { return mPlaced; }

    /// The hand's effective torsional radius (m). [any thread]
    double torsionRadiusM() const noexcept { return mTorsionRadiusM; }

private:
    /// A dynamic body's share of the last tick's force, waiting for handBack().
    struct Share {
        std::uint32_t body = 0; ///< Its body in the table.
        Vec3 forceN{0.0};       ///< The share the hand is sent (N).
        Vec3 armM{0.0};         ///< The contact point from the body's centre of mass (m).
        Vec3 normal{0.0};       ///< The contact plane's unit normal (world).
        double torsionNm = 0.0; ///< Its torsional-friction limit mu |Fn| r (N m).
    };

    BodyPoseTable* mTable = nullptr; ///< The dynamic bodies' poses and impulses, or none.
    std::uint64_t mNowNs = 0;        ///< The time the next place() places them at (ns).
    double mTorsionRadiusM = 0.0;    ///< The hand's effective torsional radius (m).
    DynamicBodySet mPlaced;          ///< The bodies placed this tick.
    std::array<Share, 3> mShares{};  ///< The first mShareCount wait for handBack().
    std::uint8_t mShareCount = 0;
};

} // namespace hapto
