#include "hapto/scenes/Generators.h"

#include "hapto/core/Random.h"
#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"
#include "hapto/scenes/MassProperties.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace hapto {
namespace {

// Generated coordinates are rounded to 1 micrometre: far below anything a hand feels, and it
// keeps scene files short and exact when read back.
double quantise(double metres) {
    return std::round(metres * 1e6) / 1e6;
}

Vec3 quantise(const Vec3& v) {
    return {quantise(v.x), quantise(v.y), quantise(v.z)};
}

// A uniformly distributed rotation (Shoemake's subgroup algorithm).
Quat randomRotation(Random& rng) {
    const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
    const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
    const double t2 = 2.0 * std::numbers::pi * u2, t3 = 2.0 * std::numbers::pi * u3;
    return glm::normalize(
        Quat(b * std::cos(t3), a * std::sin(t2), a * std::cos(t2), b * std::sin(t3)));
}

// Half extent of the cube's world AABB: how far its centre must stay from a wall.
double aabbHalf(const SceneObject& o) {
    const Vec3 h = o.aabb().halfExtents();
    return std::max({h.x, h.y, h.z});
}

// Distance from p to the object's solid (0 inside).
double distanceTo(const SceneObject& o, const Vec3& p) {
    const Vec3 local = glm::abs(o.obb().toLocal(p));
    return glm::length(glm::max(local - o.halfExtents, Vec3(0.0)));
}

// Refuses a length (m) that is NaN, infinite, out of its range or above kMaxGeneratedLength,
// naming the generator and the option.
void checkLength(const char* generator, const char* option, double v, bool zeroAllowed) {
    if (!std::isfinite(v) || (zeroAllowed ? v < 0.0 : !(v > 0.0)) || v > kMaxGeneratedLength) {
        throw InputError(std::string(generator) + " scene: " + option + " must be a finite " +
                         (zeroAllowed ? "length >= 0" : "length > 0") + " of at most " +
                         json::show(kMaxGeneratedLength) + " m, got " + json::show(v));
    }
}

void checkCount(const char* generator, const char* option, double count) {
    if (count > static_cast<double>(kMaxGeneratedObjects)) {
        throw InputError(std::string(generator) + " scene: " + option + " asks for " +
                         json::show(count) + " objects; a generated scene holds at most " +
                         json::show(static_cast<double>(kMaxGeneratedObjects)) +
                         " (about 110 bytes each in memory, 184 in the file)");
    }
}

} // namespace

Material generatedMaterial() {
    Material m;
    m.staticFriction = 0.3;
    m.dynamicFriction = 0.2;
    return m;
}

Scene makeLatticeScene(const LatticeOptions& opt) {
    if (opt.perSide < 1) {
        throw InputError("lattice scene: --per-side must be >= 1, got " +
                         std::to_string(opt.perSide));
    }
    checkCount("lattice", "--per-side (cubed)", std::pow(static_cast<double>(opt.perSide), 3));
    checkLength("lattice", "--size", opt.cubeSize, false);
    checkLength("lattice", "--gap", opt.gap, true);
    const double pitch = opt.cubeSize + opt.gap;
    const int k = opt.perSide;
    std::vector<SceneObject> objects;
    objects.reserve(static_cast<std::size_t>(k) * k * k);
    const double offset = 0.5 * (k - 1) * pitch;
    ObjectId id = 0;
    for (int z = 0; z < k; ++z) {
        for (int y = 0; y < k; ++y) {
            for (int x = 0; x < k; ++x) {
                const Vec3 c =
                    quantise(Vec3(x * pitch - offset, y * pitch - offset, z * pitch - offset));
                objects.push_back(makeBox(id++, c, Vec3(0.5 * opt.cubeSize), Quat(1, 0, 0, 0),
                                          generatedMaterial()));
            }
        }
    }
    // At least 1 µm: a lattice smaller than the rounding would otherwise get empty bounds.
    const double half = std::max(quantise(0.5 * k * pitch), 1e-6);
    return Scene({Vec3(-half), Vec3(half)}, std::move(objects));
}

