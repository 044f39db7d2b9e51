#pragma once
/// The scenes hapto_bench measures on, the walk that drives every structure through them, and
/// the check that every structure answers right.

#include "BroadPhase.h"

#include "hapto/index/IndexSpec.h"
#include "hapto/scenes/Scene.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace hapto::bench {

/// Edge of every cube in the benchmark scenes (m): 2 mm keeps 10^6 cubes sparse in the
/// 25 cm work cube (a point lies in 0.5 cubes on average at 10^6 random cubes).
inline constexpr double kCubeEdgeM = 0.002;
/// Edge of the work cube (m), the paper's 25 cm.
inline constexpr double kWorkspaceM = 0.25;
/// Clustered scenes: this many Gaussian clusters...
inline constexpr int kClusters = 8;
/// ... with this standard deviation (m).
inline constexpr double kClusterSpreadM = 0.02;
/// Forward steps of the walk (1 ms each); it then retraces itself, so it loops seamlessly.
inline constexpr std::size_t kWalkForwardSteps = std::size_t{1} << 15;

/// The two scene families.
enum class SceneKind : std::uint8_t {
    Random, ///< Cubes uniformly at random (makeRandomScene).
    Cluster ///< Cubes in Gaussian clusters (makeClusterScene).
};

/// "random" or "cluster". [any thread]
std::string_view sceneKindName(SceneKind kind);

/// A point where every structure is checked, with the right answers (slots, ascending).
struct CheckPoint {
    Vec3 point{0.0};                    ///< Where (m).
    std::vector<std::uint32_t> inAabb;  ///< Objects whose world AABB holds the point.
    std::vector<std::uint32_t> inSolid; ///< Objects whose solid holds the point (a subset).
};

/// One scene of the benchmark, with everything every structure shares.
struct SceneCase {
    SceneKind kind = SceneKind::Random; ///< Family.
    std::size_t count = 0;              ///< Objects.
    Scene scene;                        ///< The scene.
    std::vector<Aabb> boxes;            ///< World AABB of every object, by slot (m).
    std::vector<Vec3> walk;             ///< Hand-speed walk (m), a power of two long, cyclic.
    std::vector<CheckPoint> checks;     ///< Agreement checks: walk points and points in objects.
    IndexSpec grid;                     ///< hapto grid sized to the count.
    IndexSpec octree;                   ///< hapto octree for the cube size.
};

/// The case for a family and count, generated on first use. Only the most recent case is
/// kept (10^6 objects are large), so run benchmarks grouped by case. [control]
const SceneCase& sceneCase(SceneKind kind, std::size_t count);

/// The grid benchmarked at this count: n = round(cbrt(count / 2)) clamped to 4..128, about
/// two cubes per cell. [any thread]
IndexSpec gridSpecFor(std::size_t count);
/// The octree benchmarked: octree:8:0.001 (M = 8, minimum leaf edge 1 mm, half the cube
/// edge) at every count; the octree adapts by itself. [any thread]
IndexSpec octreeSpecFor(std::size_t count);

/// Checks a structure at every check point of the case. Every structure must return every
/// object whose solid holds the point, and nothing whose AABB misses it; one whose leaves are
/// cut exactly by AABBs (`exactAabb`, the baselines) must return exactly the AABB set.
/// Returns "" when all agree, else what went wrong where. [control]
template <class Structure>
std::string checkAgreement(Structure& s, const SceneCase& c, bool exactAabb) {
    std::vector<std::uint32_t> out;
    for (const CheckPoint& cp : c.checks) {
        s.query(cp.point, out);
        std::sort(out.begin(), out.end());
        const bool hasSolid =
            std::includes(out.begin(), out.end(), cp.inSolid.begin(), cp.inSolid.end());
        const bool inAabb =
            std::includes(cp.inAabb.begin(), cp.inAabb.end(), out.begin(), out.end());
        const bool exact = !exactAabb || out == cp.inAabb;
        if (!hasSolid || !inAabb || !exact) {
            return "disagrees at (" + std::to_string(cp.point.x) + ", " +
                   std::to_string(cp.point.y) + ", " + std::to_string(cp.point.z) + "): returned " +
                   std::to_string(out.size()) + " ids, " + std::to_string(cp.inAabb.size()) +
                   " AABBs and " + std::to_string(cp.inSolid.size()) + " solids hold the point" +
                   (!hasSolid ? " (an object holding the point is missing)" : "") +
                   (!inAabb ? " (an id whose AABB misses the point)" : "");
        }
    }
    return {};
}

} // namespace hapto::bench
