// Scene format version 3: dynamic bodies and the scene's physics read by both JSON loaders (the
// simdjson fast path vouching for them, the checked loader refusing bad values with their JSON
// path, the same message either way), mass properties against their analytic values, convex
// hulls and their invariants, the writer's version and exact round trip, the binary refusal.

#include "hapto/io/InputError.h"
#include "hapto/scenes/BinaryScene.h"
#include "hapto/scenes/ConvexHullOf.h"
#include "hapto/scenes/MassProperties.h"
#include "hapto/scenes/MeshGenerators.h"
#include "hapto/scenes/SceneFile.h"

#include "../../scenes/src/SceneFileChecks.h" // detail::parseSceneFast: does the fast path vouch?

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <string>

using namespace hapto;
using Catch::Matchers::Contains;

namespace {

constexpr double kPi = std::numbers::pi;

std::string v3(const std::string& objects, const std::string& top = "") {
    return R"({"format": "hapto-scene", "version": 3)" + top + R"(, "objects": [)" + objects + "]}";
}

std::string dynamicBox(const std::string& extra) {
    return R"({"id": 1, "shape": "box", "center": [0, 0.01, 0], "half_extents": [0.01, 0.02, 0.03],
              "dynamic": true)" +
           extra + "}";
}

/// The message the loader gives, or "" when it loads.
std::string refusal(bool fast, const std::string& text) {
    try {
        fast ? parseScene(text, "d.json") : parseSceneChecked(text, "d.json");
        return "";
    } catch (const InputError& e) {
        return e.what();
    }
}

/// Both loaders refuse the text with the same message, which contains `expected`.
void checkRefused(const std::string& text, const std::string& expected) {
    INFO(text);
    const std::string checked = refusal(false, text);
    CHECK_THAT(checked, Contains(expected));
    CHECK(refusal(true, text) == checked);
}

/// A closed cube mesh of half size h about `c`, 12 outward triangles.
std::shared_ptr<const TriangleMesh> cubeMesh(double h, Vec3 c = Vec3(0.0), bool open = false) {
    std::vector<Vec3> v;
    for (int i = 0; i < 8; ++i) {
        v.push_back(c + h * Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
    }
    std::vector<TriangleIndices> t = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},  // -z, +z
                                      {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},  // -y, +y
                                      {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}}; // -x, +x
    if (open) {
        t.resize(10); // no +x face
    }
    return TriangleMesh::make(std::move(v), std::move(t), MeshSource{}, "cube");
}

/// Every hull invariant: unit outward normals, every vertex and every input point inside every
/// face plane, each face plane touched by at least 3 vertices, unique edges between distinct
/// vertices, Euler's V - E + F = 2.
void checkHull(const ConvexHull& h, std::span<const Vec3> points) {
    double scale = 0.0;
    for (const Vec3& p : points) {
        scale = std::max(scale, glm::length(p));
    }
    const double tol = 1e-12 * std::max(scale, 1.0);
    // Counted, then checked once: a hull of 10^4 vertices makes 10^8 comparisons.
    std::size_t notUnit = 0, vertexOutside = 0, pointOutside = 0, fewCorners = 0;
    for (const ConvexHull::Face& f : h.faces) {
        notUnit += std::abs(glm::length(f.normal) - 1.0) > 1e-14;
        int onPlane = 0;
        for (const Vec3& v : h.vertices) {
            const double d = glm::dot(f.normal, v) - f.offset;
            vertexOutside += d > tol;
            onPlane += std::abs(d) <= 1e-9 * std::max(scale, 1.0);
        }
        fewCorners += onPlane < 3;
        for (const Vec3& p : points) {
            pointOutside += glm::dot(f.normal, p) - f.offset > 1e-9 * std::max(scale, 1.0);
        }
    }
    CHECK(notUnit == 0);
    CHECK(vertexOutside == 0);
    CHECK(pointOutside == 0);
    CHECK(fewCorners == 0);
    std::set<std::array<std::uint32_t, 2>> edges(h.edges.begin(), h.edges.end());
    CHECK(edges.size() == h.edges.size());
    for (const auto& e : h.edges) {
        CHECK(e[0] != e[1]);
        CHECK(std::max(e[0], e[1]) < h.vertices.size());
    }
    CHECK(static_cast<long>(h.vertices.size()) - static_cast<long>(h.edges.size()) +
              static_cast<long>(h.faces.size()) ==
          2);
}

