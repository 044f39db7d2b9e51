// Planning the simulated hand's scripts. Design note: every script becomes a list of timed
// world-frame keyframes, joined by minimum-jerk segments (a hand's reaching profile: rest to
// rest, peak speed 1.875 L / T). All the thinking (choosing objects, checking paths against
// solids, drawing random waypoints) happens here, on the control thread; the servo thread only
// interpolates. Random scripts draw from hapto::Random, so a seed gives the same plan on every
// platform.

#include "hapto/devices/SimScript.h"

#include "SceneQueries.h"

#include "hapto/core/Random.h"
#include "hapto/io/InputError.h"

#include <algorithm>
#include <cmath>
#include <queue>

namespace hapto {
namespace {

constexpr double kStandOffM = 0.02;      // Stand-off from the surface before pressing (m).
constexpr double kFreeMarginM = 0.006;   // Clearance free-space paths keep from solids (m).
constexpr double kEdgeMarginM = 0.003;   // Contact points stay this far from box edges (m).
constexpr double kApproachSpeed = 0.10;  // Peak approach speed (m/s).
constexpr double kPressSpeed = 0.03;     // Peak speed moving in to press (m/s).
constexpr double kSlideSpeed = 0.05;     // Peak sliding speed (m/s).
constexpr double kSlideHalfSpanM = 0.02; // Slide up to this far either side of the contact (m).

double minJerk(double tau) {
    return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}

// Duration (s) of a minimum-jerk move of `lengthM` with peak speed `peak` (m/s).
double moveDuration(double lengthM, double peak) {
    return std::max(0.05, 1.875 * lengthM / peak);
}

class Builder {
public:
    explicit Builder(const Vec3& start) { mKeys.push_back({0.0, start, ScriptPhase::Move, true}); }
    const Vec3& last() const { return mKeys.back().target; }
    double time() const { return mKeys.back().timeS; }
    std::size_t size() const { return mKeys.size(); }
    void moveTo(const Vec3& p, double durationS, ScriptPhase phase, bool smooth = true) {
        mKeys.push_back({time() + durationS, p, phase, smooth, mPressing});
    }
    // The knots added from now on hold a press (ScriptKeyframe::pressing), or stop holding it.
    void holdPress(bool pressing) { mPressing = pressing; }
    void moveAt(const Vec3& p, double peakSpeed, ScriptPhase phase) {
        moveTo(p, moveDuration(glm::length(p - last()), peakSpeed), phase);
    }
    void hold(double durationS, ScriptPhase phase) { moveTo(last(), durationS, phase); }
    void holdUntil(double timeS, ScriptPhase phase) {
        if (timeS > time()) {
            moveTo(last(), timeS - time(), phase);
        }
    }
    std::vector<ScriptKeyframe> take() { return std::move(mKeys); }

private:
    std::vector<ScriptKeyframe> mKeys;
    bool mPressing = false;
};

// The voxel grid gridPath searches: a region around the two ends, cubic voxels, and which of
// them are blocked.
struct VoxelGrid {
    Aabb region;
    double voxel = 0.0; // edge (m)
    int nx = 0, ny = 0, nz = 0;
    std::vector<std::uint8_t> blocked; // per voxel: within the clearance of a solid