Scene makeRandomScene(const RandomOptions& opt) {
    checkCount("random", "--count", static_cast<double>(opt.count));
    checkLength("random", "--workspace", opt.workspace, false);
    checkLength("random", "--size", opt.cubeSize, false);
    checkLength("random", "--keep-clear", opt.keepClear, true);
    if (opt.cubeSize >= opt.workspace) {
        throw InputError("random scene: need --size < --workspace, got " +
                         json::show(opt.cubeSize) + " and " + json::show(opt.workspace));
    }
    Random rng(opt.seed);
    std::vector<SceneObject> objects;
    objects.reserve(opt.count);
    const double w = 0.5 * opt.workspace;
    for (std::size_t i = 0; i < opt.count; ++i) {
        int attempts = 0;
        for (;;) {
            SceneObject o =
                makeBox(static_cast<ObjectId>(i), Vec3(0.0), Vec3(0.5 * opt.cubeSize),
                        opt.rotate ? randomRotation(rng) : Quat(1, 0, 0, 0), generatedMaterial());
            const double inset = std::min(aabbHalf(o), w);
            o.center = quantise(Vec3(rng.uniform(-w + inset, w - inset),
                                     rng.uniform(-w + inset, w - inset),
                                     rng.uniform(-w + inset, w - inset)));
            if (opt.keepClear <= 0.0 || distanceTo(o, Vec3(0.0)) > opt.keepClear) {
                objects.push_back(o);
                break;
            }
            if (++attempts == 10000) {
                throw InputError("random scene: --keep-clear " + std::to_string(opt.keepClear) +
                                 " m leaves no room for a cube of " + std::to_string(opt.cubeSize) +
                                 " m in a " + std::to_string(opt.workspace) + " m workspace");
            }
        }
    }
    return Scene({Vec3(-w), Vec3(w)}, std::move(objects));
}

Scene makeClusterScene(const ClusterOptions& opt) {
    checkCount("cluster", "--count", static_cast<double>(opt.count));
    if (opt.clusters < 1) {
        throw InputError("cluster scene: --clusters must be >= 1, got " +
                         std::to_string(opt.clusters));
    }
    checkCount("cluster", "--clusters", static_cast<double>(opt.clusters));
    checkLength("cluster", "--workspace", opt.workspace, false);
    checkLength("cluster", "--size", opt.cubeSize, false);
    checkLength("cluster", "--spread", opt.spread, true);
    if (opt.cubeSize >= opt.workspace) {
        throw InputError("cluster scene: need --size < --workspace, got " +
                         json::show(opt.cubeSize) + " and " + json::show(opt.workspace));
    }
    Random rng(opt.seed);
    const double w = 0.5 * opt.workspace;
    std::vector<Vec3> centres;
    for (int c = 0; c < opt.clusters; ++c) {
        const double inset = 0.5 * opt.cubeSize;
        centres.emplace_back(rng.uniform(-w + inset, w - inset), rng.uniform(-w + inset, w - inset),
                             rng.uniform(-w + inset, w - inset));
    }
    std::vector<SceneObject> objects;
    objects.reserve(opt.count);
    for (std::size_t i = 0; i < opt.count; ++i) {
        SceneObject o =
            makeBox(static_cast<ObjectId>(i), Vec3(0.0), Vec3(0.5 * opt.cubeSize),
                    opt.rotate ? randomRotation(rng) : Quat(1, 0, 0, 0), generatedMaterial());
        const Vec3& cc = centres[rng.below(centres.size())];
        const double inset = std::min(aabbHalf(o), w);
        Vec3 c = cc + opt.spread * Vec3(rng.normal(), rng.normal(), rng.normal());
        c = glm::clamp(c, Vec3(-w + inset), Vec3(w - inset));
        o.center = quantise(c);
        objects.push_back(o);
    }
    return Scene({Vec3(-w), Vec3(w)}, std::move(objects));
}

Scene makeGraspScene() {
    Material rubbery = generatedMaterial();
    rubbery.staticFriction = 0.6;
    rubbery.dynamicFriction = 0.5;
    const Material m = generatedMaterial();
    std::vector<SceneObject> objects{
        makeBox(0, Vec3(-0.05, -0.075, 0.0), Vec3(0.025), Quat(1, 0, 0, 0), rubbery),
        makeBox(1, Vec3(0.0, -0.09, 0.0), Vec3(0.005, 0.01, 0.04), Quat(1, 0, 0, 0), m),
        makeBox(2, Vec3(-0.05, -0.075, 0.08), Vec3(0.025), Quat(1, 0, 0, 0), m),
        makeBox(3, Vec3(-0.05, -0.075, -0.08), Vec3(0.025), Quat(1, 0, 0, 0), m),
        makeSphere(4, Vec3(0.10, -0.08, -0.08), 0.02, m),
        makeBox(5, Vec3(0.12, -0.05, 0.06), Vec3(0.02, 0.05, 0.02), Quat(1, 0, 0, 0), m),
    };
    return Scene({Vec3(-0.15, -0.10, -0.15), Vec3(0.15, 0.15, 0.15)}, std::move(objects));
}