void checkTensor(const Mat3& got, const Mat3& want, double rel) {
    const double scale = want[0][0] + want[1][1] + want[2][2];
    for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) {
            CHECK(got[c][r] == Approx(want[c][r]).margin(rel * scale));
        }
    }
}

Mat3 diagonal(double a, double b, double c) {
    Mat3 m(0.0);
    m[0][0] = a;
    m[1][1] = b;
    m[2][2] = c;
    return m;
}

} // namespace

TEST_CASE("a version 3 scene reads dynamic bodies and the physics in both loaders") {
    const std::string text =
        v3(R"({"id": 0, "shape": "box", "center": [0, -0.01, 0], "half_extents": [0.1, 0.01, 0.1],
               "restitution": 0.5},)" +
               dynamicBox(R"(, "mass_kg": 0.06, "restitution": 0.25, "velocity": [0, 0, 1],
                              "angular_velocity": [0, 2, 0])") +
               R"(, {"id": 2, "shape": "sphere", "center": [0.05, 0.02, 0], "radius": 0.02,
                     "dynamic": true, "density_kg_per_m3": 1000, "inertia": [1e-5, 2e-5, 2e-5]})",
           R"(, "gravity": [0, -1.62, 0], "dynamics": {"rate_hz": 2000})");
    const Scene checked = parseSceneChecked(text, "d.json");
    const auto fast = detail::parseSceneFast(text, text.size(), "d.json");
    REQUIRE(fast.has_value()); // the fast path vouches for a box-and-sphere version 3 scene
    CHECK(*fast == checked);
    CHECK(parseScene(text, "d.json") == checked);

    CHECK(checked.physics().gravity == Vec3(0, -1.62, 0));
    CHECK(checked.physics().rateHz == 2000.0);
    CHECK(checked.hasDynamicBodies());
    const BodyProperties& floor = checked.object(0).body;
    CHECK_FALSE(floor.dynamic);
    CHECK(floor.restitution == 0.5);
    CHECK(floor.massKg == 0.0);

    const BodyProperties& box = checked.object(1).body;
    CHECK(box.dynamic);
    CHECK(box.massKg == 0.06);
    CHECK(box.restitution == 0.25);
    CHECK(box.velocity == Vec3(0, 0, 1));
    CHECK(box.angularVelocity == Vec3(0, 2, 0));
    CHECK(box.centerOfMassLocal == Vec3(0.0));
    CHECK(box.hull == nullptr);
    // A box of half extents (a, b, c): Ixx = m (b^2 + c^2) / 3, and so on.
    const double a = 0.01, b = 0.02, c = 0.03, m = 0.06;
    checkTensor(box.inertia,
                diagonal(m * (b * b + c * c) / 3, m * (c * c + a * a) / 3, m * (a * a + b * b) / 3),
                1e-14);

    const BodyProperties& sphere = checked.object(2).body;
    CHECK(sphere.massKg == Approx(1000.0 * 4.0 / 3.0 * kPi * 0.02 * 0.02 * 0.02).epsilon(1e-14));
    CHECK(sphere.inertia == diagonal(1e-5, 2e-5, 2e-5)); // given: taken as written
    CHECK(sphere.restitution == 0.0);
}

TEST_CASE("defaults: static objects, default gravity and rate, and a sphere's 2/5 m r^2") {
    const Scene s = parseScene(v3(R"({"id": 0, "shape": "sphere", "center": [0, 0, 0],
                                      "radius": 0.03, "dynamic": true, "mass_kg": 0.2})"),
                               "d.json");
    CHECK(s.physics() == ScenePhysics{});
    CHECK(s.physics().gravity == Vec3(0, -9.81, 0));
    CHECK(s.physics().rateHz == 1000.0);
    const double i = 0.4 * 0.2 * 0.03 * 0.03;
    checkTensor(s.object(0).body.inertia, diagonal(i, i, i), 1e-14);
    CHECK(s.object(0).body.velocity == Vec3(0.0));

    const Scene plain = parseScene(v3(R"({"id": 0, "shape": "sphere", "center": [0, 0, 0],
                                          "radius": 0.03, "dynamic": false})"),
                                   "d.json");
    CHECK_FALSE(plain.hasDynamicBodies());
    CHECK(plain.object(0).body == BodyProperties{});
}

