// hapto_bench, mesh scenes: one generated geodesic sphere (`hapto scene mesh --shape sphere`) of
// 10^3 .. 10^6 triangles, 20 cm across, and a hand sliding on it.
//
// Benchmarks, named mesh-KIND/sphere/N/STRUCTURE:
//   mesh-near  "which triangles are near this point": one query per iteration along one loop
//              (down onto the pole, a slide 1 mm inside the surface, back out; 0.5 mm
//              steps), answered by
//                hapto-octree / hapto-grid  the cursor's locate: the leaf's triangle items
//                                           (what the servo path hands the renderer);
//                bullet-bvh   btBvhTriangleMeshShape::processAllTriangles over the cube of
//                             half-edge r = 2 mm around the point (triangles whose quantised
//                             AABB overlaps it);
//                fcl-obbrss   fcl::collide of BVHModel<OBBRSS> with a sphere of radius r
//                             (triangles that really touch the sphere, up to 10^5 contacts).
//              Counter: candidates per query (what each hands on).
//   mesh-build one build per iteration (wall clock, each run from a trimmed heap: buildLoop
//              in HeapUsage.h): hapto's index over the scene's triangle items (2 TBB threads),
//              Bullet's BVH, FCL's OBBRSS tree; counters bytes_per_triangle (hapto:
//              IndexStats bytes; the others: heap growth).
//   mesh-tick  the servo path's full tick (HapticTick: locate, candidates, god-object render,
//              safety) along the same loop; manual time per tick; counters p50_ns, p99_ns,
//              contact (the share of ticks in contact), and per tick: tested (candidate items
//              examined), passes (the last solve's solver passes), solves (the renderer's
//              solves: 1 + re-solves + pull-backs) and extra_leaves (leaves listed beyond the
//              device's and the proxy's).
//   mesh-tick-slow  the same at 0.1 mm steps (0.1 m/s): a hand feeling the surface, which
//              crosses a fifth as many facets per tick.
//   mesh-tick-patch  like for like: the same tick along a short loop (the slide only +-2 mm
//              about the pole), over the 10^6-triangle sphere's N triangles nearest the pole
//              (N = 10^3 .. 10^5; the patch keeps the sphere's bounds, so the octree cuts its
//              cells where it cuts the sphere's) and over the whole sphere ("whole"). The
//              hand meets the same facets in every scene, so what changes with N is the index
//              and the memory it spans, not the geometry; mesh-tick compares a coarse sphere
//              with a fine one, whose facets are 32 times smaller. Counter patch_mm: how far
//              the patch reaches from the axis through the pole (the loop: 2 mm).
//
//   hapto_bench --benchmark_filter='^mesh-' --benchmark_min_time=0.5

#include "HeapUsage.h"

#include "hapto/index/Cursor.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/runtime/HapticTick.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/MeshGenerators.h"

