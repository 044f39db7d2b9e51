// Scene format version 2: mesh objects, inline or from model files, placed by centre, rotation
// and scale; version 1 files and outputs unchanged; save and load round trips; bad meshes
// refused with the scene file, the JSON path and, for model files, the model's place.

#include "hapto/io/InputError.h"
#include "hapto/scenes/SceneFile.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

using namespace hapto;

namespace {

// The unit tetrahedron, outward faces, inline.
const char* kTetFields = R"("vertices": [[0,0,0], [1,0,0], [0,1,0], [0,0,1]],
   "triangles": [[0,2,1], [0,1,3], [0,3,2], [1,2,3]])";

const char* kTetObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

std::string scene2(const std::string& objects) {
    return R"({"format": "hapto-scene", "version": 2, "objects": [)" + objects + "]}";
}

std::string meshSceneErrorOf(const std::string& text, const std::filesystem::path& base = {}) {
    try {
        parseScene(text, "bad.json", base);
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

/// The mesh's corners placed in the world (center + rotation * local).
Vec3 worldVertex(const SceneObject& o, std::size_t i) {
    return o.center + o.rotation * o.mesh->vertices()[i];
}

bool near(const Vec3& a, const Vec3& b) {
    return glm::length(a - b) <= 1e-12;
}

} // namespace

TEST_CASE("a scene without meshes is still written as version 1, byte for byte as before") {
    const Scene s(Aabb{Vec3(-1), Vec3(1)},
                  {makeBox(0, Vec3(0), Vec3(0.5), Quat(1, 0, 0, 0), Material{800, 0.3, 0.2}),
                   makeSphere(7, Vec3(0.25, 0, 0), 0.125)});
    // The exact text version 1 builds wrote for this scene.
    CHECK(sceneToJson(s) ==
          "{\"format\": \"hapto-scene\", \"version\": 1,\n"
          " \"bounds\": {\"min\": [-1, -1, -1], \"max\": [1, 1, 1]},\n"
          " \"objects\": [\n"
          "  {\"id\": 0, \"shape\": \"box\", \"center\": [0, 0, 0], \"half_extents\": [0.5, 0.5, "
          "0.5], \"rotation\": [1, 0, 0, 0], \"stiffness\": 800, \"friction\": [0.3, 0.2]},\n"
          "  {\"id\": 7, \"shape\": \"sphere\", \"center\": [0.25, 0, 0], \"radius\": 0.125, "
          "\"stiffness\": 800, \"friction\": [0, 0]}]}\n");
    // And a version 2 file of boxes only loads to the same scene.
    const std::string v2 = R"({"format": "hapto-scene", "version": 2, "bounds": {"min": [-1,-1,-1],
        "max": [1,1,1]}, "objects": [{"id": 0, "shape": "box", "center": [0,0,0],
        "half_extents": [0.5,0.5,0.5], "stiffness": 800, "friction": [0.3, 0.2]},
        {"id": 7, "shape": "sphere", "center": [0.25,0,0], "radius": 0.125}]})";
    CHECK(parseScene(v2, "v2.json") == s);
}

TEST_CASE("an inline mesh is placed by its scale, rotation and centre") {
    const std::string text = scene2(R"({"id": 3, "shape": "mesh", "center": [0.1, 0.2, 0.3],
        "rotation": [0.7071067811865476, 0, 0, 0.7071067811865476], "scale": 0.02,
        "stiffness": 1500, "friction": [0.4, 0.1], )" +
                                    std::string(kTetFields) + "}");
    const Scene s = parseScene(text, "inline.json");
    REQUIRE(s.size() == 1);
    const SceneObject& o = s.object(0);
    REQUIRE(o.shape == Shape::Mesh);
    REQUIRE(o.mesh);
    CHECK(o.id == 3);
    CHECK(o.mesh->triangleCount() == 4);
    CHECK(s.triangleCount() == 4);
    CHECK(o.mesh->closed());
    CHECK(o.mesh->source().file.empty());
    CHECK(o.mesh->vertices()[1] == Vec3(0.02, 0, 0)); // scale applied, local frame
    // A quarter turn about z takes local x to world y.
    CHECK(near(worldVertex(o, 1), Vec3(0.1, 0.22, 0.3)));
    CHECK(near(worldVertex(o, 2), Vec3(0.08, 0.2, 0.3)));
    CHECK(near(worldVertex(o, 3), Vec3(0.1, 0.2, 0.32)));
    CHECK(o.material == Material{1500, 0.4, 0.1});
    CHECK(o.halfExtents == Vec3(0.01));
    // Default bounds hold the placed mesh.
    for (std::size_t i = 0; i < 4; ++i) {
        CHECK(s.bounds().contains(worldVertex(o, i)));
    }
}

