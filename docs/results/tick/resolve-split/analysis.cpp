// Where the 10^6-triangle sphere's tick goes, solve by solve (docs/results/tick-motions.md,
// "What a re-solve costs on the fine sphere, and two ideas measured and not kept"). Needs the
// probes in probes.patch (timestamps around the tick's updates and inside
// GodObjectRenderer::update, the first unlisted leaf's segment, the slide's leaf count). From a
// clean tree at the commit named in tick-motions.md:
//
//   git apply docs/results/tick/resolve-split/probes.patch
//   cmake --build build/release --target hapto_runtime hapto_experiments
//   B=build/release; g++ -std=c++20 -O2 -DNDEBUG $(for d in */include; do echo -n "-I $d "; done) \
//     docs/results/tick/resolve-split/analysis.cpp -o /tmp/analysis \
//     $B/experiments/libhapto_experiments.a $B/runtime/libhapto_runtime.a $B/index/libhapto_index.a
//     \
//     $B/devices/libhapto_devices.a $B/scenes/libhapto_scenes.a $B/dynamics/libhapto_dynamics.a \
//     $B/index/libhapto_index.a $B/scenes/libhapto_scenes.a $B/io/libhapto_io.a \
//     $B/core/libhapto_core.a -ltbb -lusb-1.0 -lsimdjson -lqhull_r -lmeshoptimizer
//   /tmp/analysis; git checkout -- runtime
//
// The sphere motion of `hapto bench tick` (10^6 triangles, its default index
// octree:8:0.00028, 20 000 ticks) run three times over; the third run's ticks are reported:
// medians (ns) of the ticks that solved once and of those that solved twice, each cut at the
// probes, and then again with the goal's near list built once untimed before the timed build
// (what the first build pays for data the tick had not touched yet). Then, for the ticks that
// solved again, where the first unlisted leaf was met: the segment of the visited paths
// (path 0: the tick's start, the solve's start, each pass's end; 100 + i: the friction
// solve's) and how many slide leaves were listed before solving.
#include "hapto/experiments/TickMotion.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/runtime/HapticTick.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/World.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <utility>
#include <vector>

namespace hapto {
extern std::uint64_t gProbe[4];
extern std::uint64_t gUp[2][5];
extern bool gBuildTwice;
extern int gFirstMiss;
extern int gSlideLeaves;
} // namespace hapto

using namespace hapto;
using namespace hapto::experiments;

static double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

static void run(const World& world, const MotionCase& c, bool buildTwice, bool histogram) {
    gBuildTwice = buildTwice;
    std::vector<double> once[5], twice[9];
    std::map<std::pair<int, int>, int> misses;
    for (int round = 0; round < 3; ++round) {
        HapticTick tick;
        HapticTick::StageStamps stamps{};
        tick.timeStages(&stamps);
        for (const Vec3& p : c.path) {
            const std::uint64_t t0 = rt::nowNs();
            const TickOutput out = tick.tick(world.current(), p, Vec3(0.0), 1e-3, Vec3(0.0));
            const double t = static_cast<double>(rt::nowNs() - t0);
            if (round < 2) {
                continue;
            }
            const auto span = [](std::uint64_t a, std::uint64_t b) {
                return static_cast<double>(b - a);
            };
            if (out.solves == 1) {
                once[0].push_back(t);
                for (int k = 0; k < 4; ++k) {
                    once[k + 1].push_back(span(gUp[0][k], gUp[0][k + 1]));
                }
            } else if (out.solves == 2) {
                twice[0].push_back(t);
                twice[1].push_back(span(t0, gProbe[0]));
                twice[2].push_back(span(gProbe[0], gProbe[1]));
                twice[3].push_back(span(gProbe[1], gProbe[2]));
                twice[4].push_back(span(gProbe[2], gProbe[3]));
                twice[5].push_back(span(gProbe[3], stamps[4]));
                for (int k = 0; k < 3; ++k) {
                    twice[6 + k].push_back(span(gUp[1][k], gUp[1][k + 1]));
                }
                ++misses[{gFirstMiss, gSlideLeaves}];
            }
        }
    }
    std::printf("%s\n", buildTwice ? "goal's list built once untimed first:" : "as in main:");
    std::printf("  solved once (%zu ticks): tick %.0f | update: goal's near list %.0f, solve %.0f, "
                "friction %.0f, contacts %.0f\n",
                once[0].size(), median(once[0]), median(once[1]), median(once[2]), median(once[3]),
                median(once[4]));
    std::printf("  solved twice (%zu ticks): tick %.0f | before %.0f, update %.0f, paths walked "
                "%.0f, update again %.0f (near list %.0f, solve %.0f, friction %.0f), after %.0f\n",
                twice[0].size(), median(twice[0]), median(twice[1]), median(twice[2]),
                median(twice[3]), median(twice[4]), median(twice[6]), median(twice[7]),
                median(twice[8]), median(twice[5]));
    if (histogram) {
        for (const auto& [at, n] : misses) {
            std::printf("  first unlisted leaf on segment %d, %d slide leaves listed: %d ticks\n",
                        at.first, at.second, n);
        }
    }
}

int main() {
    MotionOptions options;
    options.objects = 1'000'000;
    options.ticks = 20'000;
    const MotionCase c = makeMotionCase(TickMotion::Sphere, options);
    const World world(c.scene, IndexSpec::octree(8, 0.00028));
    run(world, c, false, true);
    run(world, c, true, false);
}
