// Model files read by hapto's own readers give the meshes assimp 5.2.5 gave when hapto read
// models with it: every model in the repository (its counts and bounds), and models that take
// each path assimp took silently (a concave quadrilateral cut from its concave corner, a concave
// polygon cut ear by ear, polygons sharing vertices whose triangles' corners assimp rotated,
// extra PLY properties and elements, a vertex no face names, two ASCII STL solids, OBJ weights,
// negative indices, lines and points) corner for corner. The expected figures were printed by
// the assimp path before it was removed (hexadecimal floats: exact).

#include "hapto/scenes/MeshFile.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <array>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

using namespace hapto;

namespace {

struct Expected {
    const char* file;
    const char* text; ///< The model (for the repository's files: unused, "").
    std::size_t triangles, vertices, degenerate, duplicate;
    std::array<double, 3> min, max;
    std::vector<std::array<std::array<double, 3>, 3>> corners; ///< Kept triangles, in order.
};

void checkMesh(const TriangleMesh& mesh, const Expected& e) {
    INFO(e.file);
    CHECK(mesh.triangleCount() == e.triangles);
    CHECK(mesh.vertices().size() == e.vertices);
    CHECK(mesh.droppedDegenerate() == e.degenerate);
    CHECK(mesh.droppedDuplicate() == e.duplicate);
    const Aabb b = mesh.localBounds();
    CHECK(std::array<double, 3>{b.min.x, b.min.y, b.min.z} == e.min);
    CHECK(std::array<double, 3>{b.max.x, b.max.y, b.max.z} == e.max);
    if (e.corners.empty()) {
        return;
    }
    REQUIRE(mesh.triangleCount() == e.corners.size());
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        for (int k = 0; k < 3; ++k) {
            const Vec3 v = mesh.vertices()[mesh.triangles()[t][k]];
            CHECK(std::array<double, 3>{v.x, v.y, v.z} == e.corners[t][k]);
        }
    }
}

std::string contents(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

} // namespace

TEST_CASE("every model in the repository loads to what assimp 5.2.5 made of it") {
    const std::filesystem::path root = HAPTO_SOURCE_DIR;
    // The fuzz seeds' first byte picks the format (FuzzMeshFile.cpp): the model follows it.
    const std::vector<Expected> models{
        {"tests/tools/bad_inputs/scenes/tet.obj", "", 4, 4, 0, 0, {0, 0, 0}, {1, 1, 1}, {}},
        {"tools/fuzz/corpus/mesh_file/cube-quads.obj", "", 12, 8, 0, 0, {0, 0, 0}, {1, 1, 1}, {}},
        {"tools/fuzz/corpus/mesh_file/tet-ascii.ply", "", 4, 4, 0, 0, {0, 0, 0}, {1, 1, 1}, {}},
        {"tools/fuzz/corpus/mesh_file/tet-ascii.stl", "", 4, 4, 0, 0, {0, 0, 0}, {1, 1, 1}, {}},
        {"tools/fuzz/corpus/mesh_file/tet-be.ply", "", 4, 4, 0, 0, {0, 0, 0}, {1, 1, 1}, {}},
        {"tools/fuzz/corpus/mesh_file/tet-binary.stl", "", 4, 4, 0, 0, {0, 0, 0}, {1, 1, 1}, {}},
        {"tools/fuzz/corpus/mesh_file/tet-le.ply", "", 4, 4, 0, 0, {0, 0, 0}, {1, 1, 1}, {}},
        {"tools/fuzz/corpus/mesh_file/tet-negative.obj", "", 4, 4, 0, 0, {0, 0, 0}, {1, 1, 1}, {}},
    };
    for (const Expected& e : models) {
        const std::filesystem::path path = root / e.file;
        std::string bytes = contents(path);
        REQUIRE(!bytes.empty());
        if (std::string(e.file).starts_with("tools/fuzz/")) {
            bytes.erase(0, 1);
        }
        checkMesh(*parseMeshFile(bytes, path, MeshSource{e.file, 1.0}), e);
    }
}