TEST_CASE("inline arrays stream in any field order, and each object gets its own") {
    // Triangles before vertices, scale last; then a second mesh and a box: nothing of the
    // first mesh's arrays may leak into the next object.
    const Scene s = parseScene(
        scene2(R"({"id": 0, "shape": "mesh", "triangles": [[0,2,1], [0,1,3], [0,3,2], [1,2,3]],
                   "vertices": [[0,0,0], [1,0,0], [0,1,0], [0,0,1]], "center": [0,0,0],
                   "scale": 3},
                  {"id": 1, "shape": "mesh", "center": [5,0,0],
                   "vertices": [[0,0,0], [1,0,0], [0,1,0]], "triangles": [[0,1,2]]},
                  {"id": 2, "shape": "box", "center": [0,5,0], "half_extents": [1,1,1]})"),
        "order.json");
    REQUIRE(s.size() == 3);
    CHECK(s.object(0).mesh->triangleCount() == 4);
    CHECK(s.object(0).mesh->vertices()[3] == Vec3(0, 0, 3));
    CHECK(s.object(1).mesh->triangleCount() == 1);
    CHECK(s.object(1).mesh->vertices().size() == 3);
    CHECK_FALSE(s.object(1).mesh->closed());
    CHECK(s.triangleCount() == 5);
    // An index beyond 32 bits is named with its own value.
    CHECK_THAT(meshSceneErrorOf(scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
                   "triangles": [[0,1,2],[0,99999999999,1]], "vertices": [[0,0,0],[1,0,0],[0,1,0]]})")),
               Catch::Contains("objects[0].triangles[1][1]: vertex index 99999999999 is out of "
                               "range (the mesh has 3 vertices)"));
}

TEST_CASE("a mesh from a model file is read relative to the scene file, once per file") {
    test::TempDir dir;
    std::filesystem::create_directories(dir / "scenes/models");
    test::writeFile(dir / "scenes/models/tet.obj", kTetObj);
    test::writeFile(dir / "scenes/s.json",
                    scene2(R"({"id": 0, "shape": "mesh", "center": [1, 0, 0], "scale": 2,
                                "file": "models/tet.obj"},
                               {"id": 1, "shape": "mesh", "center": [-1, 0, 0], "scale": 2,
                                "file": "models/tet.obj"},
                               {"id": 2, "shape": "mesh", "center": [0, 3, 0],
                                "file": "models/tet.obj"})"));
    const Scene s = loadSceneFile(dir / "scenes/s.json");
    REQUIRE(s.size() == 3);
    CHECK(s.triangleCount() == 12);
    CHECK(s.object(0).mesh == s.object(1).mesh); // one file at one scale: read once, shared
    CHECK(s.object(0).mesh != s.object(2).mesh);
    CHECK(s.object(0).mesh->source().file == "models/tet.obj");
    CHECK(s.object(0).mesh->source().scale == 2.0);
    CHECK(s.object(2).mesh->source().scale == 1.0);
    CHECK(s.object(0).mesh->localBounds().max == Vec3(2));
    CHECK(s.object(2).mesh->localBounds().max == Vec3(1));
    CHECK(s.object(1).obb().center == Vec3(0, 1, 1)); // (-1,0,0) + the local bounds' centre
}

TEST_CASE("a mesh scene round-trips through save and load") {
    test::TempDir dir;
    test::writeFile(dir / "tet.obj", kTetObj);
    test::writeFile(dir / "in.json",
                    scene2(R"({"id": 5, "shape": "mesh", "center": [0, 0, 0.5], "scale": 0.1,
                                "rotation": [0, 1, 0, 0], "file": "tet.obj"},
                               {"id": 6, "shape": "box", "center": [0, 0, 0],
                                "half_extents": [0.1, 0.1, 0.1]},
                               {"id": 9, "shape": "mesh", "center": [0.3, 0, 0], "scale": 0.5,
                                )" +
                           std::string(kTetFields) + "}"));
    const Scene original = loadSceneFile(dir / "in.json");
    saveSceneFile(original, dir / "out.json");
    const std::string written = test::readFile(dir / "out.json");
    CHECK(written.find("\"version\": 2") != std::string::npos);
    CHECK(written.find("\"scale\": 0.1, \"file\": \"tet.obj\"") != std::string::npos);
    const Scene loaded = loadSceneFile(dir / "out.json");
    REQUIRE(loaded.size() == original.size());
    CHECK(loaded.bounds().min == original.bounds().min);
    CHECK(loaded.bounds().max == original.bounds().max);
    for (std::uint32_t i = 0; i < original.size(); ++i) {
        const SceneObject& a = original.object(i);
        const SceneObject& b = loaded.object(i);
        INFO("object " << a.id);
        CHECK(a.id == b.id);
        CHECK(a.shape == b.shape);
        CHECK(a.center == b.center);
        CHECK(a.rotation == b.rotation);
        CHECK(a.material == b.material);
        CHECK(a.halfExtents == b.halfExtents);
        if (a.shape == Shape::Mesh) {
            REQUIRE(b.mesh);
            CHECK(std::equal(a.mesh->vertices().begin(), a.mesh->vertices().end(),
                             b.mesh->vertices().begin(), b.mesh->vertices().end()));
            CHECK(std::equal(a.mesh->triangles().begin(), a.mesh->triangles().end(),
                             b.mesh->triangles().begin(), b.mesh->triangles().end()));
            CHECK(a.mesh->source().file == b.mesh->source().file);
        }
    }
    CHECK(sceneToJson(loaded) == written); // and the same bytes again
}