#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <benchmark/benchmark.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace hapto::bench {
namespace {

constexpr double kSphereSizeM = 0.2;  // diameter
constexpr double kPressM = 0.001;     // the path runs this far inside the surface
constexpr double kNearM = 0.002;      // r: "near" for the baselines
constexpr double kStepM = 0.0005;     // path spacing: 0.5 m/s at 1 kHz
constexpr double kSlowStepM = 0.0001; // mesh-tick-slow's: 0.1 m/s, a hand feeling a surface
constexpr std::size_t kPathPoints = 4096;
constexpr double kSlideRad = 0.3;            // the slide's reach about the pole: +-3 cm
constexpr double kPatchSlideRad = 0.02;      // mesh-tick-patch's: +-2 mm
constexpr std::size_t kFineSphere = 1000000; // mesh-tick-patch's sphere (about 10^6 triangles)

/// The sphere scene of about n triangles, made once per n.
const Scene& meshScene(std::size_t n) {
    static std::map<std::size_t, Scene> scenes;
    auto it = scenes.find(n);
    if (it == scenes.end()) {
        MeshOptions o;
        o.shape = MeshShape::Sphere;
        o.triangles = n;
        o.size = kSphereSizeM;
        it = scenes.emplace(n, makeMeshScene(o)).first;
    }
    return it->second;
}

/// A touch and slide on the sphere's top, as a loop: down the +z axis from 1 cm above the pole
/// to kPressM inside, a slide along a wavy great circle through the pole (+-`reach` rad, back
/// and forth) kPressM inside, and back out along the radius; `step` apart.
const std::vector<Vec3>& slidePath(double step = kStepM, double reach = kSlideRad) {
    static std::map<std::pair<double, double>, std::vector<Vec3>> paths;
    auto found = paths.find({step, reach});
    if (found != paths.end()) {
        return found->second;
    }
    const std::vector<Vec3> path = [step, reach] {
        std::vector<Vec3> p;
        const double outside = 0.5 * kSphereSizeM + 0.01, inside = 0.5 * kSphereSizeM - kPressM;
        // A wavy line over the sphere, every point at distance r from its centre (kPressM
        // inside the sphere, deeper than the flat facets of the coarsest mesh sit below it).
        const auto onRadius = [](double a, double r) {
            return r * glm::normalize(Vec3(std::sin(a), 0.3 * std::sin(2.0 * a), std::cos(a)));
        };
        for (double r = outside; r > inside; r -= step) {
            p.push_back(onRadius(0.0, r));
        }
        const double dA = step / inside;
        double a = 0.0, dir = 1.0;
        while (p.size() < kPathPoints) {
            p.push_back(onRadius(a, inside));
            a += dir * dA;
            if (std::abs(a) > reach) {
                dir = -dir;
            }
        }
        for (double r = inside; r < outside; r += step) {
            p.push_back(onRadius(a, r));
        }
        return p;
    }();
    return paths.emplace(std::make_pair(step, reach), path).first->second;
}

IndexSpec meshSpec(bool grid) {
    return grid ? IndexSpec::grid(64) : IndexSpec::octree(8, 0.0005);
}

// ---- Bullet ----------------------------------------------------------------------------------

std::vector<int> flatIndices(const TriangleMesh& mesh) {
    std::vector<int> idx;
    idx.reserve(mesh.triangles().size() * 3);
    for (const TriangleIndices& t : mesh.triangles()) {
        idx.insert(idx.end(),
                   {static_cast<int>(t[0]), static_cast<int>(t[1]), static_cast<int>(t[2])});
    }
    return idx;
}

static_assert(sizeof(btScalar) == sizeof(double), "hapto_bench links Bullet's float64 build");

/// Bullet's mesh over the TriangleMesh's own vertices (3 doubles each, no copy) and a copy of
/// its indices as int; the BVH is quantised (Bullet's default for static meshes, up to 2^21
/// triangles).
struct BulletMesh {
    explicit BulletMesh(const TriangleMesh& mesh)
        : indices(flatIndices(mesh)),
          array(static_cast<int>(mesh.triangleCount()), indices.data(), 3 * sizeof(int),
                static_cast<int>(mesh.vertices().size()),
                const_cast<btScalar*>(&mesh.vertices()[0].x), sizeof(Vec3)),
          shape(&array, true, true) {}
    std::vector<int> indices;
    btTriangleIndexVertexArray array;
    btBvhTriangleMeshShape shape;
};

struct CountTriangles final : btTriangleCallback {
    void processTriangle(btVector3*, int, int triangle) override {
        ++count;
        if (ids) {
            ids->push_back(static_cast<std::uint32_t>(triangle));
        }
    }
    std::uint32_t count = 0;
    std::vector<std::uint32_t>* ids = nullptr; // set while checking
};

/// The triangles whose exact AABB overlaps the cube of half-edge kNearM around p, sorted.
std::vector<std::uint32_t> aabbNear(const TriangleMesh& mesh, const Vec3& p) {
    const Aabb cube{p - Vec3(kNearM), p + Vec3(kNearM)};
    std::vector<std::uint32_t> out;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        Aabb b = Aabb::empty();
        for (const Vec3& c : mesh.corners(t)) {
            b.expand(c);
        }
        if (b.overlaps(cube)) {
            out.push_back(t);
        }
    }
    return out;
}

std::size_t gMeshFailures = 0; // mesh structures that disagreed with brute force
std::size_t gMeshChecks = 0;   // mesh check points passed

constexpr std::size_t kCheckPoints = 64; // path points checked against brute force, first call

/// "" when every id of `need` is in `have` (both sorted), else what is missing.
std::string missing(const std::vector<std::uint32_t>& have, const std::vector<std::uint32_t>& need,
                    const char* what) {
    return std::includes(have.begin(), have.end(), need.begin(), need.end()) ? std::string()
                                                                             : std::string(what);
}

// ---- FCL -------------------------------------------------------------------------------------

