#include "hapto/devices/HandModel.h"

#include <cmath>

namespace hapto {

HandModel::HandModel(double massKg, double stiffness, double dampingRatio)
    : mMassKg(massKg), mStiffness(stiffness),
      mDamping(2.0 * dampingRatio * std::sqrt(stiffness * massKg)) {}

void HandModel::reset(const Vec3& position) {
    mPosition = position;
    mVelocity = Vec3(0.0);
}

void HandModel::step(const Vec3& target, const Vec3& forceN, double dtS) {
    const double a = dtS / mMassKg;
    const double denom = 1.0 + a * mDamping + a * dtS * mStiffness;
    mVelocity = (mVelocity + a * (mStiffness * (target - mPosition) + forceN)) / denom;
    mPosition += dtS * mVelocity;
}

} // namespace hapto
