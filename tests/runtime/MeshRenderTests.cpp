// The god-object on triangle meshes, by direct renderer calls: a flat mesh feels like the box
// face it replaces, closed meshes hold at edges and vertices, concave corners hold three
// planes, coplanar triangles do not snag, meshes are one-sided, a device may start inside, and
// a moving mesh (its object slot, as the moving list hands it over) carries the proxy.

#include "hapto/core/ShapeGeometry.h"
#include "hapto/runtime/GodObjectRenderer.h"

#include "MeshShapes.h"
#include "RenderTestSupport.h"

#include "hapto/core/Random.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

using namespace hapto;
using namespace hapto::test;

namespace {

constexpr double kMeshK = 1000.0; // N/m
constexpr double kSkin = GodObjectRenderer::kSkinM;
// A mesh face and the box face it replaces compute the same planes through different
// arithmetic (a triangle's cross product, a box's rotated axes): they agree to rounding,
// ~1e-16 m on the proxy, ~1e-13 N on the force. 1e-9 N leaves room for that and nothing else
// (a proxy off by 1 nm would be 1e-6 N).
constexpr double kSameN = 1e-9;

Material material(double k, double muS = 0.0, double muD = 0.0) {
    Material m;
    m.stiffness = k;
    m.staticFriction = muS;
    m.dynamicFriction = muD;
    return m;
}

/// A scene, and the candidates an index would give (every item), or the mesh object slots
/// themselves (as a moving mesh is handed over, from the snapshot's moving list).
struct Rig {
    Scene scene;
    std::vector<std::uint32_t> items;
    std::vector<std::uint32_t> slots;

    explicit Rig(std::vector<SceneObject> objects)
        : scene(Aabb{Vec3(-1.0), Vec3(1.0)}, std::move(objects)), items(indexedItems(scene)) {
        for (std::uint32_t i = 0; i < scene.size(); ++i) {
            slots.push_back(i);
        }
    }
    CandidateSet byItems() const {
        CandidateSet c;
        c.add(items);
        return c;
    }
    CandidateSet bySlots() const {
        CandidateSet c;
        c.add(slots);
        return c;
    }
};

/// One renderer following a device path (1 kHz), keeping every output.
std::vector<RenderOutput> follow(const Scene& scene, const CandidateSet& c,
                                 const std::vector<Vec3>& path) {
    GodObjectRenderer r;
    r.reset(path.front());
    std::vector<RenderOutput> outs;
    for (std::size_t i = 1; i < path.size(); ++i) {
        outs.push_back(r.update(scene, c, path[i], (path[i] - path[i - 1]) * 1000.0, 1e-3));
    }
    return outs;
}

/// Straight segments through the points, `steps` ticks each.
std::vector<Vec3> polyline(const std::vector<Vec3>& points, int steps) {
    std::vector<Vec3> path{points.front()};
    for (std::size_t k = 1; k < points.size(); ++k) {
        for (int i = 1; i <= steps; ++i) {
            path.push_back(glm::mix(points[k - 1], points[k], double(i) / steps));
        }
    }
    return path;
}

void checkSame(const std::vector<RenderOutput>& got, const std::vector<RenderOutput>& want,
               double forceTolN = kSameN) {
    REQUIRE(got.size() == want.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
        INFO("tick " << i);
        CHECK(glm::length(got[i].force - want[i].force) <= forceTolN);
        CHECK(glm::length(got[i].proxy - want[i].proxy) <= forceTolN / kMeshK);
        CHECK(got[i].contactCount == want[i].contactCount);
    }
}

Quat tilt() {
    return glm::angleAxis(0.6, glm::normalize(Vec3(1.0, 2.0, -0.5)));
}

} // namespace