TEST_CASE("a full inertia tensor is read as written, rows and columns alike") {
    const Scene s = parseScene(
        v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [[2, 0.5, 0], [0.5, 2, 0.25], [0, 0.25, 3]])")),
        "d.json");
    const Mat3& i = s.object(0).body.inertia;
    CHECK(i[0][0] == 2.0);
    CHECK(i[1][0] == 0.5);
    CHECK(i[0][1] == 0.5);
    CHECK(i[2][1] == 0.25);
    CHECK(i[1][2] == 0.25);
    CHECK(i[2][2] == 3.0);
    CHECK(s == parseSceneChecked(sceneToJson(s), "again.json"));
}

TEST_CASE("bad version 3 values are refused with their JSON path, the same in both loaders") {
    const std::string o = "d.json: objects[0]";
    checkRefused(v3(dynamicBox("")), o + ": a dynamic body needs \"mass_kg\"");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "density_kg_per_m3": 5)")),
                 o + ": give either \"mass_kg\" or \"density_kg_per_m3\", not both");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 0)")), o + ".mass_kg: the mass (kg) must be > 0");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": -1)")), o + ".mass_kg: the mass (kg) must be > 0");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1e5)")), o + ".mass_kg: the mass (kg) must be <=");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": "1")")), o + ".mass_kg: expected");
    checkRefused(v3(dynamicBox(R"(, "density_kg_per_m3": 0)")),
                 o + ".density_kg_per_m3: the density (kg/m^3) must be > 0");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "restitution": 1.5)")),
                 o + ".restitution: the restitution must be <= 1");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "restitution": -0.1)")),
                 o + ".restitution: the restitution must be >= 0");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "velocity": [0, 1e3, 0])")),
                 o + ".velocity: the speed (m/s) must be <= 100");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "velocity": [0, 1])")), o + ".velocity:");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "angular_velocity": [1e5, 0, 0])")),
                 o + ".angular_velocity: the angular speed (rad/s) must be <=");
    checkRefused(v3(R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1],
                        "dynamic": "yes"})"),
                 o + ".dynamic: expected");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [1, 1])")),
                 o + ".inertia: expected 3 principal moments");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [1, [1, 0, 0], 1])")),
                 o + ".inertia[1]: expected 3 principal moments");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [1, 0, 1])")),
                 o + ".inertia[1]: a moment of inertia (kg m^2) must be > 0");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [1, 1, 3])")),
                 o + ".inertia: the principal moments of inertia 1, 1 and 3 kg m^2 break the "
                     "triangle inequality");
    checkRefused(
        v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [[1, 0.1, 0], [0.2, 1, 0], [0, 0, 1]])")),
        o + ".inertia[0][1]: the inertia tensor must be symmetric");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [[1, 2, 0], [2, 1, 0], [0, 0, 1]])")),
                 o + ".inertia: the inertia tensor must be positive definite");
    checkRefused(
        v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 2.5]])")),
        o + ".inertia: the principal moments of inertia 1, 1 and 2.5 kg m^2 break");
    checkRefused(v3(dynamicBox(R"(, "mass_kg": 1, "inertia": [[1, 0, 0], [0, 0, 0], [0, 0, 1]])")),
                 o + ".inertia[1][1]: a moment of inertia (kg m^2) must be > 0");
    checkRefused(v3(R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1],
                        "mass_kg": 1})"),
                 o + ".mass_kg: only a dynamic body has \"mass_kg\" (add \"dynamic\": true)");
    checkRefused(v3(R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1],
                        "dynamic": false, "velocity": [0, 0, 0]})"),
                 o + ".velocity: only a dynamic body has \"velocity\"");
    checkRefused(v3(R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1],
                        "mass": 1})"),
                 o + ": unknown field 'mass'");
    const std::string box = dynamicBox(R"(, "mass_kg": 1)");
    checkRefused(v3(box, R"(, "gravity": [0, -200, 0])"),
                 "d.json: gravity: |gravity| (m/s^2) must be <= 100");
    checkRefused(v3(box, R"(, "gravity": [0, -9.81])"), "d.json: gravity:");
    checkRefused(v3(box, R"(, "dynamics": {"rate_hz": 50})"),
                 "d.json: dynamics.rate_hz: the dynamics rate (Hz) must be >= 100");
    checkRefused(v3(box, R"(, "dynamics": {"rate_hz": 20000})"),
                 "d.json: dynamics.rate_hz: the dynamics rate (Hz) must be <= 10000");
    checkRefused(v3(box, R"(, "dynamics": {"rate": 1000})"),
                 "d.json: dynamics: unknown field 'rate'");
    checkRefused(v3(box, R"(, "dynamics": 1000)"), "d.json: dynamics:");
}

