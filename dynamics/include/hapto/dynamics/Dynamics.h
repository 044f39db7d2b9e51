#pragma once
/// Rigid-body dynamics over a hapto scene: the scene's dynamic objects (BodyProperties) move
/// under gravity, contacts with the static scene (found through the shared spatial index and
/// the exact shape tests of Contact.h) and with each other, Coulomb friction and restitution,
/// and impulses handed in by the hands. SI units throughout (m, kg, s, N).
///
/// Design note: see docs/DESIGN.md, "Dynamics". Invariants: step() never allocates, locks,
/// logs or throws (everything it needs is allocated by the constructor); it is deterministic
/// (the same construction and the same calls give the same states, bit for bit); a body never
/// gains energy from contacts (restitution <= 1, no contact pushes harder than it must).

#include "hapto/core/Geometry.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/Scene.h"

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace hapto {

/// Solver settings. The defaults are what the scenes and tests here use.
struct DynamicsOptions {
    int velocityIterations = 10;       ///< Sequential-impulse passes per step.
    double penetrationSlopM = 1e-4;    ///< Overlap left uncorrected (m), so resting contacts
                                       ///< persist from step to step.
    double positionCorrection = 0.2;   ///< Fraction of the overlap beyond the slop removed per
                                       ///< step (split impulse: adds no kinetic energy).
    double speculativeMarginM = 1e-3;  ///< Contacts are gathered this far out, plus the
                                       ///< distance the pair can close in one step (m).
    double sleepSpeedMPerS = 2e-3;     ///< A body slower than this (centre of mass) ...
    double sleepAngularRadPerS = 2e-2; ///< ... and turning slower than this ...
    double sleepAfterS = 0.5;          ///< ... for this long falls asleep (0: never sleeps).
    /// Restitution acts on contacts closing faster than this (m/s): slower impacts end at
    /// rest. Above g dt (0.01 m/s at 1 kHz), so a resting contact never bounces.
    double restitutionThresholdMPerS = 0.05;
    /// A new contact, or a sliding one, sticks (static friction, an anchor) when its
    /// tangential speed is below this (m/s).
    double stickSpeedMPerS = 1e-2;
};

/// One body's state (world frame). Plain value.
struct BodyState {
    ObjectId id = 0;              ///< The scene object's id.
    std::uint32_t slot = 0;       ///< The scene object's slot.
    Vec3 position{0.0};           ///< Centre of mass (m).
    Quat orientation{1, 0, 0, 0}; ///< The object's rotation (unit).
    Vec3 velocity{0.0};           ///< Of the centre of mass (m/s).
    Vec3 angularVelocity{0.0};    ///< (rad/s).
    bool sleeping = false;        ///< Asleep: not integrated until woken.
};

/// What was measured of one body since the start.
struct BodyStats {
    double deepestPenetrationM = 0.0; ///< Largest overlap with anything, after a step (m).
    /// Largest rise of the body's energy (kinetic + potential in gravity) minus the work the
    /// hands did on it, over any interval (J): 0 for a body contacts never push into motion.
    double largestEnergyGainJ = 0.0;
};

/// Steps a scene's dynamic bodies. One instance per session; every member is used by one
/// thread (the dynamics thread, or the step mode's), except where marked.
class Dynamics {
public:
    /// Takes the scene's dynamic objects as bodies (in slot order) at their scene poses and
    /// velocities; `index` (built over the same scene, so its items are the scene's) finds
    /// the static objects a body may touch: items of dynamic objects are skipped. Both must
    /// stay alive for the dynamics' life. Allocates everything step() needs. [control]
    Dynamics(std::shared_ptr<const Scene> scene, std::shared_ptr<const SpatialIndex> index,
             DynamicsOptions options = {});
    ~Dynamics();
    Dynamics(const Dynamics&) = delete;
    Dynamics& operator=(const Dynamics&) = delete;

    /// Advances every awake body by one step of dtS(). Never allocates, locks or throws.
    void step() noexcept;
    /// The step (s): 1 / the scene's ScenePhysics::rateHz.
    double dtS() const noexcept { return mDtS; }
    /// Steps taken.
    std::uint64_t stepCount() const noexcept { return mSteps; }

    /// Number of bodies.
    std::size_t bodyCount() const noexcept { return mBodies.size(); }
    /// Every body's state, in the scene's slot order.
    std::span<const BodyState> bodies() const noexcept { return mBodies; }
    /// The body of a scene object, if it is dynamic.
    std::optional<std::size_t> bodyOf(ObjectId id) const noexcept;
    /// What was measured of body i.
    const BodyStats& stats(std::size_t i) const noexcept { return mStats[i]; }
    /// Body i's kinetic plus potential energy (J; potential 0 at the world origin).
    double energyJ(std::size_t i) const noexcept;

    /// Where body i's scene object is now: its `center` (m) and `rotation`, as SceneObject
    /// spells them (the centre of mass moved back by the rotated BodyProperties offset).
    void objectPose(std::size_t i, Vec3& center, Quat& rotation) const noexcept;

    /// Applies an impulse to body i at the start of the next step, waking it: linear (N s,
    /// world) and angular about its centre of mass (N m s, world); what the hands hand back
    /// (BodyPoseTable::takeImpulse's sums). A zero impulse does nothing (it wakes no body).
    /// Never allocates.
    void applyImpulse(std::size_t i, const Vec3& linearNs, const Vec3& angularNms) noexcept;
    /// The hands' torsional friction on body i for the next step (their soft-finger patches,
    /// runtime/BodyCoupling.h): `budgetNms` = sum over the hands' sent ticks of
    /// mu |Fn| r dt n n^T (N m s; symmetric, positive semidefinite; n a contact normal). Adds
    /// to the next step's pending angular impulse the impulse that stops the body's spin (after
    /// the impulses applyImpulse already gave it for that step) about each principal axis of
    /// the budget, clamped to the budget about that axis: about one axis, or two opposed hands'
    /// common one, this is Coulomb's torsional friction exactly. It only opposes the spin, so
    /// it never adds kinetic energy. Call it after the step's applyImpulse. Never allocates.
    /// (dynamics/src/DynamicsHands.cpp)
    void applyHandTorsion(std::size_t i, const Mat3& budgetNms) noexcept;
    /// Wakes body i (and it stays awake for at least sleepAfterS).
    void wake(std::size_t i) noexcept;
    /// Candidates and contacts a step had no room for, since the start (0 unless a body
    /// touches more than the fixed capacities allow: 256 static items, 64 contact points
    /// a body).
    std::uint64_t droppedContacts() const noexcept;

    struct Impl; ///< The solver's preallocated working state (dynamics/src/DynamicsImpl.h).

private:
    void recordPenetration() noexcept;
    void updateEnergyStats() noexcept;
    std::shared_ptr<const Scene> mScene;
    std::shared_ptr<const SpatialIndex> mIndex;
    DynamicsOptions mOptions;
    double mDtS = 1e-3;
    std::uint64_t mSteps = 0;
    std::vector<BodyState> mBodies;
    std::vector<BodyStats> mStats;
    std::unique_ptr<Impl> mImpl; // the solver's preallocated working state
};

} // namespace hapto
