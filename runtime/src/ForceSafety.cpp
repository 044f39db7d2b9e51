#include "hapto/runtime/ForceSafety.h"

#include "hapto/core/Finite.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hapto {

ForceSafety::ForceSafety(const SafetyConfig& config) : mConfig(config) {
    if (!(config.maxForceN > 0.0) || !std::isfinite(config.maxForceN)) {
        throw std::invalid_argument("ForceSafety: maxForceN must be a finite force > 0 N (got " +
                                    std::to_string(config.maxForceN) + ")");
    }
    if (!(config.maxForceStepN > 0.0)) {
        throw std::invalid_argument(
            "ForceSafety: maxForceStepN must be > 0 N per tick, or +infinity to disable (got " +
            std::to_string(config.maxForceStepN) + ")");
    }
}

ForceSafety::ForceSafety(const ForceSafety& other) noexcept {
    *this = other;
}

ForceSafety& ForceSafety::operator=(const ForceSafety& other) noexcept {
    if (this != &other) {
        mConfig = other.mConfig;
        mLast = other.mLast;
        const SafetyCounters c = other.counters();
        mFiltered.store(c.filtered, std::memory_order_relaxed);
        mClamped.store(c.clamped, std::memory_order_relaxed);
        mRateLimited.store(c.rateLimited, std::memory_order_relaxed);
        mNonFinite.store(c.nonFinite, std::memory_order_relaxed);
        mOverflowed.store(c.overflowed, std::memory_order_relaxed);
    }
    return *this;
}

Vec3 ForceSafety::filter(const Vec3& forceN) noexcept {
    bump(mFiltered);
    Vec3 f = forceN;
    if (!finite(f)) {
        const bool anyNan = std::isnan(f.x) || std::isnan(f.y) || std::isnan(f.z);
        if (anyNan) { // no direction: nothing safe to send but zero
            bump(mNonFinite);
            mLast = Vec3(0.0);
            return mLast;
        }
        // An overflow (k times a penetration beyond double range): the direction is that of
        // the infinite components, so the force is the maximum that way, not zero, which would
        // drop the hardest wall of all.
        f = Vec3(std::isinf(f.x) ? std::copysign(1.0, f.x) : 0.0,
                 std::isinf(f.y) ? std::copysign(1.0, f.y) : 0.0,
                 std::isinf(f.z) ? std::copysign(1.0, f.z) : 0.0);
        f *= mConfig.maxForceN / glm::length(f);
        bump(mOverflowed);
        bump(mClamped);
    } else {
        const double magnitude = glm::length(f);
        if (!std::isfinite(magnitude)) {
            // Finite components whose length overflows: scale down first, then clamp.
            const double largest = std::max({std::abs(f.x), std::abs(f.y), std::abs(f.z)});
            const Vec3 direction = f / largest;
            f = direction * (mConfig.maxForceN / glm::length(direction));
            bump(mOverflowed);
            bump(mClamped);
        } else if (magnitude > mConfig.maxForceN) {
            f *= mConfig.maxForceN / magnitude;
            bump(mClamped);
        }
    }
    // Both mLast and f lie in the ball of radius maxForceN, so any point between them does too.
    // A release (a smaller force, not reversed) passes at once: letting go is never the danger,
    // and a lingering force would feel like glue. Growth and reversals are rate-limited.
    const Vec3 step = f - mLast;
    const double stepN = glm::length(step);
    const bool release = glm::length(f) <= glm::length(mLast) && glm::dot(f, mLast) >= 0.0;
    if (stepN > mConfig.maxForceStepN && !release) {
        f = mLast + step * (mConfig.maxForceStepN / stepN);
        bump(mRateLimited);
    }
    if (!finite(f)) {
        bump(mNonFinite);
        f = Vec3(0.0);
    }
    mLast = f;
    return f;
}

void ForceSafety::reset() noexcept {
    mLast = Vec3(0.0);
}

SafetyCounters ForceSafety::counters() const noexcept {
    return {mFiltered.load(std::memory_order_relaxed), mClamped.load(std::memory_order_relaxed),
            mRateLimited.load(std::memory_order_relaxed),
            mNonFinite.load(std::memory_order_relaxed),
            mOverflowed.load(std::memory_order_relaxed)};
}

} // namespace hapto