TEST_CASE("a flat two-triangle square feels like the box face it replaces, along the same path") {
    // Box: centre c, half size 0.05, its +y face at c + q (0, 0.05, 0). The square: the same
    // face as a mesh (two triangles sharing a diagonal), placed by the same rotation.
    const Quat q = GENERATE(Quat(1, 0, 0, 0), tilt());
    const double muS = GENERATE(0.0, 0.6);
    INFO("rotated " << (q != Quat(1, 0, 0, 0)) << ", mu_s " << muS);
    const Material m = material(kMeshK, muS, muS * 0.7);
    const Vec3 c(0.01, -0.02, 0.03);
    const Rig box({makeBox(1, c, Vec3(0.05), q, m)});
    const Rig mesh({makeMesh(1, c + q * Vec3(0, 0.05, 0), squareMesh(0.05), q, m)});
    const auto at = [&](double x, double y, double z) { return c + q * Vec3(x, 0.05 + y, z); };
    // Touch, press 2 mm, slide across the shared diagonal (x = z) and back, press harder, lift.
    const std::vector<Vec3> path =
        polyline({at(0.01, 0.01, -0.02), at(0.01, -0.002, -0.02), at(-0.02, -0.002, 0.02),
                  at(0.03, -0.003, 0.0), at(0.03, -0.004, 0.01), at(0.0, 0.01, 0.0)},
                 40);
    const auto want = follow(box.scene, box.byItems(), path);
    const auto got = follow(mesh.scene, mesh.byItems(), path);
    checkSame(got, want);
    // The path did press and slide: this is not a comparison of two free motions.
    CHECK(want[79].contactCount == 1);
    CHECK(glm::length(want[79].force) > 1.9);
    for (const RenderOutput& o : got) {
        for (std::uint32_t i = 0; i < o.contactCount; ++i) {
            CHECK(o.contacts[i].id == 1);
            CHECK(isTriangleItem(o.contacts[i].slot));
        }
    }
}

TEST_CASE("sliding across the shared diagonal of two coplanar triangles does not snag") {
    const Rig rig({makeMesh(1, Vec3(0.0), squareMesh(0.05), Quat(1, 0, 0, 0), material(kMeshK))});
    // 1 mm deep, across the diagonal x = z at 5 cm/s, 0.05 mm per tick.
    const std::vector<Vec3> path = polyline(
        {Vec3(-0.02, 0.005, 0.01), Vec3(-0.02, -0.001, 0.01), Vec3(0.02, -0.001, -0.01)}, 900);
    const auto outs = follow(rig.scene, rig.byItems(), path);
    for (std::size_t i = 900; i < outs.size(); ++i) {
        INFO("tick " << i);
        const Vec3& device = path[i + 1];
        // Frictionless: the proxy is the device point lifted onto the skin, every tick.
        CHECK(outs[i].contactCount == 1);
        CHECK(outs[i].force.y == Approx(kMeshK * (0.001 + kSkin)).margin(kSameN));
        CHECK(std::abs(outs[i].force.x) <= kSameN);
        CHECK(std::abs(outs[i].force.z) <= kSameN);
        CHECK(std::abs(outs[i].proxy.x - device.x) <= 1e-12);
        CHECK(std::abs(outs[i].proxy.z - device.z) <= 1e-12);
        CHECK(outs[i].proxy.y == Approx(kSkin).margin(1e-12));
    }
    // Both triangles were under the proxy on the way.
    CHECK(outs[950].contacts[0].slot != outs.back().contacts[0].slot);
}

