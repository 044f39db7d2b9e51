#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/scenes/MeshGenerators.h"
#include "hapto/scenes/SceneFile.h"

#include "TestMeshes.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>

using namespace hapto;
using hapto::test::signedVolume;

namespace {

Vec3 normalOf(const TriangleMesh& m, std::uint32_t t) {
    const auto c = m.corners(t);
    return glm::cross(c[1] - c[0], c[2] - c[0]);
}

Vec3 centroidOf(const TriangleMesh& m, std::uint32_t t) {
    const auto c = m.corners(t);
    return (c[0] + c[1] + c[2]) / 3.0;
}

std::string plyBytes(const MeshOptions& o) {
    std::ostringstream out;
    writeMeshPly(*generateMesh(o), out);
    return std::move(out).str();
}

constexpr MeshShape kShapes[] = {MeshShape::Sphere, MeshShape::Torus, MeshShape::Terrain};

} // namespace

TEST_CASE("generated meshes have about N triangles: within 1.5x from 100, 1.15x from 1000",
          "[meshgen]") {
    for (const MeshShape shape : kShapes) {
        for (const std::size_t n : {100, 150, 250, 999, 1000, 3001, 12345, 100000}) {
            CAPTURE(meshShapeName(shape), n);
            MeshOptions o;
            o.shape = shape;
            o.triangles = n;
            const auto mesh = generateMesh(o);
            CHECK(mesh->triangleCount() == generatedTriangleCount(o));
            CHECK(mesh->droppedDegenerate() == 0);
            const double ratio = static_cast<double>(mesh->triangleCount()) / n;
            const double factor = n >= 1000 ? 1.15 : 1.5;
            CHECK(ratio <= factor);
            CHECK(ratio >= 1.0 / factor);
        }
    }
}

TEST_CASE("the sphere and the torus are closed and face outward, the terrain is open and faces up",
          "[meshgen]") {
    MeshOptions o;
    o.triangles = 5000;
    o.size = 0.2;

    o.shape = MeshShape::Sphere;
    const auto sphere = generateMesh(o);
    CHECK(sphere->closed());
    const double r = 0.1;
    CHECK(signedVolume(*sphere) > 0.0);
    CHECK(signedVolume(*sphere) == Approx(4.0 / 3.0 * std::numbers::pi * r * r * r).epsilon(0.02));
    for (std::uint32_t t = 0; t < sphere->triangleCount(); ++t) {
        REQUIRE(glm::dot(normalOf(*sphere, t), centroidOf(*sphere, t)) > 0.0);
    }
    for (const Vec3& v : sphere->vertices()) {
        REQUIRE(glm::length(v) == Approx(r).epsilon(1e-6));
    }
    CHECK(sphere->localBounds().max.x - sphere->localBounds().min.x == Approx(0.2).epsilon(0.01));

    o.shape = MeshShape::Torus;
    const auto torus = generateMesh(o);
    CHECK(torus->closed());
    const double major = 0.075, minor = 0.025;
    CHECK(signedVolume(*torus) ==
          Approx(2.0 * std::numbers::pi * std::numbers::pi * major * minor * minor).epsilon(0.02));
    for (std::uint32_t t = 0; t < torus->triangleCount(); ++t) {
        // Outward: away from the nearest point of the tube's core circle.
        const Vec3 c = centroidOf(*torus, t);
        const Vec3 core = glm::normalize(Vec3(c.x, 0.0, c.z)) * major;
        REQUIRE(glm::dot(normalOf(*torus, t), c - core) > 0.0);
    }
    CHECK(torus->localBounds().max.x == Approx(0.1).epsilon(1e-6));

    o.shape = MeshShape::Terrain;
    const auto terrain = generateMesh(o);
    CHECK_FALSE(terrain->closed());
    for (std::uint32_t t = 0; t < terrain->triangleCount(); ++t) {
        REQUIRE(normalOf(*terrain, t).y > 0.0);
    }
    const Aabb& b = terrain->localBounds();
    CHECK(b.min.x == Approx(-0.1));
    CHECK(b.max.z == Approx(0.1));
    CHECK(b.min.y >= -0.02);
    CHECK(b.max.y <= 0.02);
    CHECK(b.max.y - b.min.y > 0.002); // not flat
}