    int index(int x, int y, int z) const { return (z * ny + y) * nx + x; }
    bool inside(int x, int y, int z) const {
        return x >= 0 && y >= 0 && z >= 0 && x < nx && y < ny && z < nz;
    }
    Vec3 centre(int i) const {
        const int x = i % nx, y = (i / nx) % ny, z = i / (nx * ny);
        return region.min + voxel * Vec3(x + 0.5, y + 0.5, z + 0.5);
    }
};

// The grid around a and b (6 cm margin, at most 96 voxels along the longest side, none under
// 4 mm), voxels blocked within kFreeMarginM + one voxel of a solid among `slots`, so a step
// between free voxel centres keeps the margin.
VoxelGrid blockedVoxels(const Scene& scene, const Vec3& a, const Vec3& b,
                        std::span<const std::uint32_t> slots) {
    VoxelGrid g;
    g.region = Aabb::empty();
    g.region.expand(a);
    g.region.expand(b);
    g.region.min -= Vec3(0.06);
    g.region.max += Vec3(0.06);
    const Vec3 size = g.region.size();
    g.voxel = std::max(0.004, std::max({size.x, size.y, size.z}) / 96.0);
    g.nx = static_cast<int>(std::ceil(size.x / g.voxel));
    g.ny = static_cast<int>(std::ceil(size.y / g.voxel));
    g.nz = static_cast<int>(std::ceil(size.z / g.voxel));
    const double clearance = kFreeMarginM + g.voxel;
    g.blocked.assign(static_cast<std::size_t>(g.nx) * g.ny * g.nz, 0);
    for (const std::uint32_t slot : slots) {
        const SceneObject& o = scene.object(slot);
        const Aabb box = o.aabb();
        const Vec3 lo = glm::floor((box.min - Vec3(clearance) - g.region.min) / g.voxel);
        const Vec3 hi = glm::floor((box.max + Vec3(clearance) - g.region.min) / g.voxel);
        for (int z = std::max(0, int(lo.z)); z <= std::min(g.nz - 1, int(hi.z)); ++z) {
            for (int y = std::max(0, int(lo.y)); y <= std::min(g.ny - 1, int(hi.y)); ++y) {
                for (int x = std::max(0, int(lo.x)); x <= std::min(g.nx - 1, int(hi.x)); ++x) {
                    const int i = g.index(x, y, z);
                    if (!g.blocked[i] && detail::signedDistance(o, g.centre(i)) < clearance) {
                        g.blocked[i] = 1;
                    }
                }
            }
        }
    }
    return g;
}

// The free voxel nearest p (within two voxels) that p reaches in a straight line; -1 if none.
int attachVoxel(const VoxelGrid& g, const Scene& scene, std::span<const std::uint32_t> slots,
                const Vec3& p) {
    const Vec3 c = glm::floor((p - g.region.min) / g.voxel);
    int best = -1;
    double bestD = 1e300;
    for (int dz = -2; dz <= 2; ++dz) {
        for (int dy = -2; dy <= 2; ++dy) {
            for (int dx = -2; dx <= 2; ++dx) {
                const int x = int(c.x) + dx, y = int(c.y) + dy, z = int(c.z) + dz;
                if (!g.inside(x, y, z)) {
                    continue;
                }
                const int i = g.index(x, y, z);
                const double d = glm::length(g.centre(i) - p);
                if (!g.blocked[i] && d < bestD &&
                    detail::segmentClear(scene, slots, p, g.centre(i), kFreeMarginM)) {
                    best = i;
                    bestD = d;
                }
            }
        }
    }
    return best;
}

// A* from voxel `from` to voxel `to` over free voxels, 26-connected, straight-line heuristic.
// Returns each voxel's parent on the cheapest paths found (-1: not reached).
std::vector<int> searchVoxels(const VoxelGrid& g, int from, int to) {
    std::vector<double> cost(g.blocked.size(), 1e300);
    std::vector<int> parent(g.blocked.size(), -1);
    using Entry = std::pair<double, int>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
    const Vec3 goal = g.centre(to);
    cost[from] = 0.0;
    open.push({glm::length(goal - g.centre(from)), from});
    while (!open.empty()) {
        const auto [f, i] = open.top();
        open.pop();
        if (i == to) {
            break;
        }
        if (f - glm::length(goal - g.centre(i)) > cost[i] + 1e-12) {
            continue; // stale
        }
        const int x = i % g.nx, y = (i / g.nx) % g.ny, z = i / (g.nx * g.ny);
        for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int X = x + dx, Y = y + dy, Z = z + dz;
                    if ((dx | dy | dz) == 0 || !g.inside(X, Y, Z)) {
                        continue;
                    }
                    const int j = g.index(X, Y, Z);
                    if (g.blocked[j]) {
                        continue;
                    }
                    const double c =
                        cost[i] + g.voxel * std::sqrt(double(dx * dx + dy * dy + dz * dz));
                    if (c < cost[j]) {
                        cost[j] = c;
                        parent[j] = i;
                        open.push({c + glm::length(goal - g.centre(j)), j});
                    }
                }
            }
        }
    }
    return parent;
}

// Shortcuts: from each kept point of `raw`, jump to the farthest point it sees in a straight
// line. Returns the points after raw's first.
std::vector<Vec3> shortcut(const Scene& scene, std::span<const std::uint32_t> slots,
                           const std::vector<Vec3>& raw) {
    std::vector<Vec3> out;
    std::size_t i = 0;
    while (i + 1 < raw.size()) {
        std::size_t j = raw.size() - 1;
        while (j > i + 1 && !detail::segmentClear(scene, slots, raw[i], raw[j], kFreeMarginM)) {
            --j;
        }
        out.push_back(raw[j]);
        i = j;
    }
    return out;
}

