#pragma once
/// One device point moved along a path through the haptic tick: what `hapto render` prints and
/// Python's `hapto.render` returns, computed once here.
///
/// Design note. The point is the device point in the world frame: no device, no transform, no
/// threads, no clock. Tick i renders path[i] with the velocity a servo estimates for a device
/// that gives none, (path[i] - path[i-1]) * rate (zero at the first point), and dt = 1 / rate.
/// Each tick's force is the renderer's, before the force effects and the safety filter (what
/// the scene asks for; a device gets it clamped and rate-limited). One HapticTick carries the
/// proxy from tick to tick, so the same path, snapshot and rate give the same doubles every run.

#include "hapto/runtime/World.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace hapto::experiments {

/// One tick of a rendered path (world frame).
struct PathTick {
    Vec3 pointM{0.0};           ///< The device point rendered (m).
    Vec3 proxyM{0.0};           ///< The proxy after the tick (m).
    Vec3 forceN{0.0};           ///< The renderer's force (N), before effects and safety.
    std::uint32_t contacts = 0; ///< Constraints held: 0 free, 1 face, 2 edge, 3 corner.
};

/// The column names of a rendered path, in order (the CSV header of `hapto render`): tick,
/// x, y, z (m), proxy_x, proxy_y, proxy_z (m), fx, fy, fz (N), contacts. [any thread]
std::span<const std::string_view> renderPathColumns();

/// Renders `path` (m, world) tick by tick over `snapshot` at `rateHz` (> 0). [control]
std::vector<PathTick> renderPath(const WorldSnapshot& snapshot, std::span<const Vec3> path,
                                 double rateHz);

} // namespace hapto::experiments