TEST_CASE("version 1 and 2 files refuse version 3 fields, wherever \"version\" stands") {
    for (const char* version : {"1", "2"}) {
        const std::string v = version;
        INFO("version " << v);
        const std::string body = dynamicBox(R"(, "mass_kg": 1)");
        checkRefused(R"({"format": "hapto-scene", "version": )" + v + R"(, "objects": [)" + body +
                         "]}",
                     "d.json: objects[0].dynamic: \"dynamic\" needs \"version\": 3");
        checkRefused(R"({"format": "hapto-scene", "objects": [{"id": 0, "shape": "sphere",
                         "center": [0,0,0], "radius": 1}, )" +
                         body + R"(], "version": )" + v + "}",
                     "d.json: objects[1].dynamic: \"dynamic\" needs \"version\": 3");
        checkRefused(R"({"format": "hapto-scene", "version": )" + v +
                         R"(, "objects": [{"id": 0, "shape": "sphere", "center": [0,0,0],
                            "radius": 1, "restitution": 0}]})",
                     "d.json: objects[0].restitution: \"restitution\" needs \"version\": 3");
        checkRefused(R"({"format": "hapto-scene", "version": )" + v +
                         R"(, "objects": [], "gravity": [0, -9.81, 0]})",
                     "d.json: gravity: \"gravity\" needs \"version\": 3");
        checkRefused(R"({"format": "hapto-scene", "version": )" + v +
                         R"(, "objects": [], "dynamics": {"rate_hz": 1000}})",
                     "d.json: dynamics: \"dynamics\" needs \"version\": 3");
    }
}

TEST_CASE("the writer writes version 3 only when it must, and reads back exactly") {
    const std::string text =
        v3(dynamicBox(R"(, "density_kg_per_m3": 700.5, "restitution": 0.3,
                         "velocity": [0.1, 0.2, 0.3], "angular_velocity": [1, -2, 3],
                         "rotation": [0.9238795325112867, 0, 0.3826834323650898, 0])") +
               R"(, {"id": 7, "shape": "sphere", "center": [0,0,0], "radius": 0.5,
                     "restitution": 0.125})",
           R"(, "gravity": [0.5, -9, 0.25], "dynamics": {"rate_hz": 500})");
    const Scene s = parseScene(text, "d.json");
    const std::string json = sceneToJson(s);
    CHECK_THAT(json, Contains("\"version\": 3"));
    const Scene again = parseScene(json, "again.json");
    CHECK(again == s);
    CHECK(sceneToJson(again) == json);
    CHECK(sceneFormatVersionOf(s) == 3);

    // Only the physics differs from a version 1 scene: still version 3.
    Scene physicsOnly(Aabb{Vec3(-1.0), Vec3(1.0)}, {makeSphere(0, Vec3(0.0), 0.1)});
    CHECK(sceneFormatVersionOf(physicsOnly) == 1);
    ScenePhysics moon;
    moon.gravity = Vec3(0, -1.62, 0);
    physicsOnly.setPhysics(moon);
    CHECK(sceneFormatVersionOf(physicsOnly) == 3);
    CHECK(parseScene(sceneToJson(physicsOnly), "m.json") == physicsOnly);

    // Nothing of version 3: the bytes of before (version 1, no new keys).
    const Scene old = parseScene(
        R"({"format": "hapto-scene", "version": 1, "objects": [{"id": 0, "shape": "sphere",
            "center": [0,0,0], "radius": 1}]})",
        "o.json");
    CHECK_THAT(sceneToJson(old), Contains("\"version\": 1"));
    CHECK_THAT(sceneToJson(old), !Contains("gravity") && !Contains("dynamic"));
}