// A* over a voxel grid around a and b (blockedVoxels), then shortcut smoothing. Returns the
// waypoints after a, ending at b, or nothing when no path exists in the grid.
std::optional<std::vector<Vec3>> gridPath(const Scene& scene, const Vec3& a, const Vec3& b,
                                          std::span<const std::uint32_t> slots) {
    const VoxelGrid g = blockedVoxels(scene, a, b, slots);
    const int from = attachVoxel(g, scene, slots, a), to = attachVoxel(g, scene, slots, b);
    if (from < 0 || to < 0) {
        return std::nullopt;
    }
    const std::vector<int> parent = searchVoxels(g, from, to);
    if (from != to && parent[to] < 0) {
        return std::nullopt;
    }
    std::vector<Vec3> raw{b};
    for (int i = to; i >= 0; i = i == from ? -1 : parent[i]) {
        raw.push_back(g.centre(i));
    }
    raw.push_back(a);
    std::reverse(raw.begin(), raw.end());
    return shortcut(scene, slots, raw);
}

// Waypoints (excluding a, including b) from a to b keeping kFreeMarginM from solids: straight
// if clear, else a grid path, else straight anyway (the hand then touches something on the way).
std::vector<Vec3> connect(const Scene& scene, const Vec3& a, const Vec3& b) {
    Aabb around = Aabb::empty();
    around.expand(a);
    around.expand(b);
    const std::vector<std::uint32_t> slots = detail::objectsNear(scene, around, 0.08);
    if (detail::segmentClear(scene, slots, a, b, kFreeMarginM)) {
        return {b};
    }
    if (auto path = gridPath(scene, a, b, slots)) {
        return *path;
    }
    return {b};
}

// True when a hand can stand `standOffM` off object `slot` along `out` and move in to it.
bool reachableSide(const Scene& scene, std::uint32_t slot, const Vec3& surface, const Vec3& out,
                   double standOffM = kStandOffM) {
    const Vec3 standOff = surface + out * standOffM;
    Aabb around = Aabb::empty();
    around.expand(standOff);
    around.expand(surface);
    const std::vector<std::uint32_t> slots = detail::objectsNear(scene, around, 0.02);
    return detail::segmentClear(scene, slots, standOff, surface + out * (kFreeMarginM * 0.5),
                                kFreeMarginM * 0.5, slot);
}

double surfaceAlongFrom(const SceneObject& o, const Vec3& from, const Vec3& out);

// Distance from `from` (the centre by default, inside the solid) to the object's surface along
// `out` (m), by bisection on the solid.
double surfaceAlong(const SceneObject& o, const Vec3& out) {
    return surfaceAlongFrom(o, o.center, out);
}
double surfaceAlongFrom(const SceneObject& o, const Vec3& from, const Vec3& out) {
    double in = 0.0, outT = o.radius() * 1.001 + 1e-6 + glm::length(from - o.center);
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (in + outT);
        (o.contains(from + out * mid) ? in : outT) = mid;
    }
    return outT;
}

// True when the waypoints from a keep kFreeMarginM from every solid (connect's result is not,
// when it found no free path).
bool freePath(const Scene& scene, const Vec3& a, const std::vector<Vec3>& waypoints) {
    Vec3 p = a;
    for (const Vec3& q : waypoints) {
        Aabb around = Aabb::empty();
        around.expand(p);
        around.expand(q);
        if (!detail::segmentClear(scene, detail::objectsNear(scene, around, 0.02), p, q,
                                  kFreeMarginM)) {
            return false;
        }
        p = q;
    }
    return true;
}