using FclModel = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<FclModel> makeFcl(const TriangleMesh& mesh) {
    std::vector<fcl::Vector3d> v;
    v.reserve(mesh.vertices().size());
    for (const Vec3& p : mesh.vertices()) {
        v.emplace_back(p.x, p.y, p.z);
    }
    std::vector<fcl::Triangle> t;
    t.reserve(mesh.triangleCount());
    for (const TriangleIndices& i : mesh.triangles()) {
        t.emplace_back(i[0], i[1], i[2]);
    }
    auto model = std::make_shared<FclModel>();
    model->beginModel(static_cast<int>(t.size()), static_cast<int>(v.size()));
    model->addSubModel(v, t);
    model->endModel();
    return model;
}

// ---- benchmarks ------------------------------------------------------------------------------

void nearHapto(benchmark::State& state, std::size_t n, bool grid) {
    const Scene& scene = meshScene(n);
    const std::shared_ptr<const SpatialIndex> index = buildIndex(scene, meshSpec(grid));
    Cursor cursor(*index, CursorStrategy::NeighbourLinks);
    const std::vector<Vec3>& path = slidePath();
    std::size_t i = 0;
    double candidates = 0;
    for (auto _ : state) {
        const LocateResult r = cursor.locate(path[i]);
        benchmark::DoNotOptimize(r.candidates.data());
        candidates += static_cast<double>(r.candidates.size());
        i = (i + 1) % path.size();
    }
    state.counters["candidates"] =
        benchmark::Counter(candidates, benchmark::Counter::kAvgIterations);
    state.counters["triangles"] = scene.triangleCount();
}

void nearBullet(benchmark::State& state, std::size_t n) {
    const Scene& scene = meshScene(n);
    const TriangleMesh& mesh = *scene.object(0).mesh;
    const auto bullet = std::make_unique<BulletMesh>(mesh);
    const std::vector<Vec3>& path = slidePath();
    // Check: Bullet returns at least every triangle whose AABB overlaps the query cube.
    for (std::size_t k = 0; k < kCheckPoints; ++k) {
        const Vec3& p = path[k * path.size() / kCheckPoints];
        std::vector<std::uint32_t> ids;
        CountTriangles callback;
        callback.ids = &ids;
        bullet->shape.processAllTriangles(&callback,
                                          btVector3(p.x - kNearM, p.y - kNearM, p.z - kNearM),
                                          btVector3(p.x + kNearM, p.y + kNearM, p.z + kNearM));
        std::sort(ids.begin(), ids.end());
        const std::string error = missing(ids, aabbNear(mesh, p), "bullet-bvh missed a triangle");
        if (!error.empty()) {
            ++gMeshFailures;
            state.SkipWithError(error.c_str());
            return;
        }
        ++gMeshChecks;
    }
    std::size_t i = 0;
    double candidates = 0;
    for (auto _ : state) {
        const Vec3& p = path[i];
        CountTriangles callback;
        bullet->shape.processAllTriangles(&callback,
                                          btVector3(p.x - kNearM, p.y - kNearM, p.z - kNearM),
                                          btVector3(p.x + kNearM, p.y + kNearM, p.z + kNearM));
        candidates += callback.count;
        i = (i + 1) % path.size();
    }
    state.counters["candidates"] =
        benchmark::Counter(candidates, benchmark::Counter::kAvgIterations);
    state.counters["triangles"] = scene.triangleCount();
}

void nearFcl(benchmark::State& state, std::size_t n) {
    const Scene& scene = meshScene(n);
    fcl::CollisionObjectd meshObject(makeFcl(*scene.object(0).mesh));
    fcl::CollisionObjectd probe(std::make_shared<fcl::Sphered>(kNearM));
    fcl::CollisionRequestd request(100000, false);
    fcl::CollisionResultd result;
    const std::vector<Vec3>& path = slidePath();
    // Check: FCL's triangles touch the sphere, so their AABBs overlap the cube around it.
    for (std::size_t k = 0; k < kCheckPoints; ++k) {
        const Vec3& p = path[k * path.size() / kCheckPoints];
        probe.setTranslation(fcl::Vector3d(p.x, p.y, p.z));
        probe.computeAABB();
        result.clear();
        fcl::collide(&meshObject, &probe, request, result);
        std::vector<std::uint32_t> ids;
        for (std::size_t c = 0; c < result.numContacts(); ++c) {
            ids.push_back(static_cast<std::uint32_t>(result.getContact(c).b1));
        }
        std::sort(ids.begin(), ids.end());
        ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
        const std::string error =
            missing(aabbNear(*scene.object(0).mesh, p), ids, "fcl-obbrss returned a far triangle");
        if (!error.empty()) {
            ++gMeshFailures;
            state.SkipWithError(error.c_str());
            return;
        }
        ++gMeshChecks;
    }
    std::size_t i = 0;
    double candidates = 0;
    for (auto _ : state) {
        const Vec3& p = path[i];
        probe.setTranslation(fcl::Vector3d(p.x, p.y, p.z));
        probe.computeAABB();
        result.clear();
        fcl::collide(&meshObject, &probe, request, result);
        candidates += static_cast<double>(result.numContacts());
        i = (i + 1) % path.size();
    }
    state.counters["candidates"] =
        benchmark::Counter(candidates, benchmark::Counter::kAvgIterations);
    state.counters["triangles"] = scene.triangleCount();
}