TEST_CASE("bad mesh objects are refused with the file, the JSON path and the place") {
    test::TempDir dir;
    test::writeFile(dir / "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    test::writeFile(dir / "tet.obj", kTetObj);
    const std::string tet = kTetFields;
    struct Case {
        const char* name;
        std::string text;
        std::string expected;
    };
    const std::vector<Case> cases{
        {"a mesh in version 1",
         R"({"format": "hapto-scene", "version": 1, "objects": [{"id": 0, "shape": "mesh",
             "center": [0,0,0], )" +
             tet + "}]}",
         R"(bad.json: objects[0].shape: "mesh" needs "version": 2)"},
        {"a mesh in version 1, the version given last",
         R"({"format": "hapto-scene", "objects": [{"id": 0, "shape": "mesh",
             "center": [0,0,0], )" +
             tet + R"(}], "version": 1})",
         R"(bad.json: objects[0].shape: "mesh" needs "version": 2)"},
        {"version 4", R"({"format": "hapto-scene", "version": 4, "objects": []})",
         "bad.json: version: this build reads versions 1 to 3, got 4"},
        {"index out of range", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
             "vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1,2],[0,1,7]]})"),
         "bad.json: objects[0].triangles[1][2]: vertex index 7 is out of range (the mesh has 3 "
         "vertices)"},
        {"negative index", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
             "vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,-1,2]]})"),
         "bad.json: objects[0].triangles[0][1]: vertex index -1 is out of range"},
        {"fractional index", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
             "vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1.5,2]]})"),
         "bad.json: objects[0].triangles[0][1]: expected a vertex index (a whole number), got "
         "1.5"},
        {"a two-index triangle", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
             "vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1]]})"),
         "bad.json: objects[0].triangles[0]: expected [i, j, k], three vertex indices"},
        {"a bad vertex", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
             "vertices": [[0,0,0],[1,0],[0,1,0]], "triangles": [[0,1,2]]})"),
         "bad.json: objects[0].vertices[1]: expected an array of 3 numbers"},
        {"no triangles", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
             "vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": []})"),
         "bad.json: objects[0]: no triangles"},
        {"all degenerate", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
             "vertices": [[0,0,0],[1,0,0],[2,0,0]], "triangles": [[0,1,2]]})"),
         "bad.json: objects[0]: no triangles left (all 1 were degenerate)"},
        {"a scale that overflows",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "scale": 1e300,
             "vertices": [[0,0,0],[1e10,0,0],[0,1,0]], "triangles": [[0,1,2]]})"),
         "bad.json: objects[0].vertices[1]: the vertex times the scale 1e+300 is not finite"},
        // Found by attacking it: scales and vertices whose triangles' areas over- or underflow
        // were refused as "no triangles left (all 4 were degenerate)".
        {"a scale that takes a vertex too far",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "scale": 1e300, )" + tet + "}"),
         "bad.json: objects[0].vertices[1]: the vertex times the scale 1e+300 lies 1e+300 m out, "
         "beyond the 1e+09 m a mesh vertex may lie from its origin"},
        {"vertices at 1e308", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
             "vertices": [[1e308,0,0],[-1e308,0,0],[0,1,0]], "triangles": [[0,1,2]]})"),
         "bad.json: objects[0].vertices[0]: the vertex lies 1e+308 m out, beyond the 1e+09 m"},
        {"a scale that shrinks the mesh to nothing",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "scale": 1e-320, )" + tet + "}"),
         "bad.json: objects[0]: the mesh is "},
        {"a scale that shrinks a model file to nothing",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "scale": 1e-320,
             "file": "tet.obj"})"),
         "bad.json: objects[0].file: " + (dir / "tet.obj").string() + ": the mesh is "},
        // A NUL cut the path (and the message) short: "tet.obj\u0000.stl" was read as STL.
        {"a NUL in the file's name",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "file": "tet.obj\u0000.stl"})"),
         "bad.json: objects[0].file: a NUL character (\\u0000) in the model file's path, at "
         "character 7"},
        {"scale 0",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "scale": 0, )" + tet + "}"),
         "bad.json: objects[0].scale: the scale must be > 0"},
        {"both file and vertices",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "file": "a.obj", )" + tet + "}"),
         "bad.json: objects[0]: give either \"file\" or \"vertices\" and \"triangles\", not "
         "both"},
        {"neither", scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0]})"),
         "bad.json: objects[0]: a mesh needs \"file\""},
        {"vertices without triangles",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "vertices": [[0,0,0]]})"),
         "bad.json: objects[0]: missing required field 'triangles'"},
        {"a box field on a mesh",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "radius": 1, )" + tet + "}"),
         "radius"},
        {"a bad model file",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "file": "bad.obj"})"),
         "bad.json: objects[0].file: " + (dir / "bad.obj").string() +
             ":4: vertex index 4 is out of range (the file has 3 vertices)"},
        {"a missing model file",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "file": "missing.stl"})"),
         "bad.json: objects[0].file: " + (dir / "missing.stl").string() +
             ": cannot open the model file"},
        {"an unknown model format",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "file": "bad.json"})"),
         "unknown model format '.json'"},
        {"a model file that is a folder",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "file": "."})"),
         "is a directory, not a regular file"},
        {"a file that is not a string",
         scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0], "file": 3})"),
         "bad.json: objects[0].file: expected a string"},
    };
    test::writeFile(dir / "bad.json", "{}");
    for (const Case& c : cases) {
        INFO(c.name);
        CHECK_THAT(meshSceneErrorOf(c.text, dir.path()), Catch::Contains(c.expected));
    }
}

