// The tick's stages over a coarse and a fine sphere (docs/results/tick-motions.md, "One walker
// along the way"): HapticTick::timeStages along mesh-tick's loop (tools/bench/MeshBench.cpp:
// down onto the pole of a 20 cm sphere, a wavy slide 1 mm inside it at 0.5 mm a tick, back
// out), 10 laps; medians (ns) of the whole tick, the locate, the slide's listing and the
// render (solves, walks, re-solves). Build against the `release` tree and run:
//
//   B=build/release; g++ -std=c++20 -O2 -DNDEBUG $(for d in */include; do echo -n "-I $d "; done) \
//     docs/results/tick/stages.cpp -o /tmp/stages $B/runtime/libhapto_runtime.a \
//     $B/index/libhapto_index.a $B/devices/libhapto_devices.a $B/scenes/libhapto_scenes.a \
//     $B/dynamics/libhapto_dynamics.a $B/index/libhapto_index.a $B/scenes/libhapto_scenes.a \
//     $B/io/libhapto_io.a $B/core/libhapto_core.a -ltbb -lusb-1.0 -lsimdjson -lqhull_r \
//     -lmeshoptimizer
//   /tmp/stages 1000000 0.00028; /tmp/stages 980 0.005   # triangles, the octree's leaf (m)
#include "hapto/index/IndexSpec.h"
#include "hapto/runtime/HapticTick.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/MeshGenerators.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

using namespace hapto;

static std::vector<Vec3> loop(double step) {
    const double outside = 0.11, inside = 0.099, reach = 0.3;
    const auto at = [](double a, double r) {
        return r * glm::normalize(Vec3(std::sin(a), 0.3 * std::sin(2.0 * a), std::cos(a)));
    };
    std::vector<Vec3> p;
    for (double r = outside; r > inside; r -= step) {
        p.push_back(at(0.0, r));
    }
    double a = 0.0, dir = 1.0;
    while (p.size() < 4096) {
        p.push_back(at(a, inside));
        a += dir * step / inside;
        dir = std::abs(a) > reach ? -dir : dir;
    }
    for (double r = inside; r < outside; r += step) {
        p.push_back(at(a, r));
    }
    return p;
}

static double median(std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
}

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: stages TRIANGLES LEAF_M\n");
        return 2;
    }
    MeshOptions o;
    o.shape = MeshShape::Sphere;
    o.triangles = std::strtoull(argv[1], nullptr, 10);
    o.size = 0.2;
    const Scene scene = makeMeshScene(o);
    const World world(scene, IndexSpec::octree(8, std::atof(argv[2])));
    HapticTick tick;
    HapticTick::StageStamps stamps{};
    tick.timeStages(&stamps);
    std::vector<double> all, locate, slide, render;
    double solves = 0.0, extra = 0.0;
    for (int lap = 0; lap < 10; ++lap) {
        for (const Vec3& p : loop(0.0005)) {
            const std::uint64_t t0 = rt::nowNs();
            const TickOutput out = tick.tick(world.current(), p, Vec3(0.0), 1e-3, Vec3(0.0));
            all.push_back(static_cast<double>(rt::nowNs() - t0));
            locate.push_back(static_cast<double>(stamps[0] - t0));
            slide.push_back(static_cast<double>(stamps[1] - stamps[0]));
            render.push_back(static_cast<double>(stamps[2] - stamps[1]));
            solves += out.solves;
            extra += out.extraLeaves;
        }
    }
    std::printf("%s triangles, octree:8:%s: tick %.0f ns | locate %.0f, slide %.0f, render %.0f | "
                "solves %.3f, extra leaves %.2f a tick\n",
                argv[1], argv[2], median(all), median(locate), median(slide), median(render),
                solves / all.size(), extra / all.size());
}