void buildMesh(benchmark::State& state, std::size_t n, int which) {
    const Scene& scene = meshScene(n);
    const TriangleMesh& mesh = *scene.object(0).mesh;
    const std::size_t triangles = scene.triangleCount();
    double heap = 0.0; // bytes per triangle, the first build's heap growth
    double bytes = 0.0;
    if (which == 0 || which == 1) {
        const auto index = buildLoop(state, triangles, heap, [&] {
            return std::unique_ptr<const SpatialIndex>(buildIndex(scene, meshSpec(which == 1)));
        });
        bytes = index ? static_cast<double>(index->stats().bytes) / triangles : 0.0;
    } else if (which == 2) {
        buildLoop(state, triangles, heap, [&] { return std::make_unique<BulletMesh>(mesh); });
        bytes = heap;
    } else {
        buildLoop(state, triangles, heap, [&] { return makeFcl(mesh); });
        bytes = heap;
    }
    state.counters["bytes_per_triangle"] = bytes;
    state.counters["triangles"] = static_cast<double>(triangles);
}

/// The fine sphere's n triangles nearest its pole, as a scene with the sphere's bounds (n = 0:
/// the whole sphere); made once per n.
const Scene& patchScene(std::size_t n) {
    static std::map<std::size_t, Scene> scenes;
    auto it = scenes.find(n);
    if (it != scenes.end()) {
        return it->second;
    }
    const Scene& sphere = meshScene(kFineSphere);
    if (n == 0 || n >= sphere.triangleCount()) {
        return scenes.emplace(n, sphere).first->second;
    }
    const TriangleMesh& mesh = *sphere.object(0).mesh;
    const Vec3 pole(0.0, 0.0, 0.5 * kSphereSizeM);
    // A triangle's distance from the pole: its farthest corner's.
    const auto far = [&](std::uint32_t t) {
        const auto c = mesh.corners(t);
        return std::max(
            {glm::distance(c[0], pole), glm::distance(c[1], pole), glm::distance(c[2], pole)});
    };
    std::vector<std::uint32_t> order(mesh.triangleCount());
    for (std::uint32_t t = 0; t < order.size(); ++t) {
        order[t] = t;
    }
    std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(n), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return far(a) < far(b); });
    order.resize(n);
    std::sort(order.begin(), order.end()); // the sphere's order, so its memory layout
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
    std::map<std::uint32_t, std::uint32_t> renumber;
    for (const std::uint32_t t : order) {
        TriangleIndices out{};
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t v = mesh.triangles()[t][static_cast<std::size_t>(k)];
            const auto [at, added] =
                renumber.emplace(v, static_cast<std::uint32_t>(vertices.size()));
            if (added) {
                vertices.push_back(mesh.vertices()[v]);
            }
            out[static_cast<std::size_t>(k)] = at->second;
        }
        triangles.push_back(out);
    }
    std::vector<SceneObject> objects;
    objects.push_back(makeMesh(
        0, Vec3(0.0),
        TriangleMesh::make(std::move(vertices), std::move(triangles), {}, "mesh-tick-patch"),
        Quat(1, 0, 0, 0), sphere.object(0).material));
    return scenes.emplace(n, Scene(sphere.bounds(), std::move(objects))).first->second;
}