TEST_CASE("a dynamic mesh round-trips to the same bytes, its hull and centre recomputed") {
    const std::string text = v3(
        R"({"id": 3, "shape": "mesh", "center": [0, 0.1, 0], "dynamic": true, "mass_kg": 0.3,
            "vertices": [[0,0,0], [0.02,0,0], [0,0.02,0], [0,0,0.02]],
            "triangles": [[0,2,1], [0,1,3], [0,3,2], [1,2,3]]})");
    const Scene s = parseScene(text, "t.json");
    const BodyProperties& b = s.object(0).body;
    REQUIRE(b.hull != nullptr);
    CHECK(b.hull->vertices.size() == 4);
    CHECK(b.hull->faces.size() == 4);
    CHECK(b.hull->edges.size() == 6);
    // A tetrahedron's centroid is the mean of its corners.
    CHECK(b.centerOfMassLocal.x == Approx(0.005).epsilon(1e-12));
    CHECK(b.centerOfMassLocal.y == Approx(0.005).epsilon(1e-12));
    CHECK(b.centerOfMassLocal.z == Approx(0.005).epsilon(1e-12));
    const std::string json = sceneToJson(s);
    const Scene again = parseScene(json, "again.json");
    CHECK(sceneToJson(again) == json);
    CHECK(again.object(0).body.inertia == b.inertia);
    CHECK(again.object(0).body.centerOfMassLocal == b.centerOfMassLocal);
    CHECK(*again.object(0).body.hull == *b.hull);
}

TEST_CASE("a flat dynamic mesh is refused: it has no volume") {
    checkRefused(v3(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "dynamic": true,
                        "mass_kg": 1, "vertices": [[0,0,0], [1,0,0], [0,1,0], [1,1,0]],
                        "triangles": [[0,1,2], [1,3,2]]})"),
                 "d.json: objects[0]: a dynamic mesh: the points span no volume");
}

TEST_CASE("binary scenes refuse a scene of version 3 with a clear message") {
    const Scene s = parseScene(v3(dynamicBox(R"(, "mass_kg": 1)")), "d.json");
    try {
        sceneToBinary(s);
        FAIL("a dynamic scene was written as binary");
    } catch (const InputError& e) {
        CHECK_THAT(std::string(e.what()), Contains("write it as JSON"));
    }
    // A scene without version 3 still converts.
    const Scene plain(Aabb{Vec3(-1.0), Vec3(1.0)}, {makeSphere(0, Vec3(0.0), 0.1)});
    CHECK(parseBinaryScene(sceneToBinary(plain), "p.hsb") == plain);
}

TEST_CASE("mass properties of a box and a sphere are the analytic ones") {
    const SolidProperties box = boxSolid(Vec3(0.5, 1.0, 1.5));
    CHECK(box.volumeM3 == Approx(6.0).epsilon(1e-15));
    checkTensor(box.inertiaPerDensity,
                diagonal(6.0 * (1.0 + 2.25) / 3, 6.0 * (2.25 + 0.25) / 3, 6.0 * (0.25 + 1.0) / 3),
                1e-15);
    const SolidProperties sphere = sphereSolid(2.0);
    CHECK(sphere.volumeM3 == Approx(32.0 / 3.0 * kPi).epsilon(1e-15));
    const double i = 0.4 * sphere.volumeM3 * 4.0;
    checkTensor(sphere.inertiaPerDensity, diagonal(i, i, i), 1e-15);
}

