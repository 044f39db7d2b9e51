#pragma once
/// What a two-handed grasp of a dynamic body achieves while it is held: the body's slip
/// relative to the hands, the hands' vertical force against the body's weight, held or dropped.
///
/// Design note. A grasp is judged over a window the caller chooses (for the grasp scripts: from
/// the end of the squeeze, GraspTimes::kSqueezeEnd, to the end of the carry, kCarryEnd). At the
/// window's start, begin() notes the body's centre of mass relative to the midpoint of the two
/// hands; every add() after it measures how far that offset has moved since (the slip, m). A
/// body held by friction moves with the hands and its slip stays near zero; one squeezed too
/// lightly stays on the floor or slides down while the hands rise, and its slip grows to the
/// lift. The hands' force: the force sent to each hand is the reaction of what the hand exerts
/// on the body, so the upward support is -(F1 + F2) . up, and while the body does not
/// accelerate vertically it equals m g (Newton's second law); the error is
/// |-(F1 + F2) . up - m g| / (m g). The held verdict: the final slip is at most dropSlipM.
/// Invariants: slip and error are finite and >= 0 for finite samples; a non-finite sample is
/// counted and ignored. Cost: O(1) per add() (one double kept for the median); [control].

#include "hapto/core/Geometry.h"

#include <cstddef>
#include <optional>
#include <vector>

namespace hapto {
class Runtime;
}

namespace hapto::experiments {

/// One instant of a grasp, world frame.
struct GraspSample {
    Vec3 bodyM{0.0};   ///< The body's centre of mass (m).
    Vec3 handAM{0.0};  ///< Hand A's device point (m).
    Vec3 handBM{0.0};  ///< Hand B's device point (m).
    Vec3 forceAN{0.0}; ///< The force sent to hand A (N): the reaction of its push on the body.
    Vec3 forceBN{0.0}; ///< The force sent to hand B (N).
};

/// What GraspProbe judges by.
struct GraspProbeSettings {
    double massKg = 0.05;        ///< The body's mass (kg), > 0.
    double gravityMPerS2 = 9.81; ///< |g| (m/s^2), > 0.
    Vec3 up{0.0, 1.0, 0.0};      ///< Unit vector against gravity (the scene's +y by default).
    /// A final slip above this (m) is a drop: 10 mm, a fifth of the grasp scripts' 5 cm lift and
    /// far above the sub-millimetre creep of a body held by static friction.
    double dropSlipM = 0.010;
};

/// The figures of one held window.
struct GraspFigures {
    double maxSlipM = 0.0;         ///< Largest slip in the window (m).
    double finalSlipM = 0.0;       ///< Slip at the last sample (m).
    double forceErrorMedian = 0.0; ///< Median of |support - m g| / (m g) (unitless).
    double forceErrorWorst = 0.0;  ///< Largest of the same (unitless).
    std::size_t samples = 0;       ///< Finite samples measured after begin().
    std::size_t nonFinite = 0;     ///< Samples ignored for a non-finite value.
    bool held = false;             ///< samples > 0 and finalSlipM <= GraspProbeSettings::dropSlipM.
};

/// Measures one held window of a two-handed grasp: begin(), add() per step, figures().
/// [control]
class GraspProbe {
public:
    /// Throws std::invalid_argument for a mass, gravity or drop slip that is not finite and
    /// > 0, or an `up` that is not a unit vector. [control]
    explicit GraspProbe(const GraspProbeSettings& settings);

    /// Starts (or restarts) the window at `sample`: the body's offset from the hands' midpoint
    /// now is the zero of slip. Returns false (and starts nothing) for a non-finite sample.
    /// [control]
    bool begin(const GraspSample& sample);
    /// True after a successful begin(). [control]
    bool begun() const { return mBegun; }
    /// Measures one instant of the window (ignored before begin()). [control]
    void add(const GraspSample& sample);
    /// Slip of `sample` against the window's start (m); 0 before begin(). [control]
    double slipM(const GraspSample& sample) const;
    /// |-(F_A + F_B) . up - m g| / (m g) of `sample` (unitless). [control]
    double forceError(const GraspSample& sample) const;
    /// The largest slip so far (m), without the figures' median: cheap enough per step.
    /// [control]
    double maxSlipM() const { return mMaxSlipM; }
    /// The window's figures so far. [control]
    GraspFigures figures() const;

private:
    GraspProbeSettings mSettings;
    bool mBegun = false;
    Vec3 mOffset0{0.0};
    double mMaxSlipM = 0.0;
    double mLastSlipM = 0.0;
    std::size_t mNonFinite = 0;
    std::vector<double> mErrors;
};

/// The sample a stepped or threaded Runtime shows now: body `body`'s centre of mass from
/// Runtime::bodyPoses(), hands `handA` and `handB`'s device points and sent forces from
/// Runtime::lastTick(). nullopt when the runtime has no such body or a hand has not ticked yet.
/// [control]
std::optional<GraspSample> graspSampleOf(const Runtime& runtime, std::size_t body,
                                         std::size_t handA, std::size_t handB);

} // namespace hapto::experiments
