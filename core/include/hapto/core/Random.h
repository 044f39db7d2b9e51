#pragma once
/// A small, portable, seeded random generator (xoshiro256**), so scenes and simulated devices
/// reproduce bit for bit on every platform (the standard distributions do not).

#include <cmath>
#include <cstdint>
#include <numbers>

namespace hapto {

/// xoshiro256** seeded through splitmix64. Not thread-safe: one per thread. [any thread]
class Random {
public:
    /// A generator whose sequence is fixed by `seed` (the same seed, the same numbers).
    explicit Random(std::uint64_t seed) {
        for (auto& s : mState) {
            seed += 0x9E3779B97F4A7C15ull;
            std::uint64_t z = seed;
            z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
            z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
            s = z ^ (z >> 31);
        }
    }
    /// 64 random bits.
    std::uint64_t next() {
        const std::uint64_t result = rotl(mState[1] * 5, 7) * 9;
        const std::uint64_t t = mState[1] << 17;
        mState[2] ^= mState[0];
        mState[3] ^= mState[1];
        mState[1] ^= mState[2];
        mState[0] ^= mState[3];
        mState[2] ^= t;
        mState[3] = rotl(mState[3], 45);
        return result;
    }
    /// Uniform in [0, 1).
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    /// Uniform in [lo, hi).
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    /// Standard normal (Box-Muller; uses two uniforms per call, keeps no state).
    double normal() {
        const double u1 = 1.0 - uniform(); // (0, 1]
        const double u2 = uniform();
        return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
    }
    /// Uniform integer in [0, n), n > 0.
    std::uint64_t below(std::uint64_t n) { return next() % n; }

private:
    static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
    std::uint64_t mState[4];
};

} // namespace hapto