TEST_CASE("a closed cube mesh holds at its edges and vertices: no pop-through") {
    const Quat q = tilt();
    const Vec3 c(0.02, 0.01, -0.01);
    const Vec3 h(0.03);
    const Material m = material(kMeshK);
    const Rig mesh({makeMesh(1, c, boxMesh(h), q, m)});
    const Rig box({makeBox(1, c, h, q, m)});
    const Obb obb = box.scene.object(0).obb();
    const auto at = [&](double x, double y, double z) { return c + q * Vec3(x, y, z); };
    // Into an edge along its bisector, then a vertex along its diagonal, each far past the
    // centre; slide along the edge and off over the vertex; slide over the top face, off its
    // edge into free space, and into the side below it.
    const std::vector<std::vector<Vec3>> paths{
        polyline({at(0.04, 0.04, 0.0), at(-0.01, -0.01, 0.0)}, 200),
        polyline({at(0.04, 0.04, 0.04), at(-0.005, -0.005, -0.005)}, 200),
        polyline({at(0.04, 0.04, -0.01), at(0.029, 0.029, -0.01), at(0.029, 0.029, 0.04)}, 200),
        polyline({at(0.02, 0.031, 0.01), at(0.02, 0.029, 0.01), at(0.035, 0.029, 0.01),
                  at(0.029, 0.02, 0.01)},
                 200),
    };
    for (std::size_t k = 0; k < paths.size(); ++k) {
        INFO("path " << k);
        const auto got = follow(mesh.scene, mesh.byItems(), paths[k]);
        const auto viaSlot = follow(mesh.scene, mesh.bySlots(), paths[k]);
        for (std::size_t i = 0; i < got.size(); ++i) {
            INFO("tick " << i);
            // Never inside: the proxy rides on the skin, outside the solid.
            CHECK(boxSignedDistance(obb, got[i].proxy) >= 0.5 * kSkin);
            // In contact whenever the device is inside: it never fell through.
            if (boxSignedDistance(obb, paths[k][i + 1]) < 0.0) {
                CHECK(got[i].contactCount > 0);
                CHECK(glm::length(got[i].force) ==
                      Approx(kMeshK * glm::length(got[i].proxy - paths[k][i + 1])));
            }
        }
        // The same as the box, and the same whether the mesh comes as triangles or as a whole
        // (a moving mesh's slot).
        checkSame(got, follow(box.scene, box.byItems(), paths[k]), 1e-6);
        checkSame(viaSlot, got);
    }
}

TEST_CASE("a concave corner holds two and three planes") {
    const Rig rig({makeMesh(1, Vec3(0.0), cornerMesh(0.05), Quat(1, 0, 0, 0), material(kMeshK))});
    SECTION("three: floor and both walls") {
        const Vec3 goal(-0.002, -0.003, -0.001);
        const auto outs =
            follow(rig.scene, rig.byItems(), polyline({Vec3(0.02, 0.02, 0.02), goal}, 100));
        const RenderOutput& o = outs.back();
        CHECK(o.contactCount == 3);
        CHECK(glm::length(o.proxy - Vec3(kSkin)) <= 1e-12);
        CHECK(glm::length(o.force - kMeshK * (Vec3(kSkin) - goal)) <= kSameN);
    }
    SECTION("two: the crease of the floor and a wall, sliding along it") {
        const auto outs = follow(rig.scene, rig.byItems(),
                                 polyline({Vec3(0.02, 0.02, 0.01), Vec3(-0.002, -0.003, 0.01),
                                           Vec3(-0.002, -0.003, 0.04)},
                                          100));
        for (std::size_t i = 100; i < outs.size(); ++i) {
            INFO("tick " << i);
            CHECK(outs[i].contactCount == 2);
            CHECK(outs[i].proxy.x == Approx(kSkin).margin(1e-12));
            CHECK(outs[i].proxy.y == Approx(kSkin).margin(1e-12));
            CHECK(outs[i].force.x == Approx(kMeshK * (kSkin + 0.002)).margin(kSameN));
            CHECK(outs[i].force.y == Approx(kMeshK * (kSkin + 0.003)).margin(kSameN));
        }
    }
}

TEST_CASE("the crease between two separate meshes holds both planes") {
    // A floor square (id 1) and a wall square (id 2) standing on it along x = 0, facing +x.
    const Rig rig(
        {makeMesh(1, Vec3(0.0), squareMesh(0.05), Quat(1, 0, 0, 0), material(kMeshK)),
         makeMesh(2, Vec3(0.0, 0.05, 0.0), squareMesh(0.05),
                  glm::angleAxis(-0.5 * glm::pi<double>(), Vec3(0, 0, 1)), material(kMeshK))});
    const Vec3 goal(-0.002, -0.003, 0.01);
    const auto outs =
        follow(rig.scene, rig.byItems(), polyline({Vec3(0.02, 0.02, 0.01), goal}, 100));
    const RenderOutput& o = outs.back();
    REQUIRE(o.contactCount == 2);
    CHECK(o.contacts[0].id != o.contacts[1].id);
    CHECK(glm::length(o.proxy - Vec3(kSkin, kSkin, 0.01)) <= 1e-12);
    CHECK(glm::length(o.force - kMeshK * (Vec3(kSkin, kSkin, 0.01) - goal)) <= kSameN);
}

