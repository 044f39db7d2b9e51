// The JSON loader's simdjson fast path against the checked (nlohmann) loader: the same scene
// for every valid file, bit for bit, and for every bad one the checked loader's message, word
// for word (the fast path hands anything it does not vouch for to the checked loader).

#include "hapto/io/InputError.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/SceneFile.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <bit>
#include <cstring>
#include <filesystem>
#include <string>

using namespace hapto;

namespace {

/// What a loader makes of the text: the scene's JSON and its centres' bits, or the message.
std::string outcome(bool fast, const std::string& text) {
    try {
        const Scene s = fast ? parseScene(text, "t.json") : parseSceneChecked(text, "t.json");
        std::string bits = sceneToJson(s);
        for (const SceneObject& o : s.objects()) {
            for (int i = 0; i < 3; ++i) {
                bits += ' ' + std::to_string(std::bit_cast<std::uint64_t>(o.center[i]));
            }
        }
        return bits;
    } catch (const InputError& e) {
        return std::string("refused: ") + e.what();
    }
}

void checkSame(const std::string& text) {
    INFO(text.substr(0, 300));
    CHECK(outcome(true, text) == outcome(false, text));
}

std::string sceneWith(const std::string& object) {
    return R"({"format": "hapto-scene", "version": 1, "objects": [)" + object + "]}";
}

} // namespace

TEST_CASE("the fast path reads generated scenes exactly as the checked loader") {
    RandomOptions random;
    random.count = 2000;
    random.rotate = true;
    ClusterOptions cluster;
    cluster.count = 500;
    cluster.rotate = true;
    for (const Scene& scene :
         {makeRandomScene(random), makeClusterScene(cluster), makeDefaultScene(), Scene()}) {
        const std::string text = sceneToJson(scene);
        CHECK(parseScene(text, "s.json") == parseSceneChecked(text, "s.json"));
        CHECK(parseScene(text, "s.json") == scene);
        checkSame(text);
    }
}

TEST_CASE("the fast path reads numbers as the checked loader does") {
    for (const char* center :
         {"[-0, 0, 0]", "[-0.0, 1e-320, 2.2250738585072014e-308]", "[1.7976931348623157e308, 0, 0]",
          "[18446744073709551615, 0, 0]", "[-9223372036854775808, 1, 2]",
          "[99999999999999999999999, 0, 0]", "[0.1, 0.30000000000000004, 1e-7]",
          "[1E2, 1e+2, 100.000]", "[1e400, 0, 0]"}) {
        checkSame(sceneWith(std::string(R"({"id": 0, "shape": "sphere", "center": )") + center +
                            R"(, "radius": 0.5})"));
    }
    for (const char* id : {"0", "-0", "4294967294", "4294967295", "1.0", "1e0", "-1"}) {
        checkSame(sceneWith(std::string(R"({"id": )") + id +
                            R"(, "shape": "sphere", "center": [0,0,0], "radius": 1})"));
    }
}

TEST_CASE("what the fast path does not vouch for gets the checked loader's message") {
    const char* box = R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1]})";
    const std::string cases[] = {
        sceneWith(box) + " x", // trailing content
        sceneWith(box) + "]",  // a stray bracket
        sceneWith(
            R"({"id": 0, "id": 1, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1]})"),
        sceneWith(
            R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1], "x": 1})"),
        sceneWith(R"({"id": 0, "shape": "box", "center": [0,0,0], "radius": 1})"),
        sceneWith(R"({"id": 0, "shape": "box", "center": [0,0], "half_extents": [1,1,1]})"),
        sceneWith(R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,0]})"),
        sceneWith(R"({"id": 0, "shape": "cone", "center": [0,0,0], "half_extents": [1,1,1]})"),
        sceneWith(std::string(box) + ", " + box), // duplicate id
        R"({"format": "hapto-scene", "version": 4, "objects": []})",
        R"({"format": "hapto-scene", "version": 1, "objects": [], "objects": []})",
        R"({"format": "hapto-scene", "version": 1})",
        R"({"format": "hapto-scene", "version": 1, "objects": [)" + std::string(box) + ",]}",
        "{\"format\": \"hapto-scene\", \"version\": 1,\n \"objects\": [\n  {\"id\": 0,}]}",
        R"({"format": "hapto-scene", "version": 1, "objects": [], "bounds": {"min": [1,1,1], "max": [0,0,0]}})",
        R"({"format": "hapto-scene", "version": 1, "objects": [], "bounds": {"min": [0,0,0]}})",
        R"({"format": "hapto-scen\u0065", "version": 1, "objects": []})",
        R"({"form\u0061t": "hapto-scene", "version": 1, "objects": []})",
        "",
        "[]",
    };
    for (const std::string& text : cases) {
        checkSame(text);
    }
}

TEST_CASE("the bad-scene corpus and the fuzz corpus get the same answers from both paths") {
    namespace fs = std::filesystem;
    const fs::path root = HAPTO_SOURCE_DIR;
    int files = 0;
    for (const fs::path& dir :
         {root / "tests/tools/bad_inputs/scenes", root / "tools/fuzz/corpus/scene_file"}) {
        for (const auto& entry : fs::directory_iterator(dir)) {
            if (entry.path().extension() == ".json") {
                checkSame(test::readFile(entry.path()));
                ++files;
            }
        }
    }
    CHECK(files > 20);
}
