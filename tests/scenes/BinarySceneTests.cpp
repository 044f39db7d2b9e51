// The binary scene format: JSON -> binary -> JSON gives the same scene, every value is checked
// on read with the JSON loader's own rules and words plus the byte offset, and no truncation or
// bit flip gets past the reader as anything but an InputError or a valid scene.

#include "hapto/io/InputError.h"
#include "hapto/scenes/BinaryScene.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/SceneFile.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

using namespace hapto;

namespace {

const char* kMixed = R"({"format": "hapto-scene", "version": 2,
 "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]},
 "objects": [
  {"id": 7, "shape": "box", "center": [0.1, 0.2, 0.3], "half_extents": [0.01, 0.02, 0.03],
   "rotation": [0.5, 0.5, 0.5, 0.5], "stiffness": 1200, "friction": [0.4, 0.3]},
  {"id": 3, "shape": "sphere", "center": [-0.1, 0, 0], "radius": 0.05,
   "rotation": [0, 1, 0, 0]},
  {"id": 9, "shape": "mesh", "center": [0, 0.5, 0], "scale": 2,
   "vertices": [[0,0,0], [1,0,0], [0,1,0], [0,0,1]],
   "triangles": [[0,2,1], [0,1,3], [0,3,2], [1,2,3]]},
  {"id": 4, "shape": "box", "center": [0, 0, 0], "half_extents": [0.1, 0.1, 0.1]}]})";

std::string binaryErrorOf(const std::string& bytes) {
    try {
        parseBinaryScene(bytes, "bad.hsb");
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

std::string jsonErrorOf(const std::string& text) {
    try {
        parseScene(text, "bad.json");
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

template <class T> void poke(std::string& bytes, std::size_t offset, T v) {
    std::memcpy(bytes.data() + offset, &v, sizeof v);
}

std::size_t record(std::size_t slot) {
    return kBinarySceneHeaderBytes + slot * kBinarySceneRecordBytes;
}

/// Two objects, a box then a sphere, as the JSON and binary loaders see them.
const char* kTwo = R"({"format": "hapto-scene", "version": 1, "objects": [
  {"id": 0, "shape": "box", "center": [0, 0, 0], "half_extents": [0.1, 0.1, 0.1]},
  {"id": 1, "shape": "sphere", "center": [0.5, 0, 0], "radius": 0.05}]})";

} // namespace

TEST_CASE("JSON to binary to JSON gives the same scene, byte for byte") {
    RandomOptions options;
    options.count = 500;
    options.rotate = true;
    const Scene scene = makeRandomScene(options);
    const std::string bytes = sceneToBinary(scene);
    CHECK(bytes.size() == kBinarySceneHeaderBytes + 500 * kBinarySceneRecordBytes);
    CHECK(isBinaryScene(bytes));
    const Scene back = parseBinaryScene(bytes, "s.hsb");
    CHECK(back == scene);
    CHECK(sceneToJson(back) == sceneToJson(scene));
    CHECK(sceneToBinary(back) == bytes);
}

TEST_CASE("a negative zero keeps its sign through JSON and the binary format") {
    const Scene scene = parseScene(R"({"format": "hapto-scene", "version": 1, "objects": [
        {"id": 0, "shape": "box", "center": [-0.0, 0, 0], "half_extents": [1, 1, 1],
         "friction": [-0.0, -0.0]}]})",
                                   "zero.json");
    REQUIRE(std::signbit(scene.object(0).material.staticFriction));
    const std::string json = sceneToJson(scene);
    const Scene fromJson = parseScene(json, "again.json");
    CHECK(std::signbit(fromJson.object(0).center.x));
    CHECK(std::signbit(fromJson.object(0).material.dynamicFriction));
    CHECK(sceneToJson(fromJson) == json);
    const Scene fromBinary = parseBinaryScene(sceneToBinary(fromJson), "zero.hsb");
    CHECK(sceneToJson(fromBinary) == json);
    CHECK(sceneToBinary(fromBinary) == sceneToBinary(scene));
}