TEST_CASE("a closed cube mesh has the box's mass properties, wherever it lies, either winding") {
    const Vec3 offset(3.0, -2.0, 1000.0);
    const auto mesh = cubeMesh(0.25, offset);
    REQUIRE(mesh->closed());
    const auto solid = surfaceSolid(mesh->vertices(), mesh->triangles());
    REQUIRE(solid.has_value());
    const SolidProperties box = boxSolid(Vec3(0.25));
    CHECK(solid->volumeM3 == Approx(box.volumeM3).epsilon(1e-12));
    CHECK(glm::length(solid->centroid - offset) < 1e-12);
    checkTensor(solid->inertiaPerDensity, box.inertiaPerDensity, 1e-12);

    std::vector<TriangleIndices> inward(mesh->triangles().begin(), mesh->triangles().end());
    for (auto& t : inward) {
        std::swap(t[1], t[2]);
    }
    const auto flipped = surfaceSolid(mesh->vertices(), inward);
    REQUIRE(flipped.has_value());
    CHECK(flipped->volumeM3 == Approx(box.volumeM3).epsilon(1e-12));
    checkTensor(flipped->inertiaPerDensity, box.inertiaPerDensity, 1e-12);
}

TEST_CASE("a closed geodesic sphere mesh converges to the sphere's mass properties") {
    MeshOptions options;
    options.triangles = 20000;
    options.size = 0.1;
    const auto mesh = generateMesh(options);
    REQUIRE(mesh->closed());
    const SceneObject o = makeMesh(0, Vec3(0.0), mesh);
    const ObjectSolid s = solidOf(o);
    CHECK_FALSE(s.fromHull);
    REQUIRE(s.hull != nullptr);
    const SolidProperties exact = sphereSolid(0.05);
    // An inscribed polyhedron of 20,000 triangles: within 0.1 % of the ball's volume, below it.
    CHECK(s.solid.volumeM3 < exact.volumeM3);
    CHECK(s.solid.volumeM3 == Approx(exact.volumeM3).epsilon(1e-3));
    CHECK(glm::length(s.solid.centroid) < 1e-9);
    checkTensor(s.solid.inertiaPerDensity, exact.inertiaPerDensity, 2e-3);
    // Every vertex of a sphere mesh is on its hull; the hull bounds the same volume.
    CHECK(s.hull->vertices.size() == mesh->vertices().size());
    checkHull(*s.hull, mesh->vertices());
}

TEST_CASE("an open mesh takes its mass from its convex hull") {
    const auto open = cubeMesh(0.01, Vec3(0.0, 0.02, 0.0), true);
    REQUIRE_FALSE(open->closed());
    SceneObject o = makeMesh(0, Vec3(0.0), open);
    const ObjectSolid s = solidOf(o);
    CHECK(s.fromHull);
    const SolidProperties box = boxSolid(Vec3(0.01));
    CHECK(s.solid.volumeM3 == Approx(box.volumeM3).epsilon(1e-12));
    CHECK(glm::length(s.solid.centroid - Vec3(0.0, 0.02, 0.0)) < 1e-15);
    checkTensor(s.solid.inertiaPerDensity, box.inertiaPerDensity, 1e-12);

    fillMassProperties(o, std::nullopt, 2000.0, std::nullopt);
    CHECK(o.body.massKg == Approx(2000.0 * box.volumeM3).epsilon(1e-12));
    CHECK(o.body.centerOfMassLocal == s.solid.centroid);
    checkTensor(o.body.inertia, box.inertiaPerDensity * 2000.0, 1e-12);
    REQUIRE(o.body.hull != nullptr);
    CHECK(o.body.hull->faces.size() == 6);

    // The open terrain (a heightfield) still has a hull with volume.
    MeshOptions terrain;
    terrain.shape = MeshShape::Terrain;
    terrain.triangles = 2000;
    const auto t = generateMesh(terrain);
    const ObjectSolid ts = solidOf(makeMesh(0, Vec3(0.0), t));
    CHECK(ts.fromHull);
    CHECK(ts.solid.volumeM3 > 0.0);
    checkHull(*ts.hull, t->vertices());
}