void tickMesh(benchmark::State& state, const Scene& scene, bool grid,
              const std::vector<Vec3>& path) {
    World world(scene, meshSpec(grid));
    HapticTick tick;
    std::vector<double> ns;
    ns.reserve(1 << 20);
    std::size_t i = 0;
    double contacts = 0;
    double tested = 0;
    double passes = 0;
    double extra = 0;
    double solves = 0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        const TickOutput out = tick.tick(world.current(), path[i], Vec3(0.0), 1e-3, Vec3(0.0));
        const auto t1 = std::chrono::steady_clock::now();
        benchmark::DoNotOptimize(out.forceN);
        const double s = std::chrono::duration<double>(t1 - t0).count();
        state.SetIterationTime(s);
        if (ns.size() < ns.capacity()) {
            ns.push_back(1e9 * s);
        }
        contacts += out.render.contactCount > 0;
        tested += out.render.objectsTested;
        passes += out.render.iterations;
        extra += out.extraLeaves;
        solves += out.solves;
        i = (i + 1) % path.size();
    }
    std::sort(ns.begin(), ns.end());
    const auto pct = [&](double q) {
        return ns.empty() ? 0.0
                          : ns[static_cast<std::size_t>(q * static_cast<double>(ns.size() - 1))];
    };
    state.counters["p50_ns"] = pct(0.5);
    state.counters["p99_ns"] = pct(0.99);
    state.counters["contact"] = benchmark::Counter(contacts, benchmark::Counter::kAvgIterations);
    state.counters["tested"] = benchmark::Counter(tested, benchmark::Counter::kAvgIterations);
    state.counters["passes"] = benchmark::Counter(passes, benchmark::Counter::kAvgIterations);
    state.counters["extra_leaves"] = benchmark::Counter(extra, benchmark::Counter::kAvgIterations);
    state.counters["solves"] = benchmark::Counter(solves, benchmark::Counter::kAvgIterations);
    state.counters["triangles"] = scene.triangleCount();
}

} // namespace

std::size_t meshCheckFailures() {
    return gMeshFailures;
}

std::size_t meshChecksPassed() {
    return gMeshChecks;
}

void registerMeshBenchmarks() {
    using benchmark::RegisterBenchmark;
    for (const std::size_t n : {1000, 10000, 100000, 1000000}) {
        const std::string sn = "sphere/" + std::to_string(n) + "/";
        RegisterBenchmark(("mesh-build/" + sn + "hapto-octree").c_str(), buildMesh, n, 0)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
        RegisterBenchmark(("mesh-build/" + sn + "hapto-grid").c_str(), buildMesh, n, 1)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
        RegisterBenchmark(("mesh-build/" + sn + "bullet-bvh").c_str(), buildMesh, n, 2)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
        RegisterBenchmark(("mesh-build/" + sn + "fcl-obbrss").c_str(), buildMesh, n, 3)
            ->UseRealTime()
            ->Unit(benchmark::kMillisecond);
        RegisterBenchmark(("mesh-near/" + sn + "hapto-octree").c_str(), nearHapto, n, false);
        RegisterBenchmark(("mesh-near/" + sn + "hapto-grid").c_str(), nearHapto, n, true);
        RegisterBenchmark(("mesh-near/" + sn + "bullet-bvh").c_str(), nearBullet, n);
        RegisterBenchmark(("mesh-near/" + sn + "fcl-obbrss").c_str(), nearFcl, n);
        RegisterBenchmark(
            ("mesh-tick/" + sn + "hapto-octree").c_str(),
            [n](benchmark::State& state) { tickMesh(state, meshScene(n), false, slidePath()); })
            ->UseManualTime();
        RegisterBenchmark(("mesh-tick-slow/" + sn + "hapto-octree").c_str(),
                          [n](benchmark::State& state) {
                              tickMesh(state, meshScene(n), false, slidePath(kSlowStepM));
                          })
            ->UseManualTime();
    }
    for (const std::size_t n : {1000, 10000, 100000, 0}) {
        const std::string name = n == 0 ? "whole" : std::to_string(n);
        RegisterBenchmark(("mesh-tick-patch/sphere-1000000/" + name + "/hapto-octree").c_str(),
                          [n](benchmark::State& state) {
                              const Scene& scene = patchScene(n);
                              tickMesh(state, scene, false, slidePath(kStepM, kPatchSlideRad));
                              // How far the patch reaches from the pole's axis (mm).
                              double reach = 0.0;
                              for (const Vec3& v : scene.object(0).mesh->vertices()) {
                                  reach = std::max(reach, std::hypot(v.x, v.y));
                              }
                              state.counters["patch_mm"] = 1e3 * reach;
                          })
            ->UseManualTime();
    }
}

} // namespace hapto::bench