// A point straight above p (y up, as in scene files' grasp scenes) from which a hand moves
// straight down to p keeping half the free margin, and that keeps the full margin itself: above
// the tops of the objects within 2 cm of that vertical; nothing if there is none below the
// scene's top.
std::optional<Vec3> clearAbove(const Scene& scene, const Vec3& p) {
    const Aabb column{p - Vec3(0.02, 0.0, 0.02),
                      Vec3(p.x + 0.02, scene.bounds().max.y, p.z + 0.02)};
    double top = p.y;
    for (const std::uint32_t slot : detail::objectsNear(scene, column, 0.0)) {
        top = std::max(top, scene.object(slot).aabb().max.y);
    }
    const Vec3 above(p.x, top + 2.0 * kFreeMarginM, p.z);
    if (above.y > scene.bounds().max.y) {
        return std::nullopt;
    }
    Aabb around = Aabb::empty();
    around.expand(p);
    around.expand(above);
    const std::vector<std::uint32_t> near = detail::objectsNear(scene, around, 0.02);
    if (!detail::segmentClear(scene, near, above, above, kFreeMarginM) ||
        !detail::segmentClear(scene, near, above, p, kFreeMarginM * 0.5)) {
        return std::nullopt;
    }
    return above;
}

void approach(Builder& plan, const Scene& scene, const Vec3& to) {
    for (const Vec3& p : connect(scene, plan.last(), to)) {
        plan.moveAt(p, kApproachSpeed, ScriptPhase::Approach);
    }
}

std::uint32_t chosenSlot(const SimConfig& config, const Scene& scene) {
    const auto slot = scene.slotOf(*config.object);
    if (!slot) {
        throw InputError("sim script '" + std::string(name(config.script)) + "': object " +
                         std::to_string(*config.object) +
                         " is not in the scene (check \"object\" in the sim settings)");
    }
    return *slot;
}

std::optional<std::uint32_t> nearestSurface(const Scene& scene, const Vec3& p) {
    std::optional<std::uint32_t> best;
    double bestD = 0.0;
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        const double d = detail::signedDistance(scene.object(i), p);
        if (!best || d < bestD) {
            best = i;
            bestD = d;
        }
    }
    return best;
}