std::string_view graspObjectName(GraspObject object) {
    switch (object) {
    case GraspObject::Box:
        return "box";
    case GraspObject::Sphere:
        return "sphere";
    case GraspObject::Mesh:
        return "mesh";
    }
    return "box";
}

std::optional<GraspObject> parseGraspObject(std::string_view name) {
    for (const GraspObject o : {GraspObject::Box, GraspObject::Sphere, GraspObject::Mesh}) {
        if (name == graspObjectName(o)) {
            return o;
        }
    }
    return std::nullopt;
}

namespace {

// A closed octagonal prism about the origin, `apothem` (m) from its axis (y) to each of its
// eight side faces, one facing +x and one -x, and as tall as it is wide across them: 16
// vertices, 28 triangles (two per side, a fan of six per cap), counter-clockwise outward.
std::shared_ptr<const TriangleMesh> octagonalPrism(double apothem) {
    const double pi = std::numbers::pi;
    const double r = apothem / std::cos(pi / 8.0);
    std::vector<Vec3> v;
    for (const double y : {-apothem, apothem}) {
        for (int i = 0; i < 8; ++i) {
            const double a = (i + 0.5) * pi / 4.0;
            v.emplace_back(r * std::cos(a), y, r * std::sin(a));
        }
    }
    std::vector<TriangleIndices> t;
    for (std::uint32_t i = 0; i < 8; ++i) {
        const std::uint32_t j = (i + 1) % 8;
        t.push_back({i, j, j + 8});
        t.push_back({i, j + 8, i + 8});
    }
    for (std::uint32_t i = 1; i + 1 < 8; ++i) {
        t.push_back({0, i, i + 1});
        t.push_back({8, 8 + i, 8 + i + 1});
    }
    for (TriangleIndices& k : t) { // a convex solid about the origin: outward is away from it
        const Vec3 n = glm::cross(v[k[1]] - v[k[0]], v[k[2]] - v[k[0]]);
        if (glm::dot(n, v[k[0]] + v[k[1]] + v[k[2]]) < 0.0) {
            std::swap(k[1], k[2]);
        }
    }
    return TriangleMesh::make(std::move(v), std::move(t), {}, "the grasp demo's prism");
}

// The physical demo's object 0, 5 cm across, resting on the floor (y = -0.10 m) at x = -0.05:
// 100 g (a 5 cm cube of density 800 kg/m^3, a softwood), rubbery, dynamic.
SceneObject dynamicGraspObject(GraspObject shape, const Material& rubbery) {
    const double floorY = -0.10;
    const double half = 0.025;
    SceneObject o;
    if (shape == GraspObject::Box) {
        o = makeBox(0, Vec3(-0.05, floorY + half, 0.0), Vec3(half), Quat(1, 0, 0, 0), rubbery);
    } else if (shape == GraspObject::Sphere) {
        o = makeSphere(0, Vec3(-0.05, floorY + half, 0.0), half, rubbery);
    } else {
        o = makeMesh(0, Vec3(-0.05, floorY + half, 0.0), octagonalPrism(half), Quat(1, 0, 0, 0),
                     rubbery);
    }
    o.body.dynamic = true;
    fillMassProperties(o, 0.1, std::nullopt, std::nullopt);
    return o;
}

} // namespace

Scene makeDynamicGraspScene(GraspObject shape) {
    const Scene kinematic = makeGraspScene();
    std::vector<SceneObject> objects(kinematic.objects().begin(), kinematic.objects().end());
    objects[0] = dynamicGraspObject(shape, objects[0].material);
    const Material m = generatedMaterial();
    objects.push_back(makeBox(6, Vec3(0.0, -0.105, 0.0), Vec3(0.15, 0.005, 0.15), Quat(1, 0, 0, 0),
                              m)); // the floor, top at y = -0.10
    objects.push_back(makeBox(7, Vec3(0.05, -0.09, 0.0), Vec3(0.03, 0.01, 0.03), Quat(1, 0, 0, 0),
                              m)); // the plinth, top at y = -0.08
    Aabb bounds = kinematic.bounds();
    bounds.min.y = -0.11;
    Scene scene(bounds, std::move(objects));
    scene.setPhysics(ScenePhysics{}); // g = 9.81 m/s^2 along -y, 1 kHz
    return scene;
}

Scene makeDefaultScene() {
    RandomOptions opt;
    opt.count = 200;
    opt.seed = 2004;
    opt.keepClear = 0.04;
    return makeRandomScene(opt);
}

} // namespace hapto
