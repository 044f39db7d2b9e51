#pragma once
/// A hand holding a device handle: a point mass pulled towards a target by a spring-damper.

#include "hapto/core/Geometry.h"

namespace hapto {

/// The simulated hand of SimDevice. A mass m (kg) is pulled towards a moving target by a spring
/// k (N/m) and a damper c (N s/m); the force a servo writes to the device acts on the same mass.
/// At rest under a constant force F the hand sits at target + F / k.
///
/// Integration, per step of dt (s): the hand's own spring and damper are taken implicitly and the
/// device force explicitly (semi-implicit Euler),
///   v' = (v + dt/m (k (target - x) + F)) / (1 + dt c/m + dt^2 k/m),   x' = x + dt v'.
/// The hand alone is stable at any dt; results depend only on the inputs, never on wall-clock.
class HandModel {
public:
    /// A hand of mass `massKg` (> 0), stiffness `stiffness` (N/m, > 0) and damping as a fraction
    /// of critical `dampingRatio` (>= 0), at rest at the origin. [control]
    HandModel(double massKg, double stiffness, double dampingRatio);

    /// Puts the hand at rest at `position` (m). [servo]
    void reset(const Vec3& position);
    /// Advances by `dtS` (s) with the hand pulled to `target` (m) and pushed by `forceN` (N).
    /// [servo]
    void step(const Vec3& target, const Vec3& forceN, double dtS);

    /// Position (m). [servo]
    const Vec3& position() const { return mPosition; }
    /// Velocity (m/s). [servo]
    const Vec3& velocity() const { return mVelocity; }
    /// Mass (kg). [any thread]
    double massKg() const { return mMassKg; }
    /// Spring stiffness k (N/m). [any thread]
    double stiffness() const { return mStiffness; }
    /// Damping c (N s/m). [any thread]
    double damping() const { return mDamping; }

private:
    double mMassKg;
    double mStiffness;
    double mDamping;
    Vec3 mPosition{0.0};
    Vec3 mVelocity{0.0};
};

} // namespace hapto