TEST_CASE("polygons, shared corners, extra properties and several solids load as assimp 5.2.5 "
          "loaded them, corner for corner") {
    test::TempDir dir;
    const std::vector<Expected> models{
        {"dart.obj",
         "v 0 0 0\n"
         "v 2 -1 0\n"
         "v 0.5 0 0\n"
         "v 2 1 0\n"
         "f 1 2 3 4\n"
         "f 2 3 4 1\n",
         2,
         4,
         0,
         2,
         {0x0p+0, -0x1p+0, 0x0p+0},
         {0x1p+1, 0x1p+0, 0x0p+0},
         {
             {{{0x1p-1, 0x0p+0, 0x0p+0}, {0x1p+1, 0x1p+0, 0x0p+0}, {0x0p+0, 0x0p+0, 0x0p+0}}},
             {{{0x1p-1, 0x0p+0, 0x0p+0}, {0x0p+0, 0x0p+0, 0x0p+0}, {0x1p+1, -0x1p+0, 0x0p+0}}},
         }},
        {"shared.ply",
         "ply\n"
         "format ascii 1.0\n"
         "comment polygons sharing vertices, a colour, an edge element and a vertex no face names\n"
         "element vertex 10\n"
         "property float x\n"
         "property float y\n"
         "property float z\n"
         "property uchar red\n"
         "element face 5\n"
         "property list uchar int vertex_indices\n"
         "property uchar flags\n"
         "element edge 1\n"
         "property int vertex1\n"
         "property int vertex2\n"
         "end_header\n"
         "0 0 0 1\n"
         "1 0 0.25 2\n"
         "2 0 0 3\n"
         "2 1 0.125 4\n"
         "1 1.5 0 5\n"
         "0 1 0.25 6\n"
         "0 2 0 7\n"
         "2 2 0 8\n"
         "1 2.5 0 9\n"
         "9 9 9 10\n"
         "6 0 1 2 3 4 5 0\n"
         "4 0 1 4 5 1\n"
         "4 5 4 8 6 2\n"
         "3 5 6 0 3\n"
         "4 4 3 7 8 4\n"
         "0 9\n",
         11,
         10,
         0,
         0,
         {0x0p+0, 0x0p+0, 0x0p+0},
         {0x1p+1, 0x1.4p+1, 0x1p-2},
         {
             {{{0x0p+0, 0x1p+0, 0x1p-2}, {0x0p+0, 0x0p+0, 0x0p+0}, {0x1p+0, 0x0p+0, 0x1p-2}}},
             {{{0x1p+1, 0x0p+0, 0x0p+0}, {0x0p+0, 0x1p+0, 0x1p-2}, {0x1p+0, 0x0p+0, 0x1p-2}}},
             {{{0x0p+0, 0x1p+0, 0x1p-2}, {0x1p+1, 0x0p+0, 0x0p+0}, {0x1p+1, 0x1p+0, 0x1p-3}}},
             {{{0x1p+1, 0x1p+0, 0x1p-3}, {0x1p+0, 0x1.8p+0, 0x0p+0}, {0x0p+0, 0x1p+0, 0x1p-2}}},
             {{{0x0p+0, 0x0p+0, 0x0p+0}, {0x1p+0, 0x0p+0, 0x1p-2}, {0x1p+0, 0x1.8p+0, 0x0p+0}}},
             {{{0x0p+0, 0x0p+0, 0x0p+0}, {0x1p+0, 0x1.8p+0, 0x0p+0}, {0x0p+0, 0x1p+0, 0x1p-2}}},
             {{{0x0p+0, 0x1p+0, 0x1p-2}, {0x1p+0, 0x1.8p+0, 0x0p+0}, {0x1p+0, 0x1.4p+1, 0x0p+0}}},
             {{{0x0p+0, 0x1p+0, 0x1p-2}, {0x1p+0, 0x1.4p+1, 0x0p+0}, {0x0p+0, 0x1p+1, 0x0p+0}}},
             {{{0x0p+0, 0x0p+0, 0x0p+0}, {0x0p+0, 0x1p+0, 0x1p-2}, {0x0p+0, 0x1p+1, 0x0p+0}}},
             {{{0x1p+0, 0x1.8p+0, 0x0p+0}, {0x1p+1, 0x1p+0, 0x1p-3}, {0x1p+1, 0x1p+1, 0x0p+0}}},
             {{{0x1p+0, 0x1.8p+0, 0x0p+0}, {0x1p+1, 0x1p+1, 0x0p+0}, {0x1p+0, 0x1.4p+1, 0x0p+0}}},
         }},
        {"star.obj",
         "# a concave star, both ways round\n"
         "v 2.0 0.0 0.5\n"
         "v 0.53125 0.53125 0.5\n"
         "v 0.0 2.0 0.5\n"
         "v -0.53125 0.53125 0.5\n"
         "v -2.0 0.0 0.5\n"
         "v -0.53125 -0.53125 0.5\n"
         "v 0.0 -2.0 0.5\n"
         "v 0.53125 -0.53125 0.5\n"
         "f 1 2 3 4 5 6 7 8\n"
         "o reversed\n"
         "f -1 -2 -3 -4 -5 -6 -7 -8\n",
         6,
         8,
         0,
         6,
         {-0x1p+1, -0x1p+1, 0x1p-1},
         {0x1p+1, 0x1p+1, 0x1p-1},
         {
             {{{0x1.1p-1, -0x1.1p-1, 0x1p-1},
               {0x1p+1, 0x0p+0, 0x1p-1},
               {0x1.1p-1, 0x1.1p-1, 0x1p-1}}},
             {{{0x0p+0, 0x1p+1, 0x1p-1},
               {0x1.1p-1, -0x1.1p-1, 0x1p-1},
               {0x1.1p-1, 0x1.1p-1, 0x1p-1}}},
             {{{0x1.1p-1, -0x1.1p-1, 0x1p-1},
               {0x0p+0, 0x1p+1, 0x1p-1},
               {-0x1.1p-1, 0x1.1p-1, 0x1p-1}}},
             {{{-0x1p+1, 0x0p+0, 0x1p-1},
               {0x1.1p-1, -0x1.1p-1, 0x1p-1},
               {-0x1.1p-1, 0x1.1p-1, 0x1p-1}}},
             {{{0x1.1p-1, -0x1.1p-1, 0x1p-1},
               {-0x1p+1, 0x0p+0, 0x1p-1},
               {-0x1.1p-1, -0x1.1p-1, 0x1p-1}}},
             {{{-0x1.1p-1, -0x1.1p-1, 0x1p-1},
               {0x0p+0, -0x1p+1, 0x1p-1},
               {0x1.1p-1, -0x1.1p-1, 0x1p-1}}},
         }},
        {"two-solids.stl",
         "solid a\n"
         " facet normal 0 0 1\n"
         "  outer loop\n"
         "   vertex 0 0 0\n"
         "   vertex 1 0 0\n"
         "   vertex 0 1 0\n"
         "  endloop\n"
         " endfacet\n"
         " facet normal 0 0 1\n"
         "  outer loop\n"
         "   vertex 1 0 0\n"
         "   vertex 1 1 0\n"
         "   vertex 0 1 0\n"
         "  endloop\n"
         " endfacet\n"
         "endsolid a\n"
         "solid b\n"
         " facet normal 0 0 0\n"
         "  outer loop\n"
         "   vertex 0 0 1\n"
         "   vertex 1 0 1\n"
         "   vertex 0 1 1.5\n"
         "  endloop\n"
         " endfacet\n"
         "endsolid b\n",
         3,
         7,
         0,
         0,
         {0x0p+0, 0x0p+0, 0x0p+0},
         {0x1p+0, 0x1p+0, 0x1.8p+0},
         {
             {{{0x0p+0, 0x0p+0, 0x0p+0}, {0x1p+0, 0x0p+0, 0x0p+0}, {0x0p+0, 0x1p+0, 0x0p+0}}},
             {{{0x1p+0, 0x0p+0, 0x0p+0}, {0x1p+0, 0x1p+0, 0x0p+0}, {0x0p+0, 0x1p+0, 0x0p+0}}},
             {{{0x0p+0, 0x0p+0, 0x1p+0}, {0x1p+0, 0x0p+0, 0x1p+0}, {0x0p+0, 0x1p+0, 0x1.8p+0}}},
         }},
        {"weights.obj",
         "v 0 0 0\n"
         "v 2 0 0 2\n"
         "v 0 4 0 4\n"
         "v 0 0 3 0.5\n"
         "v 5 5 5\n"
         "v 7 7 7\n"
         "f -4 -3 -2\n"
         "f 1 2 4\n"
         "f 1 4 3\n"
         "f 2 3 4\n"
         "l 1 5\n"
         "p 5\n",
         4,
         5,
         0,
         0,
         {0x0p+0, 0x0p+0, 0x0p+0},
         {0x1.4p+2, 0x1.4p+2, 0x1.8p+2},
         {
             {{{0x0p+0, 0x1p+0, 0x0p+0},
               {0x0p+0, 0x0p+0, 0x1.8p+2},
               {0x1.4p+2, 0x1.4p+2, 0x1.4p+2}}},
             {{{0x0p+0, 0x0p+0, 0x0p+0}, {0x1p+0, 0x0p+0, 0x0p+0}, {0x0p+0, 0x0p+0, 0x1.8p+2}}},
             {{{0x0p+0, 0x0p+0, 0x0p+0}, {0x0p+0, 0x0p+0, 0x1.8p+2}, {0x0p+0, 0x1p+0, 0x0p+0}}},
             {{{0x1p+0, 0x0p+0, 0x0p+0}, {0x0p+0, 0x1p+0, 0x0p+0}, {0x0p+0, 0x0p+0, 0x1.8p+2}}},
         }},
    };
    for (const Expected& e : models) {
        test::writeFile(dir / e.file, e.text);
        checkMesh(*loadMeshFile(dir / e.file, MeshSource{e.file, 1.0}), e);
    }
}