Vec3 anyPerpendicular(const Vec3& n) {
    const Vec3 a = std::abs(n.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    return glm::normalize(glm::cross(n, a));
}

// What a script decides besides its keyframes (SimScript's loop start, object, contact normal).
struct PlanChoice {
    std::optional<std::size_t> loopStart;
    std::optional<ObjectId> object;
    Vec3 contactNormal{0.0};
};

// How far a press puts the target past the surface: F / k_hand, the whole press on an
// unyielding surface. On a surface of stiffness k the hand would feel only F k / (k + k_hand)
// there; while the stretch holds the press, SimDevice moves the target further in until it
// feels F.
double pressDepth(const SimConfig& config) {
    return config.pressForceN / config.handStiffness;
}

// Walk: hops of 1..12 cm in random directions at random peak speeds up to 90 % of the cap (the
// critically damped hand never outruns its target), now and then a pause; loops back to its
// first point.
PlanChoice planWalk(Builder& plan, const SimConfig& config, const Scene& scene,
                    const Vec3& startWorld) {
    Random rng(config.seed);
    const double cap = config.maxSpeedMPerS;
    const Aabb& b = scene.bounds();
    const Vec3 inset = glm::min(Vec3(0.01), 0.5 * b.halfExtents());
    const Vec3 lo = b.min + inset, hi = b.max - inset;
    Vec3 p = glm::clamp(startWorld, lo, hi);
    plan.moveAt(p, 0.5 * cap, ScriptPhase::Move);
    PlanChoice choice;
    choice.loopStart = plan.size() - 1;
    const Vec3 first = p;
    for (int i = 0; i < 512; ++i) {
        Vec3 dir(rng.normal(), rng.normal(), rng.normal());
        dir /= std::max(glm::length(dir), 1e-12);
        p = glm::clamp(p + dir * rng.uniform(0.01, 0.12), lo, hi);
        plan.moveAt(p, rng.uniform(0.1, 0.9) * cap, ScriptPhase::Move);
        if (rng.uniform() < 0.15) {
            plan.hold(rng.uniform(0.1, 0.5), ScriptPhase::Move);
        }
    }
    plan.moveAt(first, 0.5 * cap, ScriptPhase::Move);
    return choice;
}

// Free: a random waypoint walk near the start, every segment checked against the solids with a
// margin; played forwards then backwards, so it loops without a new check.
PlanChoice planFree(Builder& plan, const SimConfig& config, const Scene& scene,
                    const Vec3& startWorld) {
    Random rng(config.seed);
    const Aabb& b = scene.bounds();
    const Vec3 lo = glm::max(b.min + Vec3(kFreeMarginM), startWorld - Vec3(0.08));
    const Vec3 hi = glm::min(b.max - Vec3(kFreeMarginM), startWorld + Vec3(0.08));
    const std::vector<std::uint32_t> slots =
        detail::objectsNear(scene, {glm::min(lo, startWorld), glm::max(hi, startWorld)}, 0.02);
    const double peakHi = std::min(0.15, config.maxSpeedMPerS);
    std::vector<std::pair<Vec3, double>> legs; // waypoint, duration
    Vec3 p = startWorld;
    for (int i = 0; i < 600; ++i) {
        Vec3 next = p;
        for (int attempt = 0; attempt < 32; ++attempt) {
            Vec3 dir(rng.normal(), rng.normal(), rng.normal());
            dir /= std::max(glm::length(dir), 1e-12);
            const Vec3 q = glm::clamp(p + dir * rng.uniform(0.005, 0.03), lo, hi);
            if (detail::segmentClear(scene, slots, p, q, kFreeMarginM)) {
                next = q;
                break;
            }
        }
        const double duration =
            next == p ? rng.uniform(0.1, 0.3)
                      : moveDuration(glm::length(next - p), rng.uniform(0.03, peakHi));
        legs.emplace_back(next, duration);
        p = next;
    }
    for (const auto& [q, d] : legs) {
        plan.moveTo(q, d, ScriptPhase::Move);
    }
    for (std::size_t i = legs.size(); i-- > 0;) {
        plan.moveTo(i == 0 ? startWorld : legs[i - 1].first, legs[i].second, ScriptPhase::Move);
    }
    PlanChoice choice;
    choice.loopStart = 0;
    return choice;
}

// Slide on a box or mesh: along the longer in-face axis of the pressed face, within the face
// (a mesh: of its bounding box's face), out one way, back the other, home to `pressed`.
void slideOnFace(Builder& plan, const SceneObject& o, const detail::SurfacePoint& sp,
                 const Vec3& pressed, double speed) {
    const Obb box = o.obb();
    int normalAxis = 0;
    for (int i = 1; i < 3; ++i) {
        if (std::abs(glm::dot(box.axes[i], sp.normal)) >
            std::abs(glm::dot(box.axes[normalAxis], sp.normal))) {
            normalAxis = i;
        }
    }
    const int t1 = (normalAxis + 1) % 3, t2 = (normalAxis + 2) % 3;
    const int axis = box.halfExtents[t1] >= box.halfExtents[t2] ? t1 : t2;
    const Vec3 t = box.axes[axis];
    const double h = box.halfExtents[axis];
    const double m = std::min(kEdgeMarginM, 0.5 * h);
    const double u0 = glm::dot(sp.point - box.center, t);
    const double uHi = std::min(h - m, u0 + kSlideHalfSpanM);
    const double uLo = std::max(-h + m, u0 - kSlideHalfSpanM);
    plan.moveAt(pressed + t * (uHi - u0), speed, ScriptPhase::Slide);
    plan.moveAt(pressed + t * (uLo - u0), speed, ScriptPhase::Slide);
    plan.moveAt(pressed, speed, ScriptPhase::Slide);
}

// Slide on a sphere: along a great circle, `depth` below the surface, eased, as linear pieces.
void slideOnSphere(Builder& plan, const SceneObject& o, const detail::SurfacePoint& sp,
                   double depth, double speed) {
    const double r = o.radius() - depth;
    const Vec3 n = sp.normal, t = anyPerpendicular(n);
    const double maxAngle = std::min(kSlideHalfSpanM / o.radius(), 0.6);
    const auto arc = [&](double from, double to) {
        const double duration = moveDuration(std::abs(to - from) * o.radius(), speed);
        constexpr int kPieces = 24;
        for (int i = 1; i <= kPieces; ++i) {
            const double a = from + (to - from) * minJerk(static_cast<double>(i) / kPieces);
            plan.moveTo(o.center + r * (std::cos(a) * n + std::sin(a) * t), duration / kPieces,
                        ScriptPhase::Slide, false);
        }
    };
    arc(0.0, maxAngle);
    arc(maxAngle, -maxAngle);
    arc(-maxAngle, 0.0);
}

// Touch and slide: approach the chosen (else the nearest) surface, press into it, then hold
// (touch) or slide to and fro while pressing (slide, looping); with nothing to touch, stay put.
PlanChoice planTouch(Builder& plan, const SimConfig& config, const Scene& scene,
                     const Vec3& startWorld) {
    const std::optional<std::uint32_t> slot = config.object
                                                  ? std::optional(chosenSlot(config, scene))
                                                  : nearestSurface(scene, startWorld);
    PlanChoice choice;
    if (!slot) {
        plan.hold(1.0, ScriptPhase::Hold);
        return choice;
    }
    const SceneObject& o = scene.object(*slot);
    choice.object = o.id;
    const detail::SurfacePoint sp = detail::contactPoint(o, startWorld, kEdgeMarginM);
    choice.contactNormal = sp.normal;
    approach(plan, scene, sp.point + sp.normal * kStandOffM);
    const double depth = pressDepth(config);
    const Vec3 pressed = sp.point - sp.normal * depth;
    plan.moveAt(pressed, kPressSpeed, ScriptPhase::Press);
    plan.holdPress(true);
    if (config.script == HandScript::Touch) {
        plan.hold(0.5, ScriptPhase::Hold);
        return choice;
    }
    const double speed = std::min(kSlideSpeed, config.maxSpeedMPerS);
    choice.loopStart = plan.size() - 1;
    if (o.shape != Shape::Sphere) {
        slideOnFace(plan, o, sp, pressed, speed);
    } else {
        slideOnSphere(plan, o, sp, depth, speed);
    }
    return choice;
}

// The object a grasp takes: the chosen one, else the one nearest `near` whose both sides (-x
// and +x) a hand can reach among the 64 nearest (both hands decide the same way, sharing
// nothing), else the nearest one; nothing in an empty scene.
std::optional<std::uint32_t> graspSlot(const SimConfig& config, const Scene& scene) {
    if (config.object) {
        return chosenSlot(config, scene);
    }
    std::vector<std::pair<double, std::uint32_t>> byDistance;
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        byDistance.emplace_back(glm::length(scene.object(i).center - config.near), i);
    }
    std::sort(byDistance.begin(), byDistance.end());
    for (std::size_t k = 0; k < byDistance.size() && k < 64; ++k) {
        const SceneObject& o = scene.object(byDistance[k].second);
        const Vec3 x(1.0, 0.0, 0.0);
        if (reachableSide(scene, byDistance[k].second, o.center + x * surfaceAlong(o, x), x) &&
            reachableSide(scene, byDistance[k].second, o.center - x * surfaceAlong(o, -x), -x)) {
            return byDistance[k].second;
        }
    }
    if (!byDistance.empty()) {
        return byDistance.front().second;
    }
    return std::nullopt;
}