TEST_CASE("spheres, rotations, materials and inline meshes survive the binary format") {
    const Scene scene = parseScene(kMixed, "mixed.json");
    const std::string bytes = sceneToBinary(scene);
    const Scene back = parseBinaryScene(bytes, "mixed.hsb");
    REQUIRE(back.size() == scene.size());
    CHECK(back.triangleCount() == scene.triangleCount());
    CHECK(back.bounds().min == scene.bounds().min);
    // A mesh object compares its mesh by identity: the meshes are compared by their text.
    CHECK(sceneToJson(back) == sceneToJson(scene));
    const SceneObject& mesh = back.object(2);
    REQUIRE(mesh.shape == Shape::Mesh);
    CHECK(mesh.mesh->vertices().size() == 4);
    CHECK(mesh.mesh->vertices()[1] == Vec3(2, 0, 0)); // scale applied
    CHECK(mesh.halfExtents == scene.object(2).halfExtents);
}

TEST_CASE("a mesh from a model file is kept as a reference to the file") {
    test::TempDir dir;
    test::writeFile(dir / "tet.obj",
                    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    test::writeFile(dir / "s.json", R"({"format": "hapto-scene", "version": 2, "objects": [
        {"id": 0, "shape": "mesh", "center": [0, 0, 0], "file": "tet.obj", "scale": 0.5}]})");
    const Scene scene = loadSceneFile(dir / "s.json");
    const std::string bytes = sceneToBinary(scene);
    CHECK(bytes.find("tet.obj") != std::string::npos);
    test::writeFile(dir / "s.hsb", bytes);
    const Scene back = loadSceneFile(dir / "s.hsb");
    CHECK(back.object(0).mesh->source().file == "tet.obj");
    CHECK(back.object(0).mesh->source().scale == 0.5);
    CHECK(sceneToJson(back) == sceneToJson(scene));
    // Read relative to the binary file's folder: elsewhere the model is not found.
    CHECK_THAT(binaryErrorOf(bytes), Catch::Contains("bad.hsb: byte 232: objects[0].file: "));
}

TEST_CASE("loadSceneFile tells binary from JSON by the magic, not the name") {
    test::TempDir dir;
    const Scene scene = parseScene(kTwo, "two.json");
    test::writeFile(dir / "binary-named.json", sceneToBinary(scene));
    CHECK(loadSceneFile(dir / "binary-named.json") == scene);
    test::writeFile(dir / "json-named.hsb", sceneToJson(scene));
    CHECK(loadSceneFile(dir / "json-named.hsb") == scene);
}

TEST_CASE("a bad value is refused with the JSON loader's words, its path and its byte") {
    const std::string good = sceneToBinary(parseScene(kTwo, "two.json"));
    struct Case {
        const char* json; // the same bad value in JSON
        std::size_t offset;
        double value;
        const char* where;
    };
    const Case cases[] = {
        {R"("half_extents": [-0.1, 0.1, 0.1])", record(0) + 32, -0.1,
         "objects[0].half_extents[0]: a half extent must be > 0 (got -0.1)"},
        {R"("half_extents": [0.1, 0.1, 0.1], "stiffness": 2e6)", record(0) + 88, 2e6,
         "objects[0].stiffness: stiffness (N/m) must be <= 1e+06 (got 2e+06)"},
        {R"("half_extents": [0.1, 0.1, 0.1], "friction": [0.1, 0.2])", record(0) + 104, 0.2,
         "objects[0].friction: the dynamic coefficient (second) must not exceed the static one"},
        {R"("half_extents": [0.1, 0.1, 0.1], "rotation": [2, 0, 0, 0])", record(0) + 56, 2.0,
         "objects[0].rotation: must be a unit quaternion (w, x, y, z); its length is 2"},
    };
    for (const Case& c : cases) {
        const std::string json =
            std::string(R"({"format": "hapto-scene", "version": 1, "objects": [)") +
            R"({"id": 0, "shape": "box", "center": [0, 0, 0], )" + c.json +
            R"(}, {"id": 1, "shape": "sphere", "center": [0.5, 0, 0], "radius": 0.05}]})";
        std::string bytes = good;
        poke(bytes, c.offset, c.value);
        INFO(c.where);
        CHECK_THAT(jsonErrorOf(json), Catch::Contains(std::string("bad.json: ") + c.where));
        CHECK_THAT(binaryErrorOf(bytes),
                   Catch::Contains("bad.hsb: byte " + std::to_string(record(0)) + ": " + c.where));
    }
}

