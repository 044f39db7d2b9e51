#pragma once
/// The haptic tick, once: locate (device and proxy cursors) -> candidates -> render -> force
/// effects -> safety filter, for one device, real-time safe.

#include "hapto/index/Cursor.h"
#include "hapto/runtime/CandidateSet.h"
#include "hapto/runtime/ForceSafety.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/World.h"

#include <cstdint>

namespace hapto {

/// What one tick computed (world frame).
struct TickOutput {
    /// The renderer's result: proxy, contacts, objects tested, status, and its force (N)
    /// before effects, the external force and the safety filter.
    RenderOutput render;
    /// The force to send (N): render force + external force + effects, through the safety
    /// filter.
    Vec3 forceN{0.0};
    std::uint32_t locateSteps = 0; ///< Cursor steps, both cursors.
    bool outside = false;          ///< The device point is outside the index's bounds.
    bool newSnapshot = false; ///< The snapshot differs from the previous tick's (cursors re-bound).
};

/// One device's haptic tick. Design note: the sequence every caller runs (the servo threads,
/// the runtime's step mode, `hapto render`, the experiments' warm-up and tick probe) lives
/// here and nowhere else:
///   1. locate: the device point's cursor and the proxy's cursor each find their leaf (they
///      differ while the tool presses into a surface, the proxy resting on it);
///   2. candidates: the two leaves' object slots (the proxy's only when its leaf differs) and
///      the snapshot's moving objects, as spans (no copy);
///   3. render: the god-object renderer moves the proxy and computes k (proxy - device);
///   4. force effects: the extension point where effects add force (empty today; see
///      effectsForceN);
///   5. safety: ForceSafety clamps, rate-limits and sanitises the sum.
/// It holds the two cursors, the renderer, the safety filter and the candidate set, sized at
/// construction: tick() never allocates, locks, makes a syscall or throws. One instance per
/// device, used by one thread at a time. The caller owns the snapshot (it stays valid for the
/// tick) and the device side: reading, the frames, and what to do with the force.
///
/// Size: 1728 bytes, 64-byte aligned (checked by a static_assert in the source file), of
/// which 1408 are the renderer.
class alignas(64) HapticTick {
public:
    /// Checks both configurations; throws std::invalid_argument when one is invalid. [control]
    explicit HapticTick(const RendererConfig& renderer = {}, const SafetyConfig& safety = {});

    /// The next tick starts afresh: the proxy is put on that tick's device point with no
    /// contact, the cursors are bound to its snapshot, and the force grows from zero at the
    /// safety filter's rate. Counters are kept. [servo]
    void reset() noexcept;

    /// One tick for the device point `devicePointWorld` (m) moving at `velocityWorld` (m/s;
    /// not finite: estimated from the last point over dtS) against `snapshot`, `dtS` seconds
    /// after the last tick, with `externalForceN` (N, e.g. a carried object's weight) added
    /// before the safety filter. [servo]
    TickOutput tick(const WorldSnapshot& snapshot, const Vec3& devicePointWorld,
                    const Vec3& velocityWorld, double dtS, const Vec3& externalForceN) noexcept;

    /// The force of the last tick is not sent (a fault rule commanded zero): the next force
    /// grows from zero at the safety filter's rate. [servo]
    void zeroForce() noexcept { mSafety.reset(); }

    /// The proxy (m, world). [servo]
    const Vec3& proxy() const noexcept { return mRenderer.proxy(); }
    /// The renderer (its counters, configuration). [servo]
    const GodObjectRenderer& renderer() const noexcept { return mRenderer; }
    /// The safety filter; its counters() may be read from any thread. [any thread]
    const ForceSafety& safety() const noexcept { return mSafety; }

private:
    /// Force effects (N, world frame), added after rendering and before the safety filter,
    /// so an effect is clamped and rate-limited like contact. The extension point for a set
    /// of effects (a vibration, a viscous field, a spring to a point, a button click): each
    /// sees this tick's render result and device motion, must be real-time safe like the
    /// rest of the tick, and adds its force here. None today: zero. [servo]
    Vec3 effectsForceN(const RenderOutput& render, const Vec3& devicePointWorld,
                       const Vec3& velocityWorld, double dtS) const noexcept;

    Cursor mDeviceCursor; ///< The device point's leaf.
    Cursor mProxyCursor;  ///< The proxy's leaf.
    GodObjectRenderer mRenderer;
    ForceSafety mSafety;
    CandidateSet mCandidates;                  ///< This tick's spans (views into the snapshot).
    const SpatialIndex* mBoundIndex = nullptr; ///< The index the cursors are bound to.
    std::uint64_t mBoundVersion = 0;           ///< The snapshot version they were bound for.
    bool mFresh = true;                        ///< The next tick starts afresh (reset()).
};

} // namespace hapto
