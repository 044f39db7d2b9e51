// A device point along a path through the haptic tick (RenderPath.h).

#include "hapto/experiments/RenderPath.h"

#include "hapto/runtime/HapticTick.h"

#include <array>

namespace hapto::experiments {

std::span<const std::string_view> renderPathColumns() {
    static constexpr std::array<std::string_view, 11> kColumns = {
        "tick", "x", "y", "z", "proxy_x", "proxy_y", "proxy_z", "fx", "fy", "fz", "contacts"};
    return kColumns;
}

std::vector<PathTick> renderPath(const WorldSnapshot& snapshot, std::span<const Vec3> path,
                                 double rateHz) {
    std::vector<PathTick> ticks;
    ticks.reserve(path.size());
    HapticTick tick;
    const double dtS = 1.0 / rateHz;
    Vec3 last = path.empty() ? Vec3(0.0) : path.front();
    for (const Vec3& p : path) {
        const Vec3 velocity = (p - last) / dtS; // as a servo estimates it for a device without one
        last = p;
        const TickOutput t = tick.tick(snapshot, p, velocity, dtS, Vec3(0.0));
        ticks.push_back({p, t.render.proxy, t.render.force, t.render.contactCount});
    }
    return ticks;
}

} // namespace hapto::experiments
