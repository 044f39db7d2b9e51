#pragma once
/// The servo loop's warm-up: what a servo thread does a few microseconds before its deadline so
/// that the tick starts with its working set in cache (RuntimeOptions::warmUpNs).
///
/// Design note. A servo thread sleeps about a millisecond between ticks, and in that time the
/// other threads on its core evict what the tick reads: the snapshot, the cursor's leaf and its
/// candidate objects, the renderer and the rest of the haptic tick. With a warm-up the thread
/// wakes warmUpNs before its deadline, calls warmUpTick() (a read-only walk over that working
/// set: a prefetch of the servo's hot state, a locate from the root at the predicted device point
/// and at the proxy, a prefetch of every candidate object, and a dry render on a copy of the
/// renderer, which also brings the solver's code back into the instruction cache), spins to the
/// deadline, and only then reads the device and ticks as before. Invariant: the warm-up writes
/// nothing the tick reads (it does not move a cursor or the proxy; the snapshot claim it may take
/// is the one the tick takes again), so forces and timing semantics are unchanged: the device is
/// never sampled before the deadline (at it, or just after the warm-up when the wake-up came
/// later than the window). Cost: warmUpNs of CPU per tick (spinning), which is why it is an
/// option, and why the runtime turns it off by itself when servo threads share cores.

#include "hapto/core/Geometry.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/World.h"

#include <cstddef>
#include <cstdint>
#include <span>

namespace hapto {

/// The warm-up the runtime runs when RuntimeOptions::warmUpNs is unset and every servo thread
/// can have a core of its own (ns): chosen by measurement with `hapto bench tick`
/// (docs/results/tick.md).
inline constexpr std::uint64_t kDefaultWarmUpNs = 5'000;
/// The largest warm-up the options accept (ns): 100 µs, a tenth of a 1 kHz period.
inline constexpr std::uint64_t kMaxWarmUpNs = 100'000;
/// Candidate objects warmUpTick() prefetches per point at most (bounds its time).
inline constexpr std::size_t kMaxWarmUpPrefetches = 256;

/// Warms the next tick up without changing anything it reads: prefetches every cache line of
/// `tickState` (the servo's hot state: the HapticTick with its cursors, renderer, safety filter
/// and effects), locates the predicted device point `lastPointM + lastStepM` (m, world: the last
/// device point and the last tick's move of it; the last point alone if the step is not finite)
/// and the renderer's proxy from the index root (reading the nodes on the way; no cursor moves),
/// prefetches the scene objects those leaves and the moving list name (up to
/// kMaxWarmUpPrefetches each), and runs a dry render: a copy of `renderer` (on the stack)
/// updated at the predicted point against those candidates, so the solver's code paths and the
/// objects' data the tick is about to need are in cache; the copy is dropped. Returns a value
/// derived from what it read (callers keep it, so the work is not optimised away). Never allocates,
/// locks, logs or throws. [servo]
std::uint64_t warmUpTick(const WorldSnapshot& snapshot, const GodObjectRenderer& renderer,
                         std::span<const std::byte> tickState, const Vec3& lastPointM,
                         const Vec3& lastStepM, double dtS) noexcept;

/// Spins (cpuPause) until CLOCK_MONOTONIC reaches `deadlineNs`. [servo]
void spinUntilNs(std::uint64_t deadlineNs) noexcept;

} // namespace hapto
