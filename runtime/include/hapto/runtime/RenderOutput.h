#pragma once
/// What a force algorithm is configured with and what one tick of it gives: RendererConfig,
/// RenderOutput with its Contacts and RenderStatus, RenderCounters (the ForceAlgorithm seam's
/// vocabulary, shared by GodObjectRenderer and any algorithm beside it).

#include "hapto/core/Geometry.h"
#include "hapto/scenes/Scene.h"

#include <array>
#include <cstdint>

namespace hapto {

/// How a renderer behaves; fixed at construction.
struct RendererConfig {
    /// Contact damping b (N·s/m), applied along the contact force direction only while in
    /// contact, never pulling the tool into a surface. >= 0; 0 turns it off.
    double damping = 0.0;
    /// Proxy solver passes per tick (each pass: one small plane solve + one swept test over the
    /// nearby objects), 1..GodObjectRenderer::kMaxIterations (32).
    std::uint32_t maxIterations = 10;
    /// The hand's contact patch for the dynamic bodies it touches: its effective torsional
    /// radius r (m, 0..kMaxTorsionRadiusM; 0: a point contact), so the hand resists a body's
    /// spin about the contact normal up to mu |Fn| r (BodyCoupling.h). 3 mm by default: a few
    /// millimetres, a choice (a fingertip-sized patch), not a measured fact.
    double torsionRadiusM = 0.003;
    /// The farthest a proxy that the last tick left behind its device point moves toward it in
    /// one tick (m, world; finite, > 0): its goal is the device point, or the point this far
    /// along the way to it (HapticTick.h). 3 mm by default, 3 m/s at 1 kHz, faster than a hand
    /// slides while it presses; it bounds the space one tick's solve can reach, and so the
    /// worst tick of a hand that pushed through a dense scene (docs/results/tick-motions.md,
    /// "The proxy's step: 3 mm"). The runtime gives each device this much of its own motion:
    /// times its transform's scale (withDeviceSettings).
    double maxProxyStepM = 0.003;
};

/// What happened in a tick besides the force.
enum class RenderStatus : std::uint8_t {
    Ok,                ///< Normal tick.
    NonFiniteInput,    ///< Device position was NaN/inf: zero force, proxy kept.
    NonFiniteOutput,   ///< The computation produced NaN/inf (a broken scene?): zero force.
    CandidatesDropped, ///< The CandidateSet overflowed (a span was dropped); tick still ran.
    NearListFull,      ///< More nearby items than kMaxNearObjects: ran on the raw spans.
};

/// How often each fault happened in one renderer, as plain values.
struct RenderCounters {
    std::uint64_t ticks = 0;             ///< update() calls.
    std::uint64_t nonFiniteInput = 0;    ///< Ticks with a NaN/inf device position.
    std::uint64_t nonFiniteOutput = 0;   ///< Ticks whose result was NaN/inf (zeroed).
    std::uint64_t candidatesDropped = 0; ///< Ticks whose CandidateSet had overflowed.
    std::uint64_t nearListFull = 0;      ///< Ticks that fell back to the raw spans.
};

/// One active constraint plane of the proxy.
struct Contact {
    std::uint32_t slot = 0; ///< The touched item: a box's or sphere's slot in `scene.objects()`,
                            ///< or a mesh triangle's item (isTriangleItem; Scene::triangle).
    ObjectId id = 0;        ///< The touched object's id (a triangle's: its mesh's).
    Vec3 normal{0.0};       ///< Outward unit normal of the constraint plane (world).
    double depth = 0.0;     ///< How far the device point is behind that plane (m), > 0.
};

/// The result of one tick.
struct RenderOutput {
    Vec3 force{0.0};                   ///< Force to send (N, world frame), before ForceSafety.
    Vec3 proxy{0.0};                   ///< Proxy (god-object) position after the tick (m, world).
    std::array<Contact, 3> contacts{}; ///< Active constraints; the first `contactCount` are valid.
    std::uint8_t contactCount = 0;     ///< 0 = free motion, 1 = face, 2 = edge/crease, 3 = corner.
    bool sliding = false;              ///< In contact and the proxy moved along the surface.
    RenderStatus status = RenderStatus::Ok; ///< Faults, as a value.
    std::uint8_t iterations = 0;     ///< Solver passes used (both solves when friction slipped).
    std::uint32_t objectsTested = 0; ///< Candidate slots examined (duplicates included).
};

} // namespace hapto