TEST_CASE("duplicate triangles are dropped and counted, however their corners are ordered") {
    // 250,000 copies of one triangle loaded as 250,000 triangles, and a run over them took
    // 811 MB and faulted both hands. Copies by the same indices, turned, reversed, or through
    // other vertices at the same positions are one triangle.
    std::string triangles = "[0,1,2]";
    for (int i = 1; i < 250000; ++i) {
        triangles += ",[0,1,2]";
    }
    const Scene many = parseScene(scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
        "vertices": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [)" +
                                         triangles + "]}"),
                                  "many.json");
    CHECK(many.object(0).mesh->triangleCount() == 1);
    CHECK(many.object(0).mesh->droppedDuplicate() == 249999);
    const Scene turned = parseScene(scene2(R"({"id": 0, "shape": "mesh", "center": [0,0,0],
        "vertices": [[0,0,0],[1,0,0],[0,1,0],[0,0,1],[0,-0.0,0],[1,0,0]],
        "triangles": [[0,2,1],[0,1,3],[0,3,2],[1,2,3],[2,1,0],[1,0,2],[4,5,2],[0,1,2]]})"),
                                    "turned.json");
    const TriangleMesh& mesh = *turned.object(0).mesh;
    CHECK(mesh.triangleCount() == 4);
    CHECK(mesh.droppedDuplicate() == 4);
    CHECK(mesh.droppedDegenerate() == 0);
    CHECK(mesh.closed());
    // The first of each is kept, in order.
    CHECK(mesh.triangles()[0] == TriangleIndices{0, 2, 1});
    CHECK(mesh.triangles()[3] == TriangleIndices{1, 2, 3});
}

TEST_CASE("the user guide's inline mesh loads, and the guide shows it as tested") {
    const std::string object =
        R"({"id": 1, "shape": "mesh", "center": [0.05, 0, 0], "rotation": [1, 0, 0, 0], "scale": 0.01,
   "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
   "triangles": [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]})";
    const Scene s = parseScene(scene2(object), "readme.json");
    REQUIRE(s.size() == 1);
    CHECK(s.object(0).mesh->triangleCount() == 4);
    CHECK(s.object(0).mesh->closed());
    const auto squash = [](std::string t) {
        t.erase(std::remove_if(t.begin(), t.end(), ::isspace), t.end());
        return t;
    };
    const std::string readme =
        test::readFile(std::string(HAPTO_SOURCE_DIR) + "/docs/guide/scenes.md");
    CHECK(squash(readme).find(squash(object)) != std::string::npos);
}