TEST_CASE("an open mesh is one-sided: from behind the device passes, from the front it is held") {
    const Rig rig({makeMesh(1, Vec3(0.0), squareMesh(0.05), Quat(1, 0, 0, 0), material(kMeshK))});
    // Up through the square from below, then back down onto it from above.
    const std::vector<Vec3> path =
        polyline({Vec3(0.01, -0.02, 0.01), Vec3(0.01, 0.02, 0.01), Vec3(0.01, -0.002, 0.01)}, 100);
    const auto outs = follow(rig.scene, rig.byItems(), path);
    for (std::size_t i = 0; i < 100; ++i) {
        CHECK(outs[i].force == Vec3(0.0));
        CHECK(outs[i].proxy == path[i + 1]);
    }
    CHECK(outs.back().contactCount == 1);
    CHECK(outs.back().force.y == Approx(kMeshK * (0.002 + kSkin)).margin(kSameN));
    CHECK(outs.back().proxy.y == Approx(kSkin).margin(1e-12));
}

TEST_CASE("a device that starts inside a closed mesh is neither trapped nor shot out") {
    const Rig rig({makeMesh(1, Vec3(0.0), boxMesh(Vec3(0.03)), tilt(), material(kMeshK))});
    const Quat q = tilt();
    // Inside, around, out through the +x face, and back in from outside.
    const std::vector<Vec3> path = polyline(
        {q * Vec3(0.01, 0.0, 0.0), q * Vec3(0.02, 0.005, -0.01), q * Vec3(-0.02, 0.0, 0.02),
         q * Vec3(0.05, 0.005, -0.01), q * Vec3(0.028, 0.005, -0.01)},
        50);
    for (const CandidateSet& c : {rig.byItems(), rig.bySlots()}) {
        const auto outs = follow(rig.scene, c, path);
        for (std::size_t i = 0; i < 150; ++i) {
            CHECK(outs[i].force == Vec3(0.0)); // not pushed out while inside
            CHECK(outs[i].proxy == path[i + 1]);
        }
        // Outside it is felt again: pressed 2 mm into the +x face.
        const RenderOutput& o = outs.back();
        CHECK(o.contactCount == 1);
        CHECK(glm::length(o.force - kMeshK * (0.002 + kSkin) * (q * Vec3(1, 0, 0))) <= kSameN);
    }
}

TEST_CASE("friction on a mesh face matches friction on the equivalent box face") {
    // Stick, then slip, with a rubbery material, over a rotated face.
    const Quat q = tilt();
    const Material m = material(kMeshK, 0.8, 0.5);
    const Rig box({makeBox(1, Vec3(0.0), Vec3(0.05), q, m)});
    const Rig mesh({makeMesh(1, q * Vec3(0, 0.05, 0), squareMesh(0.05), q, m)});
    const auto at = [&](double x, double y, double z) { return q * Vec3(x, 0.05 + y, z); };
    const std::vector<Vec3> path =
        polyline({at(0.0, 0.005, 0.0), at(0.0, -0.002, 0.0), at(0.0005, -0.002, 0.0004),
                  at(0.02, -0.002, 0.015), at(0.02, -0.001, -0.02)},
                 60);
    const auto want = follow(box.scene, box.byItems(), path);
    const auto got = follow(mesh.scene, mesh.byItems(), path);
    checkSame(got, want);
    // Static friction held on the short move (the proxy stayed behind by its 0.64 mm), and
    // the long one slipped.
    const Vec3 up = q * Vec3(0, 1, 0);
    const Vec3 stuck = got[119].proxy - path[120];
    CHECK(glm::length(stuck - glm::dot(stuck, up) * up) > 6e-4);
    CHECK(got[179].sliding);
}