TEST_CASE("every float is finite, every record and header field checked") {
    const std::string good = sceneToBinary(parseScene(kTwo, "two.json"));
    std::string bytes = good;
    poke(bytes, record(1) + 16, std::numeric_limits<double>::quiet_NaN());
    CHECK_THAT(binaryErrorOf(bytes),
               Catch::Contains("bad.hsb: byte 208: objects[1].center[1]: expected a finite "
                               "number"));
    bytes = good;
    poke(bytes, record(0) + 40, std::numeric_limits<double>::infinity());
    CHECK_THAT(binaryErrorOf(bytes),
               Catch::Contains("objects[0].half_extents[1]: expected a finite number"));
    bytes = good;
    poke(bytes, record(1) + 40, 0.07);
    CHECK_THAT(binaryErrorOf(bytes), Catch::Contains("objects[1].radius: a sphere's record holds "
                                                     "its radius three times"));
    bytes = good;
    poke(bytes, record(1) + 4, std::uint8_t{5});
    CHECK_THAT(binaryErrorOf(bytes), Catch::Contains("objects[1].shape: unknown shape code 5"));
    bytes = good;
    poke(bytes, record(1), std::uint32_t{0});
    CHECK_THAT(binaryErrorOf(bytes), Catch::Contains("objects[1].id: duplicate id 0 (also at "
                                                     "objects[0])"));
    bytes = good;
    poke(bytes, 8, std::uint32_t{2});
    CHECK_THAT(binaryErrorOf(bytes),
               Catch::Contains("bad.hsb: byte 8: this build reads binary scene version 1, got 2"));
    bytes = good;
    poke(bytes, 24, std::uint64_t{1} << 40);
    CHECK_THAT(binaryErrorOf(bytes), Catch::Contains("bad.hsb: byte 24: the header's") &&
                                         Catch::Contains("truncated or damaged"));
    bytes = good;
    poke(bytes, 40, 2.0); // bounds min x above max x
    CHECK_THAT(binaryErrorOf(bytes),
               Catch::Contains("bad.hsb: byte 40: bounds: min must be < max on every axis"));
    CHECK_THAT(binaryErrorOf(good.substr(0, 50)),
               Catch::Contains("bad.hsb: byte 0: the file has 50 bytes"));
    CHECK_THAT(binaryErrorOf("HAPTOSCX" + good.substr(8)),
               Catch::Contains("the magic \"HAPTOSCN\" is missing"));
    CHECK_THAT(binaryErrorOf(good + "x"), Catch::Contains("do not add up"));
}

TEST_CASE("an inline mesh's counts are checked against the file before allocating") {
    const std::string good = sceneToBinary(parseScene(kMixed, "mixed.json"));
    const std::size_t entry = record(4);
    std::string bytes = good;
    poke(bytes, entry + 16, std::uint64_t{1} << 60); // vertex count
    CHECK_THAT(binaryErrorOf(bytes),
               Catch::Contains("bad.hsb: byte " + std::to_string(entry + 16) + ": objects[2]: ") &&
                   Catch::Contains("a mesh may have at most"));
    bytes = good;
    poke(bytes, entry + 16, std::uint64_t{1000}); // more than the section holds
    CHECK_THAT(binaryErrorOf(bytes), Catch::Contains("the mesh section has"));
    bytes = good;
    poke(bytes, entry + 32 + 4 * 24, std::uint32_t{4}); // triangle 0, corner 0: vertex 4 of 4
    CHECK_THAT(binaryErrorOf(bytes),
               Catch::Contains("objects[2].triangles[0][0]: vertex index 4 is out of range (the "
                               "mesh has 4 vertices)"));
}

TEST_CASE("every truncation of a binary scene is refused") {
    const std::string good = sceneToBinary(parseScene(kMixed, "mixed.json"));
    for (std::size_t n = 0; n < good.size(); ++n) {
        INFO(n);
        CHECK_THROWS_AS(parseBinaryScene(good.substr(0, n), "cut.hsb"), InputError);
    }
}

TEST_CASE("a bit flip anywhere is refused or gives a valid scene that writes back stably") {
    const std::string good = sceneToBinary(parseScene(kMixed, "mixed.json"));
    std::size_t refused = 0;
    for (std::size_t byte = 0; byte < good.size(); ++byte) {
        for (int bit = 0; bit < 8; ++bit) {
            std::string bytes = good;
            bytes[byte] = static_cast<char>(bytes[byte] ^ (1 << bit));
            INFO("byte " << byte << " bit " << bit);
            try {
                const Scene s = parseBinaryScene(bytes, "flip.hsb");
                // What loads holds only valid values: it writes and reads back to itself.
                const std::string again = sceneToBinary(s);
                CHECK(sceneToBinary(parseBinaryScene(again, "again.hsb")) == again);
            } catch (const InputError&) {
                ++refused;
            }
        }
    }
    CHECK(refused > 0);
}