// The stand-off of a grasp: 2 cm out, or as far as the hand can stand where something else is
// nearer (a flat object lying 1.5 cm from a wall), down to the hand's free margin (m).
double graspStandOff(const Scene& scene, std::uint32_t slot, const Vec3& surface, const Vec3& out) {
    for (const double d : {kStandOffM, 0.015, 0.01, kFreeMarginM}) {
        if (reachableSide(scene, slot, surface, out, d)) {
            return d;
        }
    }
    return kStandOffM;
}

// The grasp's approach: a free path to the stand-off if there is one; else to above it, clear
// of everything near it, and straight down into it (the way into a narrow gap beside the
// object). The legs share the fixed approach time in proportion to their length.
void graspApproach(Builder& plan, const Scene& scene, const Vec3& startWorld,
                   const Vec3& standOff) {
    std::vector<Vec3> legs = connect(scene, startWorld, standOff);
    if (!freePath(scene, startWorld, legs)) {
        if (const std::optional<Vec3> above = clearAbove(scene, standOff)) {
            std::vector<Vec3> down = connect(scene, startWorld, *above);
            if (freePath(scene, startWorld, down)) {
                down.push_back(standOff);
                legs = std::move(down);
            }
        }
    }
    double total = 0.0;
    Vec3 p = startWorld;
    for (const Vec3& q : legs) {
        total += glm::length(q - p);
        p = q;
    }
    p = startWorld;
    if (total > 1e-9) {
        for (const Vec3& q : legs) {
            plan.moveTo(q, GraspTimes::kApproachEnd * glm::length(q - p) / total,
                        ScriptPhase::Approach);
            p = q;
        }
    }
    plan.holdUntil(GraspTimes::kApproachEnd, ScriptPhase::Approach);
}

// Where a grasp holds: a dynamic body on the axis through its centre of mass (squeezing there
// leaves gravity no lever about the axis between the hands, so two point contacts need no
// torsional friction to keep it from turning), a static object at its centre.
Vec3 graspCentre(const SceneObject& o) {
    return o.body.dynamic ? o.center + o.rotation * o.body.centerOfMassLocal : o.center;
}

