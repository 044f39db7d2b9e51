#include "BenchScenes.h"

#include "hapto/experiments/HandWalk.h"

#include "hapto/core/Random.h"
#include "hapto/scenes/Generators.h"

#include <cmath>
#include <memory>

namespace hapto::bench {
namespace {

/// Check points: about 2^27 / N (128..1024), half on the walk, half inside random objects.
std::vector<CheckPoint> makeChecks(const SceneCase& c) {
    const std::size_t n = std::max<std::size_t>(c.count, 1);
    const std::size_t total = std::clamp<std::size_t>((std::size_t{1} << 27) / n, 128, 1024);
    std::vector<CheckPoint> checks;
    for (std::size_t i = 0; i < total / 2; ++i) {
        checks.push_back({c.walk[i * c.walk.size() / (total / 2)], {}, {}});
    }
    Random random(7);
    for (std::size_t i = 0; i < total / 2 && c.count > 0; ++i) {
        const SceneObject& o = c.scene.object(static_cast<std::uint32_t>(random.below(c.count)));
        Vec3 local(0.0);
        for (int a = 0; a < 3; ++a) {
            local[a] = random.uniform(-0.95, 0.95) * o.halfExtents[a];
        }
        const Vec3 p = o.shape == Shape::Box ? o.center + o.rotation * local : o.center;
        checks.push_back({glm::clamp(p, c.scene.bounds().min, c.scene.bounds().max), {}, {}});
    }
    for (CheckPoint& cp : checks) {
        for (std::uint32_t slot = 0; slot < c.count; ++slot) {
            if (c.boxes[slot].contains(cp.point)) {
                cp.inAabb.push_back(slot);
                if (c.scene.object(slot).contains(cp.point)) {
                    cp.inSolid.push_back(slot);
                }
            }
        }
    }
    return checks;
}

std::unique_ptr<SceneCase> makeCase(SceneKind kind, std::size_t count) {
    auto c = std::make_unique<SceneCase>();
    c->kind = kind;
    c->count = count;
    if (kind == SceneKind::Random) {
        RandomOptions o;
        o.count = count;
        o.seed = 1;
        o.workspace = kWorkspaceM;
        o.cubeSize = kCubeEdgeM;
        c->scene = makeRandomScene(o);
    } else {
        ClusterOptions o;
        o.count = count;
        o.clusters = kClusters;
        o.seed = 1;
        o.workspace = kWorkspaceM;
        o.cubeSize = kCubeEdgeM;
        o.spread = kClusterSpreadM;
        c->scene = makeClusterScene(o);
    }
    c->boxes.reserve(count);
    for (const SceneObject& o : c->scene.objects()) {
        c->boxes.push_back(o.aabb());
    }
    c->walk = experiments::makeHandWalk(c->scene.bounds(), 1, kWalkForwardSteps);
    c->walk.insert(c->walk.end(), c->walk.rbegin(), c->walk.rend()); // retrace: a seamless loop
    c->checks = makeChecks(*c);
    c->grid = gridSpecFor(count);
    c->octree = octreeSpecFor(count);
    return c;
}

} // namespace

std::string_view sceneKindName(SceneKind kind) {
    return kind == SceneKind::Random ? "random" : "cluster";
}

IndexSpec gridSpecFor(std::size_t count) {
    const double n = std::round(std::cbrt(static_cast<double>(count) / 2.0));
    return IndexSpec::grid(static_cast<int>(std::clamp(n, 4.0, 128.0)));
}

IndexSpec octreeSpecFor(std::size_t) {
    return IndexSpec::octree(8, 0.001);
}

const SceneCase& sceneCase(SceneKind kind, std::size_t count) {
    static std::unique_ptr<SceneCase> current;
    if (!current || current->kind != kind || current->count != count) {
        current.reset(); // free the old one first: two 10^6 cases at once are wasteful
        current = makeCase(kind, count);
    }
    return *current;
}

} // namespace hapto::bench
