// Model files (MeshFile.h): a cube and a tetrahedron in every format hapto reads, checked for
// their triangles, shared vertices, positions after scale, orientation and closed-ness; and
// every kind of bad model refused with the file and the place.

#include "hapto/io/InputError.h"
#include "hapto/scenes/MeshFile.h"

#include "TestMeshes.h"
#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <sys/resource.h>
#include <sys/stat.h>
#include <vector>

using namespace hapto;
using hapto::test::signedVolume;

namespace {

using Corners = std::vector<std::array<double, 3>>;
using Faces = std::vector<std::vector<int>>; // 0-based, counter-clockwise seen from outside

// The unit tetrahedron and the unit cube, outward faces.
const Corners kTet{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
const Faces kTetFaces{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
const Corners kCube{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                    {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const Faces kCubeQuads{{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                       {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

/// OBJ text: every face in its own group with its own normal (so assimp keeps the corners of
/// different faces apart, and the loader must merge them).
std::string objText(const Corners& v, const Faces& f) {
    std::string s = "# a test model\n";
    for (const auto& p : v) {
        s += "v " + num(p[0]) + " " + num(p[1]) + " " + num(p[2]) + "\n";
    }
    for (std::size_t i = 0; i < f.size(); ++i) {
        s += "g face" + std::to_string(i) + "\nvn 0 0 1\nf";
        for (const int k : f[i]) {
            s += " " + std::to_string(k + 1) + "//" + std::to_string(i + 1);
        }
        s += "\n";
    }
    return s;
}

std::string asciiStl(const Corners& v, const Faces& f) {
    std::string s = "solid test\n";
    for (const auto& t : f) {
        s += " facet normal 0 0 0\n  outer loop\n";
        for (const int k : t) {
            s += "   vertex " + num(v[k][0]) + " " + num(v[k][1]) + " " + num(v[k][2]) + "\n";
        }
        s += "  endloop\n endfacet\n";
    }
    return s + "endsolid test\n";
}

void putU32(std::string& s, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
        s += static_cast<char>((v >> (8 * i)) & 0xFF);
    }
}

void putF32(std::string& s, float v) {
    std::uint32_t u;
    std::memcpy(&u, &v, 4);
    putU32(s, u);
}

/// Binary STL, little-endian: 80-byte header, count, 50 bytes per facet.
std::string binaryStl(const Corners& v, const Faces& f, std::uint32_t count) {
    std::string s(80, ' ');
    s.replace(0, 6, "binary");
    putU32(s, count);
    for (const auto& t : f) {
        for (int k = 0; k < 3; ++k) {
            putF32(s, 0.0f);
        }
        for (const int k : t) {
            for (int c = 0; c < 3; ++c) {
                putF32(s, static_cast<float>(v[k][c]));
            }
        }
        s += std::string(2, '\0');
    }
    return s;
}

std::string plyHeader(const std::string& format, std::size_t vertices, std::size_t faces) {
    return "ply\nformat " + format + " 1.0\ncomment a test model\nelement vertex " +
           std::to_string(vertices) +
           "\nproperty float x\nproperty float y\nproperty float z\nelement face " +
           std::to_string(faces) + "\nproperty list uchar int vertex_indices\nend_header\n";
}

std::string asciiPly(const Corners& v, const Faces& f) {
    std::string s = plyHeader("ascii", v.size(), f.size());
    for (const auto& p : v) {
        s += num(p[0]) + " " + num(p[1]) + " " + num(p[2]) + "\n";
    }
    for (const auto& t : f) {
        s += std::to_string(t.size());
        for (const int k : t) {
            s += " " + std::to_string(k);
        }
        s += "\n";
    }
    return s;
}

std::string binaryPly(const Corners& v, const Faces& f) {
    std::string s = plyHeader("binary_little_endian", v.size(), f.size());
    for (const auto& p : v) {
        for (int c = 0; c < 3; ++c) {
            putF32(s, static_cast<float>(p[c]));
        }
    }
    for (const auto& t : f) {
        s += static_cast<char>(t.size());
        for (const int k : t) {
            putU32(s, static_cast<std::uint32_t>(k));
        }
    }
    return s;
}

/// True when every given corner, times `scale`, is a vertex of the mesh.
bool hasCorners(const TriangleMesh& m, const Corners& corners, double scale) {
    for (const auto& p : corners) {
        const Vec3 want = Vec3(p[0], p[1], p[2]) * scale;
        bool found = false;
        for (const Vec3& v : m.vertices()) {
            found = found || glm::length(v - want) <= 1e-6 * scale;
        }
        if (!found) {
            return false;
        }
    }
    return true;
}

std::string meshFileErrorOf(const std::filesystem::path& path, double scale = 1.0) {
    try {
        loadMeshFile(path, MeshSource{path.filename().string(), scale});
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

/// What parseMeshFile makes of the same bytes under the same name: the message, or "(no error)".
std::string parseErrorOf(const std::string& bytes, const std::filesystem::path& path) {
    try {
        parseMeshFile(bytes, path, MeshSource{path.filename().string(), 1.0});
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

} // namespace

TEST_CASE("a cube and a tetrahedron load from every format, closed, sharing their vertices") {
    test::TempDir dir;
    struct Model {
        const char* file;
        std::string bytes;
        bool cube;
    };
    const std::vector<Model> models{
        {"cube.obj", objText(kCube, kCubeQuads), true},
        {"tet.obj", objText(kTet, kTetFaces), false},
        {"tet-ascii.stl", asciiStl(kTet, kTetFaces), false},
        {"tet-binary.stl", binaryStl(kTet, kTetFaces, 4), false},
        {"cube-ascii.ply", asciiPly(kCube, kCubeQuads), true},
        {"tet-binary.ply", binaryPly(kTet, kTetFaces), false},
        {"TET.OBJ", objText(kTet, kTetFaces), false}, // the extension in any case
    };
    for (const double scale : {1.0, 0.01}) {
        for (const Model& m : models) {
            INFO(m.file << " at scale " << scale);
            test::writeFile(dir / m.file, m.bytes);
            const auto mesh = loadMeshFile(dir / m.file, MeshSource{m.file, scale});
            const std::size_t corners = m.cube ? 8 : 4;
            CHECK(mesh->triangleCount() == (m.cube ? 12u : 4u));
            CHECK(mesh->vertices().size() == corners); // shared edges share vertex indices
            CHECK(mesh->closed());
            CHECK(mesh->droppedDegenerate() == 0);
            CHECK(hasCorners(*mesh, m.cube ? kCube : kTet, scale));
            const double volume = (m.cube ? 1.0 : 1.0 / 6.0) * scale * scale * scale;
            CHECK(signedVolume(*mesh) == Approx(volume).epsilon(1e-6)); // faces point outward
            CHECK(mesh->localBounds().max.x == Approx(scale));
            CHECK(mesh->source().file == m.file);
            CHECK(mesh->source().scale == scale);
            // The bytes alone (what the fuzz target drives) give the same mesh.
            const auto parsed = parseMeshFile(m.bytes, dir / m.file, MeshSource{m.file, scale});
            CHECK(std::equal(parsed->vertices().begin(), parsed->vertices().end(),
                             mesh->vertices().begin(), mesh->vertices().end()));
            CHECK(std::equal(parsed->triangles().begin(), parsed->triangles().end(),
                             mesh->triangles().begin(), mesh->triangles().end()));
        }
    }
}

TEST_CASE("an open surface is open, and degenerate triangles are dropped and counted") {
    test::TempDir dir;
    // Three faces of the tetrahedron: open. A fourth, collinear triangle (vertex 5 lies on the
    // edge 1-2): degenerate.
    test::writeFile(dir / "open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 0.5 0 0\n"
                                      "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 1 5 2\n");
    const auto mesh = loadMeshFile(dir / "open.obj", MeshSource{"open.obj", 1.0});
    CHECK(mesh->triangleCount() == 3);
    CHECK(mesh->droppedDegenerate() == 1);
    CHECK_FALSE(mesh->closed());
    // A byte order mark, a tab after 'v', parameter-space vertices, vertex colours and a normal
    // written with leading points (assimp reads a vn's three words whatever they begin with).
    test::writeFile(dir / "bom.obj",
                    "\xEF\xBB\xBFv 0 0 0\nv\t1 0 0 0.5 0.5 0.5\nvp 0.5\nv 0 1 0\nvn .6 0 .8\n"
                    "f 1 2 3\n");
    const auto bom = loadMeshFile(dir / "bom.obj", MeshSource{"bom.obj", 1.0});
    CHECK(bom->triangleCount() == 1);
    CHECK(bom->localBounds().max.x == 1.0);
    // Lines and points are not triangles: ignored.
    test::writeFile(dir / "lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\np 3\nf 1 2 3\n");
    CHECK(loadMeshFile(dir / "lines.obj", MeshSource{"lines.obj", 1.0})->triangleCount() == 1);
}

TEST_CASE("bad model files are refused with the file and the place") {
    test::TempDir dir;
    struct Case {
        const char* file;
        std::string bytes;
        std::string expected; // the message must contain it (after the file's path)
    };
    std::string nanStl = binaryStl(kTet, kTetFaces, 4);
    {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        std::memcpy(&nanStl[84 + 50 + 12 + 4], &nan, 4); // facet 1, vertex 0, y
    }
    std::string nanPly = binaryPly(kTet, kTetFaces);
    std::string truncatedPly = binaryPly(kTet, kTetFaces);
    truncatedPly.resize(truncatedPly.size() - 3);
    std::string negativePly = binaryPly(kTet, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, -1}});
    std::string hugeFace;
    std::string hugePlyFace = "40000";
    for (int i = 0; i < 40000; ++i) {
        hugeFace += " " + std::to_string(1 + i % 3);
        hugePlyFace += " " + std::to_string(i % 3);
    }
    hugePlyFace += "\n";
    // end_header followed by a tab, and no newline anywhere in the body: the checker once read
    // its body from past the end of the file (found by fuzz_mesh_file, under ASan).
    std::string tabPly = binaryPly(kTet, kTetFaces);
    REQUIRE(tabPly.find("end_header\n") != std::string::npos);
    tabPly.replace(tabPly.find("end_header\n"), 11, "end_header\t");
    REQUIRE(tabPly.find('\n', tabPly.find("end_header")) == std::string::npos);
    const std::vector<Case> cases{
        {"nan.obj", "v 0 0 0\nv 1 0 0\n\nv 0 nan 0\nf 1 2 3\n",
         ":4: vertex coordinate 'nan' is not finite"},
        {"inf.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n",
         ":2: vertex coordinate '1e999' is not finite"},
        {"text.obj", "v 0 0 0\nv one 0 0\nv 0 1 0\nf 1 2 3\n", ":2: 'one' is not a number"},
        {"index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n# comment\nf 1 2 9\n",
         ":5: vertex index 9 is out of range (the file has 3 vertices)"},
        {"relative.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n",
         ":3: relative vertex index -3 is out of range (only 2 vertices come before this line)"},
        {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4: vertex index 0"},
        {"normal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2//1 3//1\n",
         ":4: normal index 1 is out of range (the file has 0 normals)"},
        {"two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", ":3: a face needs at least 3 vertices"},
        {"nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", ": no triangles"},
        {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
         ": no triangles left (all 1 were degenerate)"},
        {"binary.obj", std::string("v 0 0 0\n\0\n", 10), ": byte 8: a NUL byte"},
        {"nan.stl", nanStl, ": byte 150: facet 1, vertex 0: y is not finite (NaN)"},
        {"short.stl", binaryStl(kTet, kTetFaces, 5),
         "as binary STL its size, 284 bytes, is not the 84 + 50 x 5 = 334 bytes"},
        {"tiny.stl", "abc", "3 bytes: not ASCII STL"},
        {"empty.stl", "", "the model file is empty"},
        {"zero.stl", binaryStl(kTet, {}, 0), "no triangles (the binary STL header declares 0"},
        {"nan-ascii.stl",
         "solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
         "vertex 0 -inf 0\nendloop\nendfacet\nendsolid t\n",
         ":6: y '-inf' is not finite"},
        {"quad.stl",
         "solid t\n\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
         "vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
         ":3: the facet has 4 vertices; an STL facet is a triangle"},
        // Lines assimp 5.2.5 reads otherwise than the OBJ specification (found by
        // fuzz_mesh_file: it lost the line, or threw and leaked).
        {"indented.obj", "v 0 0 0\n  v 1 0 0\nv 0 1 0\nf 1 2 3\n", ":2: an indented 'v' statement"},
        {"word.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nfo 1 2 3\nf 1 2 3\n",
         ":4: 'fo' is not an OBJ geometry statement, but other readers (assimp) would read it as "
         "one"},
        {"five.obj", "v 0 0 0\nv 1 0 0 0 0\nv 0 1 0\nf 1 2 3\n",
         ":2: 'v' takes x y z, x y z w or x y z r g b, got 5 numbers"},
        {"uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 1\nf 1 2 3\n",
         ":4: 'vt' takes u v or u v w, got 1 numbers"},
        {"return.obj", "v 0 0 0\r\nv 1 0 0\r\nv \r0 1 0\nf 1 2 3\n",
         ":3: a carriage return inside a line"},
        {"feed.obj", "v 0 0 0\nv 1 0 \f0\nv 0 1 0\nf 1 2 3\n", ":2: a form feed inside a line"},
        {"dot.obj", "v 0 0 0\nv 1 0 0\nv 0 .5 0\nf 1 2 3\n",
         ":3: '.5' does not begin with a digit or a sign"},
        {"point.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1  11\nf 1 2 3\n",
         ":4: vertex index 11 is out of range (the file has 3 vertices)"},
        {"colour.obj", "v 0 0 0 1 red 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", ":1: 'red' is not a number"},
        {"open-facet.stl", "solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\n",
         ":2: the file ends inside this facet"},
        // Found by fuzz_mesh_file: assimp throws on a normal that is not a number (and leaks
        // what it read), and finds keywords inside other text, so every line is checked whole.
        {"normal.stl",
         "solid t\nfacet normal 0 0 \xca\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
         "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
         ":2: normal z '\xca' is not a number"},
        {"hidden-vertex.stl",
         "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
         "vertex 0 1 0\n\xff\xff  vertex 0 0 1\nendloop\nendfacet\nendsolid t\n",
         ":7: '\xff\xff' is not an ASCII STL keyword"},
        {"glued.stl",
         "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
         "vertex 0 1 0\nAendloop\nendfacet\nendsolid t\n",
         ":7: 'Aendloop' is not an ASCII STL keyword"},
        {"loop.stl",
         "solid t\nfacet normal 0 0 1\nouter loop vertex 0 0 0\nvertex 1 0 0\n"
         "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
         ":3: expected 'outer loop', got 6 words"},
        {"index.ply", asciiPly(kTet, {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 9}}),
         ":18: face element 3: vertex index 9 is out of range (the file has 4 vertices)"},
        {"nan.ply", asciiPly({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, NAN}}, kTetFaces),
         ":14: vertex element 3: z is not finite"},
        {"negative.ply", negativePly, "face element 3: vertex index -1 is out of range"},
        {"tab.ply", tabPly, ": expected 'end_header' alone on its line"},
        {"truncated.ply", truncatedPly,
         "the file ends inside face element 3, but the header declares 4 face elements"},
        {"too-many.ply", plyHeader("ascii", 3, 20000000),
         "more than 16777216 triangles; a mesh may have at most 16777216"},
        {"trailing.ply", asciiPly(kTet, kTetFaces) + "3 0 1 2\n",
         ":19: data after the last element the header declares"},
        // One element split over two lines: assimp's line-based reader misread it and then
        // aborted (an ai_assert in its Triangulate step), found by mutating a valid file.
        {"split.ply",
         plyHeader("ascii", 4, 4) +
             "0 0 0\n1 0\n0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
         ":12: the line ends inside vertex element 1 (an ASCII PLY element is one line"},
        {"long-line.ply",
         plyHeader("ascii", 4, 4) +
             "0 0 0 5\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
         ":11: more values on the line of vertex element 0 than its properties"},
        {"noface.ply",
         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty "
         "float y\nproperty float z\nend_header\n0 0 0\n",
         "no triangles (the PLY header declares no 'face' element)"},
        {"notply.ply", "solid t\n", ":1: not a PLY file"},
        // Float overflow, found by attacking it: assimp reads coordinates as 32-bit floats, and
        // the infinity it made was reported with the wrong coordinates and no line.
        {"float.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n",
         ":2: vertex coordinate '1e39' is beyond the largest 32-bit float"},
        {"float.stl",
         "solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1e308 0 0\n"
         "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
         ":5: x '1e308' is beyond the largest 32-bit float"},
        {"double.ply",
         "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
         "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
         "end_header\n0 0 0\n1 0 0\n0 1e300 0\n3 0 1 2\n",
         ":12: vertex element 2: y is beyond the largest 32-bit float"},
        // Farther than a mesh vertex may be (TriangleMesh::kMaxCoordinate), before degenerate
        // triangles could take the blame for the overflow in their area.
        {"far.obj", "v 0 0 0\nv 1e20 0 0\nv 0 1 0\nf 1 2 3\n",
         ":2: vertex coordinate '1e20' times the scale 1 is 1e+20 m, beyond the 1e+09 m"},
        // A weight that is 0 as a float: assimp's "Division by zero", with no line.
        {"weight.obj", "v 0 0 0 1e-320\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
         ":1: the vertex's weight w is 0 as a 32-bit float ('1e-320')"},
        {"min-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n",
         ":4: relative vertex index -9223372036854775808 is out of range"},
        {"vtab.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1\v2 3\n", ":4: a vertical tab"},
        {"huge-face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf" + hugeFace + "\n",
         ":4: a face of 40000 vertices; hapto reads at most 32767"},
        {"huge-face.ply", plyHeader("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n" + hugePlyFace,
         ":14: face element 0: a face of 40000 vertices; hapto reads at most 32767"},
        // A blank header line: assimp 5.2.5 refused this one ("Missing format specification").
        {"blank.ply",
         "ply\n \r\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float "
         "y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
         "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
         ":2: a blank line in the PLY header"},
        {"model.3ds", "anything", "unknown model format '.3ds' (hapto reads .obj, .stl and .ply)"},
    };
    for (const Case& c : cases) {
        INFO(c.file);
        test::writeFile(dir / c.file, c.bytes);
        const std::string message = meshFileErrorOf(dir / c.file);
        CHECK_THAT(message,
                   Catch::StartsWith((dir / c.file).string()) && Catch::Contains(c.expected));
        CHECK(parseErrorOf(c.bytes, dir / c.file) == message);
    }
    // The binary PLY's NaN: a vertex whose x is NaN, named by its byte.
    {
        const float nan = std::numeric_limits<float>::quiet_NaN();
        const std::size_t at = plyHeader("binary_little_endian", 4, 4).size() + 12;
        std::memcpy(&nanPly[at], &nan, 4); // vertex 1, x
        test::writeFile(dir / "nan-binary.ply", nanPly);
        CHECK_THAT(meshFileErrorOf(dir / "nan-binary.ply"),
                   Catch::Contains(": byte " + std::to_string(at) +
                                   ": vertex element 1: x is not finite"));
    }
    // A scale that takes a vertex farther than a mesh vertex may be, and one so small that
    // every triangle's area underflows (which once read as "all 4 were degenerate").
    test::writeFile(dir / "big.obj", "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n");
    CHECK_THAT(meshFileErrorOf(dir / "big.obj", 1e10),
               Catch::Contains("big.obj:2: vertex coordinate '1e30' times the scale 1e+10 is "
                               "1e+40 m, beyond the 1e+09 m a mesh vertex may lie"));
    test::writeFile(dir / "tet.obj", objText(kTet, kTetFaces));
    CHECK_THAT(meshFileErrorOf(dir / "tet.obj", 1e-320),
               Catch::Contains("tet.obj: the mesh is ") &&
                   Catch::Contains(" m across (after the scale ") &&
                   Catch::Contains("less than the 1e-09 m a mesh must span"));
}

TEST_CASE("a comment after a face is read as a comment") {
    // Legal OBJ that assimp 5.2.5 refused ("Invalid face index", no line): the loader blanks
    // comments before the check and assimp read the file.
    test::TempDir dir;
    test::writeFile(dir / "comment.obj",
                    "v 0 0 0 # a corner\nv 1 0 0\nv 0 1 0\nf 1 2 3 # c\n# f 1 2 9\n");
    const auto mesh = loadMeshFile(dir / "comment.obj", MeshSource{"comment.obj", 1.0});
    CHECK(mesh->triangleCount() == 1);
    // A NUL in a comment is still a NUL: refused, at its byte.
    CHECK_THAT(parseErrorOf(std::string("v 0 0 0 #") + '\0' + "\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
                            dir / "nul.obj"),
               Catch::Contains("nul.obj: byte 9: a NUL byte"));
}

TEST_CASE("duplicate triangles in a model file are dropped and counted") {
    // The tetrahedron with its first face twice more (once turned, once reversed): the corners
    // are welded, so the copies name the same vertices.
    test::TempDir dir;
    Faces faces = kTetFaces;
    faces.push_back({2, 1, 0});
    faces.push_back({1, 0, 2});
    test::writeFile(dir / "dup.stl", binaryStl(kTet, faces, 6));
    const auto mesh = loadMeshFile(dir / "dup.stl", MeshSource{"dup.stl", 1.0});
    CHECK(mesh->triangleCount() == 4);
    CHECK(mesh->droppedDuplicate() == 2);
    CHECK(mesh->droppedDegenerate() == 0);
    CHECK(mesh->closed());
}

namespace {

/// The process's peak resident memory so far (bytes).
std::uint64_t peakResidentBytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;
}

} // namespace

TEST_CASE("a 2 GB model file its first bytes refuse is refused without being read") {
    // A sparse file of 2 GiB of zeros: as binary STL its size does not match its count (0),
    // and it does not begin with 'solid'. Before, it was read whole (2 GB and more in memory).
    test::TempDir dir;
    const std::uint64_t size = std::uint64_t(2) << 30;
    for (const char* file : {"zeros.stl", "zeros.obj", "zeros.ply"}) {
        INFO(file);
        test::writeFile(dir / file, "");
        std::filesystem::resize_file(dir / file, size);
        const std::uint64_t before = peakResidentBytes();
        const std::string message = meshFileErrorOf(dir / file);
        CHECK(peakResidentBytes() - before < (std::uint64_t(64) << 20));
        CHECK_THAT(message, Catch::StartsWith((dir / file).string()));
        if (std::string(file) == "zeros.stl") {
            CHECK_THAT(message, Catch::Contains("not ASCII STL (it does not begin with 'solid'), "
                                                "and as binary STL its size, 2147483648 bytes, "
                                                "is not the 84 + 50 x 0 = 84 bytes"));
        } else {
            CHECK_THAT(message, Catch::Contains(": byte 0: a NUL byte"));
        }
        std::filesystem::remove(dir / file);
    }
    // A binary STL whose count is past the triangle limit, refused by its header.
    std::string header(80, ' ');
    putU32(header, 20000000);
    test::writeFile(dir / "many.stl", header);
    std::filesystem::resize_file(dir / "many.stl", 84 + 50 * std::uint64_t(20000000));
    CHECK_THAT(meshFileErrorOf(dir / "many.stl"), Catch::Contains("more than 16777216 triangles"));
}

TEST_CASE("a model file that is missing, a folder or a FIFO is refused without blocking") {
    test::TempDir dir;
    CHECK_THAT(meshFileErrorOf(dir / "missing.obj"),
               Catch::Contains("missing.obj: cannot open the model file"));
    std::filesystem::create_directory(dir / "folder.obj");
    CHECK_THAT(meshFileErrorOf(dir / "folder.obj"),
               Catch::Contains("folder.obj: is a directory, not a regular file"));
    REQUIRE(::mkfifo((dir / "pipe.stl").c_str(), 0600) == 0);
    CHECK_THAT(meshFileErrorOf(dir / "pipe.stl"), Catch::Contains("pipe.stl: is a FIFO"));
}

TEST_CASE("a model's material libraries are never opened, so a FIFO or a stray file named there "
          "changes nothing") {
    // assimp's default file access would open what `mtllib` names: the FIFO blocked the load
    // forever, and a one-byte file got the model refused ("File is too small").
    test::TempDir dir;
    REQUIRE(::mkfifo((dir / "fifo.mtl").c_str(), 0600) == 0);
    test::writeFile(dir / "tiny.mtl", "x");
    const std::string triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    for (const char* library : {"fifo.mtl", "tiny.mtl"}) {
        INFO(library);
        test::writeFile(dir / "model.obj", "mtllib " + (dir / library).string() + "\nmtllib " +
                                               library + "\n" + triangle);
        const auto mesh = loadMeshFile(dir / "model.obj", MeshSource{"model.obj", 1.0});
        CHECK(mesh->triangleCount() == 1);
        CHECK(mesh->vertices().size() == 3);
    }
}

TEST_CASE("isMeshFile knows the three formats by extension") {
    CHECK(isMeshFile("a/b.obj"));
    CHECK(isMeshFile("B.Stl"));
    CHECK(isMeshFile("c.PLY"));
    CHECK_FALSE(isMeshFile("d.3ds"));
    CHECK_FALSE(isMeshFile("obj"));
}