TEST_CASE("a moving mesh carries the proxy like a moving box, from its object slot") {
    const Material m = material(kMeshK, 1.0, 0.8);
    const Rig mesh({makeMesh(1, Vec3(0.0), squareMesh(0.05), Quat(1, 0, 0, 0), m)});
    const Rig box({makeBox(1, Vec3(0, -0.05, 0), Vec3(0.05), Quat(1, 0, 0, 0), m)});
    GodObjectRenderer onMesh;
    GodObjectRenderer onBox;
    const Vec3 device(0.0, -0.001, 0.0);
    onMesh.reset(Vec3(0, 0.005, 0));
    onBox.reset(Vec3(0, 0.005, 0));
    for (int i = 1; i <= 20; ++i) {
        const Vec3 p = glm::mix(Vec3(0, 0.005, 0), device, i / 20.0);
        onMesh.update(mesh.scene, mesh.bySlots(), p, Vec3(NAN), 1e-3);
        onBox.update(box.scene, box.byItems(), p, Vec3(NAN), 1e-3);
    }
    // Both objects move 0.05 mm along x per tick, for 10 ticks, and turn a little about y; the
    // device stays. Static friction (mu_s = 1 at 1 mm depth) holds: the proxy rides along.
    Scene movedMesh = mesh.scene;
    Scene movedBox = box.scene;
    RenderOutput a, b;
    for (int i = 1; i <= 10; ++i) {
        const Quat turn = glm::angleAxis(0.001 * i, Vec3(0, 1, 0));
        movedMesh.setPose(0, Vec3(5e-5 * i, 0, 0), turn);
        movedBox.setPose(0, Vec3(5e-5 * i, 0, 0) + turn * Vec3(0, -0.05, 0), turn);
        a = onMesh.update(movedMesh, mesh.bySlots(), device, Vec3(0.0), 1e-3);
        b = onBox.update(movedBox, box.byItems(), device, Vec3(0.0), 1e-3);
        CHECK(glm::length(a.force - b.force) <= kSameN);
        CHECK(glm::length(a.proxy - b.proxy) <= 1e-12);
    }
    CHECK(a.contactCount == 1);
    CHECK(a.proxy.x == Approx(5e-4).margin(1e-9));
    CHECK(a.force.x == Approx(kMeshK * 5e-4).margin(1e-6));
}

TEST_CASE("a fine mesh under a pressing, sliding tool keeps the near list small") {
    // 0.2 mm triangles (20000 of them); pressed 2 mm deep and slid with friction. The near
    // ball for triangles is the proxy's reach plus 1 µm, so only the few triangles around the
    // contact are tracked: the list never overflows.
    const Rig rig({makeMesh(1, Vec3(0.0), gridMesh(0.01, 100), Quat(1, 0, 0, 0),
                            material(kMeshK, 0.5, 0.3))});
    const std::vector<Vec3> path = polyline(
        {Vec3(0.001, 0.003, 0.001), Vec3(0.001, -0.002, 0.001), Vec3(-0.006, -0.002, 0.004)}, 100);
    for (const CandidateSet& c : {rig.byItems(), rig.bySlots()}) {
        GodObjectRenderer r;
        r.reset(path.front());
        RenderOutput o;
        for (std::size_t i = 1; i < path.size(); ++i) {
            o = r.update(rig.scene, c, path[i], Vec3(NAN), 1e-3);
            CHECK(o.status == RenderStatus::Ok);
        }
        CHECK(r.counters().nearListFull == 0);
        CHECK(o.contactCount >= 1);
        CHECK(o.force.y == Approx(kMeshK * (0.002 + kSkin)).margin(1e-6));
    }
}

TEST_CASE("an overflowing near list falls back to the spans and still holds") {
    // Pressing from far above gives the first tick a reach that covers thousands of 0.2 mm
    // triangles: the list overflows, the tick runs on the raw spans (and the mesh slot's
    // triangles near the ball), and the proxy still stops on the surface.
    const Rig rig(
        {makeMesh(1, Vec3(0.0), gridMesh(0.01, 100), Quat(1, 0, 0, 0), material(kMeshK))});
    for (const CandidateSet& c : {rig.byItems(), rig.bySlots()}) {
        GodObjectRenderer r;
        r.reset(Vec3(0.001, 0.008, 0.0));
        const RenderOutput o = r.update(rig.scene, c, Vec3(0.0012, -0.002, 0.0), Vec3(NAN), 1e-3);
        CHECK(o.status == RenderStatus::NearListFull);
        CHECK(o.contactCount == 1);
        CHECK(o.proxy.y == Approx(kSkin).margin(1e-12));
        CHECK(o.force.y == Approx(kMeshK * (0.002 + kSkin)).margin(kSameN));
    }
}

