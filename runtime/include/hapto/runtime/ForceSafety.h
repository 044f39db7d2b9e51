#pragma once
/// The last stage before a device: clamps, rate-limits and sanitises every force.

#include "hapto/core/Geometry.h"

#include <atomic>
#include <cstdint>

namespace hapto {

/// Limits for one device's forces.
struct SafetyConfig {
    /// Default peak force (N): 8.5 N, the maximum exertable force of a SensAble PHANToM
    /// Premium 1.0 (the paper's device), from SensAble's PHANToM Premium 1.0/1.5 specification
    /// sheet (its continuous force is 1.4 N). Set it from DeviceCapabilities::maxForceN.
    static constexpr double kPhantom10PeakForceN = 8.5;
    /// Default largest change per tick (N per call of filter()): 1 N, i.e. 1000 N/s at 1 kHz.
    /// An 800 N/m wall met at 1 m/s rises 0.8 N per 1 kHz tick, so real contact passes untouched
    /// while a jump to full force is spread over about 9 ms.
    static constexpr double kDefaultMaxForceStepN = 1.0;

    double maxForceN = kPhantom10PeakForceN;      ///< Magnitude clamp (N), > 0.
    double maxForceStepN = kDefaultMaxForceStepN; ///< Max |F(t) - F(t-1)| per tick (N), > 0, for
                                                  ///< growth and reversals; a release (smaller,
                                                  ///< same direction) passes at once. +infinity
                                                  ///< turns rate limiting off.
};

/// How often each safety rule fired, as plain values.
struct SafetyCounters {
    std::uint64_t filtered = 0;    ///< Forces seen.
    std::uint64_t clamped = 0;     ///< Forces whose magnitude was cut to maxForceN.
    std::uint64_t rateLimited = 0; ///< Forces whose change was cut to maxForceStepN.
    std::uint64_t nonFinite = 0;   ///< NaN inputs (or outputs) replaced by zero force.
    std::uint64_t overflowed = 0;  ///< Infinite or overflowing forces, sent as the maximum in
                                   ///< their direction (also counted in `clamped`).
};

/// Per-device force filter: NaN -> zero (immediately, and the next force ramps up from zero);
/// an infinite force, or one whose magnitude overflows, -> maxForceN in its direction (a wall
/// so stiff its force overflowed is the last place to feel nothing); then magnitude clamp, then
/// a per-tick change limit. The output magnitude never exceeds maxForceN. One instance per device;
/// filter() and reset() belong to its servo thread, counters() may be read from any thread (relaxed
/// atomics, single writer).
class ForceSafety {
public:
    /// Checks the limits; throws std::invalid_argument when one is not > 0 (or NaN). [control]
    explicit ForceSafety(const SafetyConfig& config = {});
    /// Copies limits, last force and counters (for per-device arrays). [control]
    ForceSafety(const ForceSafety& other) noexcept;
    /// Copies limits, last force and counters. [control]
    ForceSafety& operator=(const ForceSafety& other) noexcept;

    /// The force (N) safe to send for a requested force (N). [servo]
    Vec3 filter(const Vec3& forceN) noexcept;
    /// The next force starts from zero (rate limit ramps from 0). Counters are kept. [servo]
    void reset() noexcept;
    /// A snapshot of the counters. [any thread]
    SafetyCounters counters() const noexcept;
    /// The last force returned (N). [servo]
    const Vec3& lastForce() const noexcept { return mLast; }
    /// The limits. [any thread]
    const SafetyConfig& config() const noexcept { return mConfig; }

private:
    static void bump(std::atomic<std::uint64_t>& c) noexcept {
        c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    }

    SafetyConfig mConfig;
    Vec3 mLast{0.0};
    std::atomic<std::uint64_t> mFiltered{0};
    std::atomic<std::uint64_t> mClamped{0};
    std::atomic<std::uint64_t> mRateLimited{0};
    std::atomic<std::uint64_t> mNonFinite{0};
    std::atomic<std::uint64_t> mOverflowed{0};
};

} // namespace hapto