TEST_CASE("generated meshes are byte-identical per seed, the terrain changes with the seed",
          "[meshgen]") {
    for (const MeshShape shape : kShapes) {
        CAPTURE(meshShapeName(shape));
        MeshOptions o;
        o.shape = shape;
        o.triangles = 2000;
        o.seed = 7;
        const std::string first = plyBytes(o);
        CHECK(plyBytes(o) == first);
        o.seed = 8;
        if (shape == MeshShape::Terrain) {
            CHECK(plyBytes(o) != first);
        } else {
            CHECK(plyBytes(o) == first); // only the terrain is random
        }
    }
}

TEST_CASE("the PLY file holds the header, 12 B per vertex and 13 B per triangle", "[meshgen]") {
    MeshOptions o;
    o.shape = MeshShape::Torus;
    o.triangles = 300;
    const auto mesh = generateMesh(o);
    const std::string bytes = plyBytes(o);
    const std::string endHeader = "end_header\n";
    const std::size_t header = bytes.find(endHeader);
    REQUIRE(header != std::string::npos);
    CHECK(bytes.starts_with("ply\nformat binary_little_endian 1.0\n"));
    CHECK(bytes.find("element vertex " + std::to_string(mesh->vertices().size()) + "\n") < header);
    CHECK(bytes.find("element face " + std::to_string(mesh->triangleCount()) + "\n") < header);
    CHECK(bytes.size() ==
          header + endHeader.size() + 12 * mesh->vertices().size() + 13 * mesh->triangleCount());
}

TEST_CASE("a mesh scene holds the mesh as object 0 inside padded bounds", "[meshgen]") {
    MeshOptions o;
    o.shape = MeshShape::Terrain;
    o.triangles = 800;
    const Scene s = makeMeshScene(o);
    REQUIRE(s.size() == 1);
    CHECK(s.object(0).shape == Shape::Mesh);
    CHECK(s.triangleCount() == generatedTriangleCount(o));
    CHECK(s.bounds().contains(s.object(0).aabb().min));
    CHECK(s.bounds().contains(s.object(0).aabb().max));
}

TEST_CASE("bad generator options are refused, naming the option", "[meshgen]") {
    MeshOptions o;
    o.triangles = 99;
    CHECK_THROWS_WITH(generateMesh(o), Catch::Contains("--triangles"));
    o.triangles = kMaxGeneratedTriangles + 1;
    CHECK_THROWS_AS(generateMesh(o), InputError);
    o.triangles = 1000;
    for (const double size : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                              std::numeric_limits<double>::infinity(), 2e6}) {
        o.size = size;
        CHECK_THROWS_WITH(generateMesh(o), Catch::Contains("--size"));
    }
    CHECK(parseMeshShape("torus") == MeshShape::Torus);
    CHECK_FALSE(parseMeshShape("cube"));
}

TEST_CASE("a generated mesh written as PLY beside its scene loads back as the same mesh",
          "[meshgen]") {
    const std::filesystem::path dir =
        std::filesystem::temp_directory_path() /
        ("hapto-meshgen-" + std::to_string(std::hash<std::string>{}(
                                std::to_string(reinterpret_cast<std::uintptr_t>(&dir)))));
    std::filesystem::create_directories(dir);
    for (const MeshShape shape : kShapes) {
        CAPTURE(meshShapeName(shape));
        MeshOptions o;
        o.shape = shape;
        o.triangles = 2000;
        o.seed = 5;
        const std::string name = std::string(meshShapeName(shape));
        const Scene scene = makeMeshScene(o, MeshSource{name + ".ply", 1.0});
        {
            std::ofstream ply(dir / (name + ".ply"), std::ios::binary);
            writeMeshPly(*scene.object(0).mesh, ply);
        }
        writeFileAtomically(dir / (name + ".json"), sceneToJson(scene));
        const Scene loaded = loadSceneFile(dir / (name + ".json"));
        REQUIRE(loaded.size() == 1);
        const TriangleMesh& a = *scene.object(0).mesh;
        const TriangleMesh& b = *loaded.object(0).mesh;
        CHECK(b.triangleCount() == a.triangleCount());
        CHECK(b.vertices().size() == a.vertices().size()); // shared vertices stay shared
        CHECK(b.closed() == a.closed());
        CHECK(b.droppedDegenerate() == 0);
        // Within float rounding (the loader's arithmetic is its own): 1e-8 m on a 0.1 m mesh.
        CHECK(glm::length(b.localBounds().min - a.localBounds().min) < 1e-8);
        CHECK(glm::length(b.localBounds().max - a.localBounds().max) < 1e-8);
        CHECK(signedVolume(b) == Approx(signedVolume(a)).epsilon(1e-6));
        CHECK(sceneToJson(loaded) == sceneToJson(scene));
    }
    std::filesystem::remove_all(dir);
}