TEST_CASE("random walks around rotated closed meshes: the proxy never inside, always held") {
    // A torus, an L-shaped prism (a concave edge) and a cube, each rotated, touching nothing;
    // the device wanders at up to 0.5 m/s, drawn toward each mesh's centre in turn.
    const std::uint64_t seed = GENERATE(1, 2);
    hapto::Random rng(seed * 131);
    const Rig rig({makeMesh(1, Vec3(-0.04, 0.0, 0.0), torusMesh(0.02, 0.008, 32, 12),
                            glm::angleAxis(0.5, glm::normalize(Vec3(1, 1, 0))), material(kMeshK)),
                   makeMesh(2, Vec3(0.02, -0.03, 0.0), lPrismMesh(0.02, 0.015), tilt(),
                            material(kMeshK, 0.5, 0.3)),
                   makeMesh(3, Vec3(0.03, 0.06, 0.02), boxMesh(Vec3(0.015, 0.02, 0.01)),
                            glm::angleAxis(1.1, glm::normalize(Vec3(0, 1, 2))), material(kMeshK))});
    for (const SceneObject& o : rig.scene.objects()) {
        REQUIRE(o.mesh->closed());
    }
    const CandidateSet cands = rig.byItems();
    GodObjectRenderer r;
    Vec3 p(0.0, 0.0, 0.08);
    Vec3 v(0.0);
    r.reset(p);
    std::uint64_t insideTicks = 0, unheldTicks = 0, deviceInsideTicks = 0, multiTicks = 0;
    for (int tick = 0; tick < 12000; ++tick) {
        const Vec3 target = rig.scene.object((tick / 400) % 3).center;
        v += Vec3(rng.normal(), rng.normal(), rng.normal()) * 0.05 + (target - p) * 0.5; // m/s
        if (glm::length(v) > 0.5) {
            v = 0.5 * glm::normalize(v); // at most 0.5 mm per tick
        }
        p += v * 1e-3;
        const RenderOutput out = r.update(rig.scene, cands, p, v, 1e-3);
        // Pressed centimetres deep, the reach covers hundreds of triangles: the list may
        // overflow, and the fallback must hold just the same.
        REQUIRE((out.status == RenderStatus::Ok || out.status == RenderStatus::NearListFull));
        bool deviceInside = false;
        for (const SceneObject& o : rig.scene.objects()) {
            insideTicks += o.contains(out.proxy) ? 1 : 0;
            deviceInside = deviceInside || o.contains(p);
        }
        deviceInsideTicks += deviceInside ? 1 : 0;
        unheldTicks += deviceInside && out.contactCount == 0 ? 1 : 0;
        multiTicks += out.contactCount > 1 ? 1 : 0;
    }
    CHECK(insideTicks == 0);
    CHECK(unheldTicks == 0);
    CHECK(deviceInsideTicks > 500); // the walk really pressed into the meshes
    INFO("multi-contact ticks " << multiTicks);
    CHECK(multiTicks > 0); // ... at edges and vertices too
}

