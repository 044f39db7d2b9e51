#pragma once
/// The seam for force algorithms: what the haptic tick asks of the algorithm that turns a
/// device point and the candidate items into a proxy, contacts and a force.
///
/// Design note. The tick (HapticTick) does the same work around any force algorithm: locate
/// the cursors, gather the candidate spans, walk the leaves the proxy's way crosses and solve
/// again with each one it missed, add the effects and the hook, filter for safety. Only the
/// step in the middle differs: the god-object renderer today (GodObjectRenderer, a proxy that
/// never enters an object), a coupling to simulated rigid bodies or later algorithms beside it.
/// The seam is this concept, not a virtual base: the tick is a template over it
/// (BasicHapticTick), instantiated once per algorithm in HapticTick.cpp, so the servo path
/// makes no indirect call, the algorithm stays a member of the tick (no allocation, its size
/// written down), and the tick can copy the algorithm's State to solve a tick again.
///
/// An algorithm must, without allocating, locking or throwing on the servo path:
///   - be constructible from the RendererConfig (damping, solver passes; it may check them and
///     throw at construction);
///   - reset(point): start afresh at a device point, with no contact;
///   - update(scene, candidates, device, velocity, dtS) and update(scene, candidates, device,
///     goal, velocity, dtS): one tick, the second with the proxy's motion held to `goal` (on
///     the way to the device point) and the contacts and force still the device point's;
///     looking only at the items the candidate spans name, returning a RenderOutput;
///   - proxy(), inContact(): where its proxy is, and whether the last tick touched;
///   - state() and restore(state): a plain copy of what carries over between ticks, so the
///     tick can solve the same tick again with more candidates;
///   - visitedPath(0), visitedPath(1): the polylines the proxy moved along in the last update,
///     so the tick can walk every leaf they cross (an algorithm whose proxy jumps would list
///     its start and end).

#include "hapto/runtime/CandidateSet.h"
#include "hapto/runtime/RenderOutput.h"
#include "hapto/scenes/Scene.h"

#include <concepts>
#include <span>
#include <type_traits>

namespace hapto {

/// A force algorithm the haptic tick can run (see the design note above). [any thread]
// (clang-format 14 breaks requires-expressions apart: this one is formatted by hand.)
// clang-format off
template <class A>
concept ForceAlgorithm =
    std::constructible_from<A, const RendererConfig&> &&
    std::is_trivially_copyable_v<typename A::State> &&
    requires(A& a, const A& c, const Scene& scene, const CandidateSet& candidates, const Vec3& p,
             const typename A::State& state) {
        { a.reset(p) } noexcept;
        { a.update(scene, candidates, p, p, 0.001) } noexcept -> std::same_as<RenderOutput>;
        { a.update(scene, candidates, p, p, p, 0.001) } noexcept -> std::same_as<RenderOutput>;
        { c.proxy() } noexcept -> std::convertible_to<Vec3>;
        { c.inContact() } noexcept -> std::same_as<bool>;
        { c.state() } noexcept -> std::convertible_to<typename A::State>;
        { a.restore(state) } noexcept;
        { c.visitedPath(0) } noexcept -> std::same_as<std::span<const Vec3>>;
    };
// clang-format on

} // namespace hapto