TEST_CASE("the convex hull of a cube merges coplanar facets: 8 vertices, 6 faces, 12 edges") {
    std::vector<Vec3> points;
    for (int i = 0; i < 27; ++i) { // corners, edge midpoints, face centres and the centre
        points.emplace_back(i % 3 - 1.0, (i / 3) % 3 - 1.0, i / 9 - 1.0);
    }
    const ConvexHullSurface h = convexHullOf(points);
    CHECK(h.hull.vertices.size() == 8);
    CHECK(h.hull.faces.size() == 6);
    CHECK(h.hull.edges.size() == 12);
    for (const ConvexHull::Face& f : h.hull.faces) {
        CHECK(f.offset == Approx(1.0).epsilon(1e-15));
        CHECK(std::abs(std::abs(f.normal.x) + std::abs(f.normal.y) + std::abs(f.normal.z) - 1.0) <
              1e-15);
    }
    checkHull(h.hull, points);
    // Its surface triangles are outward: they bound the cube's volume, positive.
    const auto solid = surfaceSolid(h.hull.vertices, h.triangles);
    REQUIRE(solid.has_value());
    CHECK(solid->volumeM3 == Approx(8.0).epsilon(1e-14));
}

TEST_CASE("convex hulls of random point clouds keep every invariant") {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> normal;
    for (int trial = 0; trial < 20; ++trial) {
        std::vector<Vec3> points(4 + trial * 37);
        for (Vec3& p : points) {
            p = Vec3(normal(rng), normal(rng), normal(rng)) * (0.01 + trial);
        }
        const ConvexHullSurface h = convexHullOf(points);
        checkHull(h.hull, points);
        // Each surface triangle lies in its hull: outward, so the volume is positive.
        const auto solid = surfaceSolid(h.hull.vertices, h.triangles);
        REQUIRE(solid.has_value());
    }
}

TEST_CASE("a convex hull of points that span no volume is refused") {
    const std::vector<Vec3> flat = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.5, 0}};
    CHECK_THROWS_AS(convexHullOf(flat), std::invalid_argument);
    const std::vector<Vec3> three = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    CHECK_THROWS_AS(convexHullOf(three), std::invalid_argument);
    const std::vector<Vec3> nan = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, std::nan("")}};
    CHECK_THROWS_AS(convexHullOf(nan), std::invalid_argument);
}

TEST_CASE("the example scene: a dynamic box resting on a static floor") {
    const Scene s = loadSceneFile(std::filesystem::path(HAPTO_SOURCE_DIR) / "scenes" / "examples" /
                                  "dynamic_box_on_floor.json");
    REQUIRE(s.size() == 2);
    CHECK_FALSE(s.object(0).body.dynamic);
    const SceneObject& box = s.object(1);
    CHECK(box.body.dynamic);
    CHECK(box.body.massKg > 0.0);
    // It rests on the floor: its bottom face on the floor's top face.
    const double floorTop = s.object(0).aabb().max.y;
    CHECK(box.aabb().min.y == Approx(floorTop).margin(1e-12));
    CHECK(s.physics() == ScenePhysics{});
}

TEST_CASE("the user guide shows the example scene file") {
    const auto squash = [](std::string t) {
        t.erase(std::remove_if(t.begin(), t.end(), ::isspace), t.end());
        return t;
    };
    const std::string guide =
        test::guideJsonBlock("scenes.md", "### Dynamic bodies (version 3)", 0);
    const std::string file = test::readFile(std::filesystem::path(HAPTO_SOURCE_DIR) / "scenes" /
                                            "examples" / "dynamic_box_on_floor.json");
    CHECK(squash(guide) == squash(file));
}

TEST_CASE("an older file is refused for a version 3 field before its value is looked at") {
    checkRefused(R"({"format": "hapto-scene", "version": 2, "objects": [{"id": 0, "shape": "box",
                     "center": [0,0,0], "half_extents": [1,1,1], "mass_kg": "heavy"}]})",
                 "d.json: objects[0].mass_kg: \"mass_kg\" needs \"version\": 3");
}