TEST_CASE("the near list's copy of a triangle renders exactly as the scene's triangle does") {
    // The renderer copies the plane, corners and edges of a tick's first candidate triangles
    // (GodObjectRenderer::kCachedTriangles) and reads any past them from the scene. Two
    // renderers follow one walk over a fine rotated torus with friction: one is handed the
    // triangles near the device point (its near triangles are copies), the other the same
    // after 40 far triangles of another mesh (rejected, but they take the copied places, so
    // its near triangles are read from the scene). Every output must be the same, bit for bit.
    const Rig rig(
        {makeMesh(1, Vec3(0.0), torusMesh(0.02, 0.008, 128, 48), tilt(),
                  material(kMeshK, 0.5, 0.3)),
         makeMesh(2, Vec3(0.5, 0.0, 0.0), gridMesh(0.01, 10), Quat(1, 0, 0, 0), material(kMeshK))});
    std::vector<std::uint32_t> far;
    for (const std::uint32_t item : rig.items) {
        if (isTriangleItem(item) && rig.scene.objectSlotOf(item) == 1 && far.size() < 40) {
            far.push_back(item);
        }
    }
    REQUIRE(far.size() > GodObjectRenderer::kCachedTriangles);
    hapto::Random rng(7);
    const Vec3 onRing = tilt() * Vec3(0.02, 0.0, 0.0); // the walk is drawn to the tube's core
    GodObjectRenderer copied;
    GodObjectRenderer read;
    Vec3 p(0.0, 0.0, 0.05);
    Vec3 v(0.0);
    copied.reset(p);
    read.reset(p);
    std::uint64_t contactTicks = 0;
    for (int tick = 0; tick < 3000; ++tick) {
        v += Vec3(rng.normal(), rng.normal(), rng.normal()) * 0.05 + (onRing - p) * 0.5;
        if (glm::length(v) > 0.5) {
            v = 0.5 * glm::normalize(v);
        }
        p += v * 1e-3;
        std::vector<std::uint32_t> near;
        for (const std::uint32_t item : rig.items) {
            if (isTriangleItem(item) && rig.scene.objectSlotOf(item) == 0) {
                const std::array<Vec3, 3> c = rig.scene.triangleCorners(item);
                if (glm::length((c[0] + c[1] + c[2]) / 3.0 - p) < 0.006) {
                    near.push_back(item);
                }
            }
        }
        CandidateSet nearOnly;
        nearOnly.add(near);
        CandidateSet farFirst;
        farFirst.add(far);
        farFirst.add(near);
        const RenderOutput a = copied.update(rig.scene, nearOnly, p, v, 1e-3);
        const RenderOutput b = read.update(rig.scene, farFirst, p, v, 1e-3);
        INFO("tick " << tick);
        test::requireSameOutput(a, b);
        REQUIRE(a.iterations == b.iterations);
        contactTicks += a.contactCount > 0;
    }
    CHECK(contactTicks >
          300); // the walk swings through the tube: in contact on 451 of the 3000 ticks
}

TEST_CASE("a renderer put back to its State renders the tick again exactly") {
    // HapticTick solves a tick again from the renderer's State (not a copy of the whole
    // renderer): the second update must give what the first gave.
    const Rig rig({makeMesh(1, Vec3(0.0), torusMesh(0.02, 0.008, 64, 24), tilt(),
                            material(kMeshK, 0.5, 0.3))});
    const CandidateSet c = rig.byItems();
    GodObjectRenderer r;
    // Down onto the tube's top (the torus stands in its local x-y plane), 4 mm in, and along
    // the ring over its facets' edges and vertices.
    std::vector<Vec3> corners{Vec3(0.02, 0.0, 0.03), Vec3(0.02, 0.0, 0.004), Vec3(0.0, 0.02, 0.004),
                              Vec3(-0.02, 0.0, 0.006)};
    for (Vec3& corner : corners) {
        corner = tilt() * corner;
    }
    const std::vector<Vec3> path = polyline(corners, 200);
    r.reset(path.front());
    std::uint64_t contactTicks = 0;
    for (std::size_t i = 1; i < path.size(); ++i) {
        const GodObjectRenderer::State before = r.state();
        const RenderOutput first = r.update(rig.scene, c, path[i], Vec3(NAN), 1e-3);
        const GodObjectRenderer::State after = r.state();
        r.restore(before);
        const RenderOutput again = r.update(rig.scene, c, path[i], Vec3(NAN), 1e-3);
        INFO("tick " << i);
        REQUIRE(again.proxy == first.proxy);
        REQUIRE(again.force == first.force);
        REQUIRE(again.contactCount == first.contactCount);
        REQUIRE(r.state().proxy == after.proxy);
        REQUIRE(r.state().slipping == after.slipping);
        REQUIRE(r.counters().ticks == after.counters.ticks);
        contactTicks += first.contactCount > 0;
    }
    CHECK(contactTicks > 350);
}