// How far above its start a dynamic body is set down (m, along +y): the top of the highest
// other object under its footprint once carried, no higher than the lift takes its bottom
// (the floor under it gives 0). A static object is put back at its own height (0).
double setDownRaise(const Scene& scene, std::uint32_t slot, const SimConfig& config) {
    const SceneObject& o = scene.object(slot);
    if (!o.body.dynamic) {
        return 0.0;
    }
    const Aabb box = o.aabb();
    const double bottom = box.min.y;
    const double inset = 1e-4; // touching footprints side by side do not support it
    double raise = 0.0;
    for (std::uint32_t i = 0; i < scene.size(); ++i) {
        const Aabb other = scene.object(i).aabb();
        const bool under = i != slot && other.max.x > box.min.x + config.carry.x + inset &&
                           other.min.x < box.max.x + config.carry.x - inset &&
                           other.max.z > box.min.z + config.carry.z + inset &&
                           other.min.z < box.max.z + config.carry.z - inset &&
                           other.max.y <= bottom + config.lift.y;
        if (under) {
            raise = std::max(raise, other.max.y - bottom);
        }
    }
    return raise;
}

// A dynamic body's drop, after the first release: reach its sides where it was set down,
// squeeze again, lift it GraspTimes::kDropHeightM and open the hands quickly, so it falls.
void planDrop(Builder& plan, const Vec3& surface, const Vec3& squeezed, const Vec3& standOff) {
    using G = GraspTimes;
    const Vec3 up(0.0, G::kDropHeightM, 0.0);
    plan.moveTo(surface, G::kRegraspEnd - G::kReleaseEnd, ScriptPhase::Reach);
    plan.moveTo(squeezed, 0.5 * (G::kResqueezeEnd - G::kRegraspEnd), ScriptPhase::Squeeze);
    plan.holdPress(true);
    plan.holdUntil(G::kResqueezeEnd, ScriptPhase::Squeeze);
    plan.moveTo(squeezed + up, G::kDropLiftEnd - G::kResqueezeEnd, ScriptPhase::Lift);
    plan.holdPress(false);
    plan.moveTo(standOff + up, G::kDropEnd - G::kDropLiftEnd, ScriptPhase::Drop);
    plan.hold(0.5, ScriptPhase::Done);
}

// Grasp (left hand from -x, right from +x): approach the stand-off, reach the surface, squeeze,
// lift, carry, put down (a dynamic body on what is under it) and release on GraspTimes' fixed
// schedule, so two hands keep step; a dynamic body is then grasped again and dropped.
PlanChoice planGrasp(Builder& plan, const SimConfig& config, const Scene& scene,
                     const Vec3& startWorld) {
    PlanChoice choice;
    const std::optional<std::uint32_t> slot = graspSlot(config, scene);
    if (!slot) {
        plan.holdUntil(GraspTimes::kReleaseEnd, ScriptPhase::Done);
        return choice;
    }
    const SceneObject& o = scene.object(*slot);
    choice.object = o.id;
    const double side = config.script == HandScript::GraspLeft ? -1.0 : 1.0;
    const Vec3 out(side, 0.0, 0.0);
    const Vec3 centre = graspCentre(o);
    const Vec3 surface = centre + out * surfaceAlongFrom(o, centre, out);
    choice.contactNormal = out;
    const Vec3 standOff = surface + out * graspStandOff(scene, *slot, surface, out);
    const Vec3 squeezed = surface - out * pressDepth(config);
    const Vec3 setDown = config.carry + Vec3(0.0, setDownRaise(scene, *slot, config), 0.0);
    graspApproach(plan, scene, startWorld, standOff);
    using G = GraspTimes;
    plan.moveTo(surface, G::kReachEnd - G::kApproachEnd, ScriptPhase::Reach);
    plan.moveTo(squeezed, 0.5 * (G::kSqueezeEnd - G::kReachEnd), ScriptPhase::Squeeze);
    plan.holdPress(true);
    plan.holdUntil(G::kSqueezeEnd, ScriptPhase::Squeeze);
    plan.moveTo(squeezed + config.lift, G::kLiftEnd - G::kSqueezeEnd, ScriptPhase::Lift);
    plan.moveTo(squeezed + config.lift + config.carry, G::kCarryEnd - G::kLiftEnd,
                ScriptPhase::Carry);
    plan.moveTo(squeezed + setDown, G::kPutDownEnd - G::kCarryEnd, ScriptPhase::PutDown);
    plan.holdPress(false);
    plan.moveTo(standOff + setDown, G::kReleaseEnd - G::kPutDownEnd, ScriptPhase::Release);
    if (o.body.dynamic) {
        planDrop(plan, surface + setDown, squeezed + setDown, standOff + setDown);
        return choice;
    }
    plan.hold(0.5, ScriptPhase::Done);
    return choice;
}

} // namespace

