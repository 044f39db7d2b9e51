#pragma once
/// A seeded hand-speed random walk: one pointer position per servo tick, for benchmarks and
/// experiments (hapto_bench, `hapto bench query`, the cursor part of `hapto experiment scaling`).
///
/// The idea: drive every index and every baseline with the same motion a hand makes at a
/// haptic device, so cursor caching is exercised the way a servo thread exercises it. The
/// velocity is an Ornstein-Uhlenbeck process per axis (it turns smoothly, over about
/// `turnTimeS`), its magnitude capped at `maxSpeedMPerS`; the position moves by velocity x tick
/// and is mirrored at the faces of the box (the velocity component flips).
/// Invariant: every position lies in the closed box, and each step moves at most
/// maxSpeedMPerS x tickS (0.5 mm at 0.5 m/s and 1 kHz) from the last position, which holdBack()
/// may have moved (a hand stopped by a surface).
/// Cost: a few flops and two normal draws per axis per step; no allocation in next().

#include "hapto/core/Geometry.h"
#include "hapto/core/Random.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace hapto::experiments {

/// How the simulated hand moves.
struct HandWalkOptions {
    double tickS = 1.0e-3;        ///< Time between positions (s): 1 ms, a 1 kHz servo loop.
    double maxSpeedMPerS = 0.5;   ///< Speed cap (m/s): a brisk hand at a desktop device.
    double axisSpeedMPerS = 0.15; ///< Standard deviation of each velocity component (m/s).
    double turnTimeS = 0.25;      ///< Correlation time of the velocity (s).
};

/// The walk itself: a small value type, deterministic for a seed. [any thread, one per thread]
class HandWalk {
public:
    /// Starts at the centre of `box` (m) at rest. [any thread]
    HandWalk(const Aabb& box, std::uint64_t seed, const HandWalkOptions& options = {})
        : mBox(box), mOptions(options), mRandom(seed), mPosition(box.center()) {}

    /// The current position (m). [any thread]
    const Vec3& position() const { return mPosition; }

    /// Advances one tick and returns the new position (m). [any thread]
    Vec3 next() {
        const double dt = mOptions.tickS;
        const double decay = std::exp(-dt / mOptions.turnTimeS);
        const double kick = mOptions.axisSpeedMPerS * std::sqrt(1.0 - decay * decay);
        for (int a = 0; a < 3; ++a) {
            mVelocity[a] = decay * mVelocity[a] + kick * mRandom.normal();
        }
        const double speed = glm::length(mVelocity);
        if (speed > mOptions.maxSpeedMPerS) {
            mVelocity *= mOptions.maxSpeedMPerS / speed;
        }
        mPosition += mVelocity * dt;
        for (int a = 0; a < 3; ++a) {
            // Mirror at the faces; a mirrored step is never longer than the step itself.
            if (mPosition[a] < mBox.min[a]) {
                mPosition[a] = 2.0 * mBox.min[a] - mPosition[a];
                mVelocity[a] = -mVelocity[a];
            } else if (mPosition[a] > mBox.max[a]) {
                mPosition[a] = 2.0 * mBox.max[a] - mPosition[a];
                mVelocity[a] = -mVelocity[a];
            }
            // A box thinner than one step: stay inside anyway.
            mPosition[a] = std::clamp(mPosition[a], mBox.min[a], mBox.max[a]);
        }
        return mPosition;
    }

    /// A hand that feels the surface it pushes into: the position goes back to `to` (m, a
    /// point on the segment from the current position toward where the surface holds the
    /// hand, e.g. within a given distance of the god-object's proxy), clamped to the box, and
    /// the velocity loses its component along the push (position - to), if it points that way:
    /// the hand stops pushing in and keeps what it had along the surface. Consecutive
    /// positions stay at most maxSpeedMPerS x tickS apart after the next step. [any thread]
    void holdBack(const Vec3& to) {
        const Vec3 push = mPosition - to;
        const double length = glm::length(push);
        mPosition = glm::clamp(to, mBox.min, mBox.max);
        if (length > 0.0) {
            const Vec3 n = push / length;
            const double in = glm::dot(mVelocity, n);
            if (in > 0.0) {
                mVelocity -= in * n;
            }
        }
    }

private:
    Aabb mBox;
    HandWalkOptions mOptions;
    Random mRandom;
    Vec3 mPosition{0.0};
    Vec3 mVelocity{0.0};
};

/// `count` consecutive positions of a fresh walk (m). [control]
inline std::vector<Vec3> makeHandWalk(const Aabb& box, std::uint64_t seed, std::size_t count,
                                      const HandWalkOptions& options = {}) {
    HandWalk walk(box, seed, options);
    std::vector<Vec3> out;
    out.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        out.push_back(walk.next());
    }
    return out;
}

} // namespace hapto::experiments