std::string_view scriptPhaseName(ScriptPhase phase) {
    switch (phase) {
    case ScriptPhase::Move:
        return "move";
    case ScriptPhase::Approach:
        return "approach";
    case ScriptPhase::Press:
        return "press";
    case ScriptPhase::Hold:
        return "hold";
    case ScriptPhase::Slide:
        return "slide";
    case ScriptPhase::Reach:
        return "reach";
    case ScriptPhase::Squeeze:
        return "squeeze";
    case ScriptPhase::Lift:
        return "lift";
    case ScriptPhase::Carry:
        return "carry";
    case ScriptPhase::PutDown:
        return "put-down";
    case ScriptPhase::Release:
        return "release";
    case ScriptPhase::Done:
        return "done";
    case ScriptPhase::Drop:
        return "drop";
    }
    return "unknown";
}

SimScript::SimScript(std::vector<ScriptKeyframe> keyframes, std::optional<std::size_t> loopStart)
    : mKeyframes(std::move(keyframes)), mLoopStart(loopStart) {
    if (mKeyframes.empty()) {
        mKeyframes.push_back({});
    }
    if (mLoopStart && (*mLoopStart + 1 >= mKeyframes.size())) {
        mLoopStart.reset();
    }
}

ScriptSample SimScript::targetAt(double timeS, std::size_t& cursor) const {
    const ScriptKeyframe& back = mKeyframes.back();
    if (mLoopStart && timeS > back.timeS) {
        const double t0 = mKeyframes[*mLoopStart].timeS;
        const double period = back.timeS - t0;
        if (period > 0.0) {
            timeS = t0 + std::fmod(timeS - t0, period);
        }
    }
    if (mKeyframes.size() < 2 || timeS >= back.timeS) {
        return {back.target, back.phase, back.pressing};
    }
    if (timeS < 0.0) {
        timeS = 0.0;
    }
    if (cursor == 0 || cursor >= mKeyframes.size() || mKeyframes[cursor - 1].timeS > timeS) {
        cursor = 1;
    }
    while (mKeyframes[cursor].timeS <= timeS) {
        ++cursor;
    }
    const ScriptKeyframe& a = mKeyframes[cursor - 1];
    const ScriptKeyframe& b = mKeyframes[cursor];
    const double tau = (timeS - a.timeS) / (b.timeS - a.timeS);
    return {a.target + (b.target - a.target) * (b.smooth ? minJerk(tau) : tau), b.phase,
            b.pressing};
}

SimScript SimScript::plan(const SimConfig& config, const Scene& scene, const Vec3& startWorld) {
    Builder plan(startWorld);
    PlanChoice choice;
    switch (config.script) {
    case HandScript::Walk:
        choice = planWalk(plan, config, scene, startWorld);
        break;
    case HandScript::Free:
        choice = planFree(plan, config, scene, startWorld);
        break;
    case HandScript::Touch:
    case HandScript::Slide:
        choice = planTouch(plan, config, scene, startWorld);
        break;
    case HandScript::GraspLeft:
    case HandScript::GraspRight:
        choice = planGrasp(plan, config, scene, startWorld);
        break;
    default:
        throw InputError("unknown sim script '" + std::string(name(config.script)) +
                         "' (expected free, touch, slide, walk, grasp-left or grasp-right)");
    }
    SimScript script(plan.take(), choice.loopStart);
    script.mObject = choice.object;
    script.mContactNormal = choice.contactNormal;
    return script;
}

Quat scriptedOrientation(const Quat& start, const Vec3& spinRadPerS, double timeS) noexcept {
    const double rate = glm::length(spinRadPerS);
    if (!(rate > 0.0)) {
        return start;
    }
    return glm::normalize(glm::angleAxis(rate * timeS, spinRadPerS / rate) * start);
}

} // namespace hapto
