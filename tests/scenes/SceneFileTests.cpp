#include "hapto/io/InputError.h"
#include "hapto/io/InputFile.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/SceneFile.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <regex>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

using namespace hapto;

namespace {

// The exact example from the user guide (docs/guide/scenes.md) and the issue.
const char* kReadmeExample = R"({"format": "hapto-scene", "version": 1,
 "bounds": {"min": [-0.125, -0.125, -0.125], "max": [0.125, 0.125, 0.125]},
 "objects": [
  {"id": 0, "shape": "box", "center": [0, 0, 0], "half_extents": [0.025, 0.025, 0.025],
   "rotation": [1, 0, 0, 0], "stiffness": 800, "friction": [0.3, 0.2]},
  {"id": 1, "shape": "sphere", "center": [0.05, 0, 0], "radius": 0.01}]})";

std::string errorOf(const std::string& text) {
    try {
        parseScene(text, "bad.json");
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

std::string withObject(const std::string& object) {
    return R"({"format": "hapto-scene", "version": 1, "objects": [)"
           R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1]}, )" +
           object + "]}";
}

} // namespace

TEST_CASE("the user guide's scene example loads with its defaults applied") {
    const Scene s = parseScene(kReadmeExample, "example.json");
    REQUIRE(s.size() == 2);
    CHECK(s.bounds().min == Vec3(-0.125));
    CHECK(s.bounds().max == Vec3(0.125));
    const SceneObject& box = s.object(0);
    CHECK(box.shape == Shape::Box);
    CHECK(box.halfExtents == Vec3(0.025));
    CHECK(box.material.stiffness == 800.0);
    CHECK(box.material.staticFriction == 0.3);
    CHECK(box.material.dynamicFriction == 0.2);
    const SceneObject& sphere = s.object(1);
    CHECK(sphere.shape == Shape::Sphere);
    CHECK(sphere.radius() == 0.01);
    CHECK(sphere.center == Vec3(0.05, 0, 0));
    CHECK(sphere.material == Material{});
    CHECK(sphere.rotation == Quat(1, 0, 0, 0));
}

TEST_CASE("the user guide shows the same scene example the tests load") {
    const std::string readme =
        test::readFile(std::string(HAPTO_SOURCE_DIR) + "/docs/guide/scenes.md");
    // Compare ignoring white space.
    auto squash = [](std::string s) {
        s.erase(std::remove_if(s.begin(), s.end(), ::isspace), s.end());
        return s;
    };
    CHECK(squash(readme).find(squash(kReadmeExample)) != std::string::npos);
}

TEST_CASE("bounds default to the objects' union, padded") {
    const Scene s = parseScene(
        withObject(R"({"id": 5, "shape": "sphere", "center": [3,0,0], "radius": 0.5})"), "x.json");
    CHECK(s.bounds().min.x < -1.0);
    CHECK(s.bounds().max.x > 3.5);
    CHECK(s.bounds().max.x < 3.5 + 0.5);
}

TEST_CASE("save then load gives the same scene, and ids need not be dense") {
    test::TempDir dir;
    std::vector<SceneObject> objects{
        makeBox(1000, Vec3(0.01, -0.02, 0.03), Vec3(0.01, 0.02, 0.005),
                glm::normalize(Quat(0.9, 0.1, -0.3, 0.2)), Material{1200, 0.5, 0.25}),
        makeSphere(3, Vec3(-0.05, 0, 0.1), 0.0125, Material{300, 0, 0}),
        makeBox(4000000000u, Vec3(0), Vec3(0.001))};
    const Scene original(Aabb{Vec3(-0.2), Vec3(0.3)}, objects);
    saveSceneFile(original, dir / "s.json");
    const Scene loaded = loadSceneFile(dir / "s.json");
    CHECK(loaded == original);
    CHECK(loaded.slotOf(4000000000u) == 2u);
}

TEST_CASE("a sphere's rotation survives save and load") {
    // Failed fuzz_scene_file's round-trip check (corpus crash-sphere-rotation-lost.json):
    // spheres accept a "rotation" (a grasp turns them too) but the writer left it out.
    const Scene original = parseScene(
        withObject(
            R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "rotation": [0, 1, 0, 0]})"),
        "x.json");
    REQUIRE(original.object(1).rotation == Quat(0, 1, 0, 0));
    CHECK(parseScene(sceneToJson(original), "again.json") == original);
    // An unturned sphere is written as before, without a rotation.
    const Scene plain(Aabb{Vec3(-1), Vec3(1)}, {makeSphere(2, Vec3(0), 0.5)});
    CHECK(sceneToJson(plain).find("rotation") == std::string::npos);
}

TEST_CASE("generated scenes round-trip through files bit for bit") {
    test::TempDir dir;
    RandomOptions opt;
    opt.count = 500;
    opt.seed = 9;
    opt.rotate = true;
    const Scene original = makeRandomScene(opt);
    saveSceneFile(original, dir / "r.json");
    const Scene loaded = loadSceneFile(dir / "r.json");
    CHECK(loaded == original);
    CHECK(sceneToJson(loaded) == test::readFile(dir / "r.json"));
}

TEST_CASE("every class of bad file is refused with the file, the JSON path and the reason") {
    struct Case {
        const char* name;
        std::string text;
        const char* expected; // a regex the message must match
    };
    const std::vector<Case> cases{
        {"syntax error", R"({"format": "hapto-scene", "version": 1, "objects": [})",
         R"(bad\.json:1:\d+: not valid JSON)"},
        {"syntax error on a later line",
         "{\"format\": \"hapto-scene\",\n \"version\": 1,\n \"objects\": [,]}",
         R"(bad\.json:3:\d+: not valid JSON)"},
        {"not an object", "[1, 2]", "bad.json: \\(top level\\): expected a JSON object"},
        {"wrong format", R"({"format": "obj", "version": 1, "objects": []})",
         "bad.json: format: expected \"hapto-scene\""},
        {"missing format", R"({"version": 1, "objects": []})", "missing required field 'format'"},
        {"unknown version", R"({"format": "hapto-scene", "version": 4, "objects": []})",
         "bad.json: version: this build reads versions 1 to 3, got 4"},
        {"missing objects", R"({"format": "hapto-scene", "version": 1})",
         "missing required field 'objects'"},
        {"objects not an array", R"({"format": "hapto-scene", "version": 1, "objects": {}})",
         "bad.json: objects: expected an array"},
        {"unknown top-level field",
         R"({"format": "hapto-scene", "version": 1, "objects": [], "lights": []})",
         "unknown field 'lights'"},
        {"object not an object", withObject("42"), R"(objects\[1\]: expected an object)"},
        {"array as an object", withObject("[1, 2]"),
         R"(objects\[1\]: expected an object, got an array)"},
        {"missing id",
         withObject(R"({"shape": "box", "center": [0,0,0], "half_extents": [1,1,1]})"),
         R"(objects\[1\]: missing required field 'id')"},
        {"negative id",
         withObject(R"({"id": -1, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1]})"),
         R"(objects\[1\]\.id: must be in 0\.\.)"},
        {"fractional id",
         withObject(R"({"id": 1.5, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1]})"),
         R"(objects\[1\]\.id: expected a non-negative integer)"},
        {"duplicate id",
         withObject(R"({"id": 0, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1]})"),
         R"(objects\[1\]\.id: duplicate id 0 \(also at objects\[0\]\))"},
        {"unknown shape", withObject(R"({"id": 1, "shape": "cone", "center": [0,0,0]})"),
         R"(objects\[1\]\.shape: unknown shape 'cone')"},
        {"mistyped shape", withObject(R"({"id": 1, "shape": 3, "center": [0,0,0]})"),
         R"(objects\[1\]\.shape: expected a string)"},
        {"missing center", withObject(R"({"id": 1, "shape": "sphere", "radius": 1})"),
         R"(objects\[1\]: missing required field 'center')"},
        {"mistyped center",
         withObject(R"({"id": 1, "shape": "sphere", "center": "here", "radius": 1})"),
         R"(objects\[1\]\.center: expected an array of 3 numbers, got a string)"},
        {"short center",
         withObject(R"({"id": 1, "shape": "sphere", "center": [0, 1], "radius": 1})"),
         R"(objects\[1\]\.center: expected an array of 3 numbers, got an array of 2)"},
        {"string in center",
         withObject(R"({"id": 1, "shape": "sphere", "center": [0, "1", 2], "radius": 1})"),
         R"(objects\[1\]\.center\[1\]: expected a number, got a string)"},
        {"non-finite number",
         withObject(R"({"id": 1, "shape": "sphere", "center": [0, 1e999, 2], "radius": 1})"),
         R"(bad\.json)"},
        {"zero size",
         withObject(R"({"id": 1, "shape": "box", "center": [0,0,0], "half_extents": [1, 0, 1]})"),
         R"(objects\[1\]\.half_extents\[1\]: a half extent must be > 0 \(got 0\))"},
        {"negative size",
         withObject(R"({"id": 1, "shape": "box", "center": [0,0,0], "half_extents": [1, 1, -2]})"),
         R"(objects\[1\]\.half_extents\[2\]: a half extent must be > 0)"},
        {"zero radius",
         withObject(R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 0})"),
         R"(objects\[1\]\.radius: the radius must be > 0)"},
        {"quaternion far from unit",
         withObject(
             R"({"id": 1, "shape": "box", "center": [0,0,0], "half_extents": [1,1,1], "rotation": [1, 1, 0, 0]})"),
         R"(objects\[1\]\.rotation: must be a unit quaternion)"},
        {"negative stiffness",
         withObject(
             R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "stiffness": -5})"),
         R"(objects\[1\]\.stiffness: stiffness \(N/m\) must be > 0)"},
        {"friction out of order",
         withObject(
             R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "friction": [0.1, 0.5]})"),
         R"(objects\[1\]\.friction: the dynamic coefficient)"},
        {"radius on a box",
         withObject(R"({"id": 1, "shape": "box", "center": [0,0,0], "radius": 1})"),
         R"(objects\[1\]: unknown field 'radius')"},
        {"typo in a field",
         withObject(
             R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "stifness": 5})"),
         R"(objects\[1\]: unknown field 'stifness')"},
        {"inverted bounds",
         R"({"format": "hapto-scene", "version": 1, "bounds": {"min": [0,0,0], "max": [1,-1,1]}, "objects": []})",
         R"(bad\.json: bounds: min must be < max)"},
        {"bounds missing max",
         R"({"format": "hapto-scene", "version": 1, "bounds": {"min": [0,0,0]}, "objects": []})",
         R"(bounds: missing required field 'max')"},
        // Found by fuzz_scene_file (corpus crash-default-bounds-collapse.json): 1 mm of margin
        // is lost to rounding at 1e19 m, and the Scene threw std::invalid_argument.
        {"objects too far out for default bounds",
         R"({"format": "hapto-scene", "version": 1, "objects": [{"id": 1, "shape": "sphere", "center": [0, 0, 1e19], "radius": 1}]})",
         R"(bad\.json: objects: the objects lie too far out on axis 2 .*give "bounds" explicitly)"},
        {"default bounds overflow",
         R"({"format": "hapto-scene", "version": 1, "objects": [{"id": 1, "shape": "sphere", "center": [1e308, 0, 0], "radius": 1}, {"id": 2, "shape": "sphere", "center": [-1e308, 0, 0], "radius": 1}]})",
         R"(bad\.json: objects: the objects lie too far out on axis 0)"},
        {"stiffness that would overflow a force",
         withObject(
             R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "stiffness": 1e200})"),
         R"(bad\.json: objects\[1\]\.stiffness: stiffness \(N/m\) must be <= 1e\+06 \(got 1e\+200\))"},
        {"stiffness just above the limit",
         withObject(
             R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "stiffness": 1000001})"),
         R"(objects\[1\]\.stiffness: stiffness \(N/m\) must be <= 1e\+06)"},
        {"friction that would overflow",
         withObject(
             R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "friction": [1e300, 0]})"),
         R"(objects\[1\]\.friction\[0\]: a friction coefficient must be <= 10)"},
        {"bounds whose size overflows",
         R"({"format": "hapto-scene", "version": 1, "bounds": {"min": [-1e308, 0, 0], "max": [1e308, 1, 1]}, "objects": []})",
         R"(bad\.json: bounds: the bounds are too large: max - min overflows on axis 0)"},
        {"object too far from explicit bounds",
         R"({"format": "hapto-scene", "version": 1, "bounds": {"min": [-1e308, 0, 0], "max": [0, 1, 1]}, "objects": [{"id": 4, "shape": "sphere", "center": [0, 0, 0], "radius": 1}, {"id": 5, "shape": "sphere", "center": [1e308, 0, 0], "radius": 1}]})",
         R"(bad\.json: objects\[1\]: the object lies too far from the bounds: .* overflows on axis 0)"},
        {"sphere whose own size overflows",
         R"({"format": "hapto-scene", "version": 1, "bounds": {"min": [0, 0, 0], "max": [1, 1, 1]}, "objects": [{"id": 4, "shape": "sphere", "center": [0, 0, 0], "radius": 1e308}]})",
         R"(bad\.json: objects\[0\]: the object lies too far from the bounds)"},
        {"duplicate top-level key",
         R"({"format": "hapto-scene", "version": 1, "version": 1, "objects": []})",
         R"(bad\.json: \(top level\): duplicate field 'version')"},
        {"duplicate key in an object",
         withObject(
             R"({"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "stiffness": 900, "stiffness": 1})"),
         R"(bad\.json: objects\[1\]: duplicate field 'stiffness')"},
        {"duplicate key in the bounds",
         R"({"format": "hapto-scene", "version": 1, "bounds": {"min": [0,0,0], "max": [1,1,1], "min": [-1,-1,-1]}, "objects": []})",
         R"(bad\.json: bounds: duplicate field 'min')"},
        {"duplicate key deep inside",
         R"({"format": "hapto-scene", "version": 1, "objects": [], "x": [[1, {"a": 1}], [2, {"b": 1, "b": 2}]]})",
         R"(bad\.json: x\[1\]\[1\]: duplicate field 'b')"},
        {"object reaching past the largest double",
         withObject(
             R"({"id": 1, "shape": "box", "center": [0, 1.7e308, 0], "half_extents": [1e308, 1, 1]})"),
         R"(objects\[1\]: the object reaches past the largest finite coordinate)"},
    };
    for (const Case& c : cases) {
        INFO(c.name);
        const std::string message = errorOf(c.text);
        INFO(message);
        CHECK(std::regex_search(message, std::regex(c.expected)));
    }
}

TEST_CASE("a deeply nested wrong value is named by its type, not printed") {
    // The message used to dump() the value, which recurses once per level: 12000 levels
    // overflowed the stack under ASan (corpus crash-deep-version-dump.json).
    const std::string deep = std::string(12000, '[') + std::string(12000, ']');
    CHECK(errorOf(R"({"format": "hapto-scene", "version": )" + deep + R"(, "objects": []})") ==
          "bad.json: version: this build reads versions 1 to 3, got an array");
    CHECK(errorOf(R"({"format": )" + deep + R"(, "version": 1, "objects": []})") ==
          "bad.json: format: expected \"hapto-scene\", got an array");
    CHECK(errorOf(R"({"format": "hapto-scene", "version": 1.5, "objects": []})") ==
          "bad.json: version: this build reads versions 1 to 3, got 1.5");
}

TEST_CASE("a missing file is named in the message") {
    CHECK_THROWS_WITH(loadSceneFile("/nonexistent/scene.json"),
                      Catch::Contains("/nonexistent/scene.json") && Catch::Contains("cannot open"));
}

TEST_CASE("the same key in two different objects is no duplicate") {
    const Scene s = parseScene(
        R"({"format": "hapto-scene", "version": 1, "objects": [
            {"id": 1, "shape": "sphere", "center": [0,0,0], "radius": 1, "stiffness": 900},
            {"id": 2, "shape": "sphere", "center": [0,0,0], "radius": 1, "stiffness": 1e6}]})",
        "ok.json");
    REQUIRE(s.size() == 2);
    CHECK(s.object(1).material.stiffness == 1e6); // the limit itself is allowed
}

TEST_CASE("an object with many fields is checked for duplicates past the short list") {
    std::string fields;
    for (int i = 0; i < 100; ++i) {
        fields += "\"k" + std::to_string(i) + "\": 1, ";
    }
    const std::string text = R"({"format": "hapto-scene", "version": 1, "objects": [], "x": {)" +
                             fields + R"("k7": 2}})";
    CHECK(errorOf(text) == "bad.json: x: duplicate field 'k7' (each field may appear once; JSON "
                           "readers differ on which copy they keep)");
    // Without the repeat only the unknown top-level field is refused.
    const std::string ok = R"({"format": "hapto-scene", "version": 1, "objects": [], "x": {)" +
                           fields + R"("k100": 2}})";
    CHECK_THAT(errorOf(ok), Catch::Contains("unknown field 'x'"));
}

namespace {

std::string loadError(const std::filesystem::path& path) {
    try {
        loadSceneFile(path);
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

} // namespace

TEST_CASE("special files are refused at once, naming what they are") {
    test::TempDir dir;
    CHECK(loadError(dir.path()) ==
          dir.path().string() +
              ": is a directory, not a regular file (give the scene file as a file on disk)");

    // A FIFO with no writer: opening it for reading would block; it must be refused at once.
    const auto fifo = dir / "scene.fifo";
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    CHECK_THAT(loadError(fifo),
               Catch::StartsWith(fifo.string() + ": is a FIFO, not a regular file"));

    CHECK_THAT(loadError("/dev/zero"),
               Catch::StartsWith("/dev/zero: is a character device, not a regular file"));

    // A process substitution: /dev/fd/N naming a pipe, here with a writer that never ends.
    int fds[2];
    REQUIRE(::pipe(fds) == 0);
    const std::string byFd = "/dev/fd/" + std::to_string(fds[0]);
    CHECK_THAT(loadError(byFd), Catch::StartsWith(byFd + ": is a FIFO, not a regular file"));
    ::close(fds[0]);
    ::close(fds[1]);

    // A socket cannot even be opened; it is still named for what it is.
    const auto sock = dir / "s.sock";
    const int sfd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    REQUIRE(sfd >= 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", sock.c_str());
    if (sock.string().size() < sizeof addr.sun_path &&
        ::bind(sfd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0) {
        CHECK_THAT(loadError(sock), Catch::StartsWith(sock.string() + ": is a socket"));
    }
    ::close(sfd);

    // A symbolic link to a regular file is followed.
    const auto real = dir / "real.json";
    test::writeFile(real, R"({"format": "hapto-scene", "version": 1, "objects": []})");
    std::filesystem::create_symlink(real, dir / "link.json");
    CHECK(loadSceneFile(dir / "link.json").size() == 0);
}

TEST_CASE("input files are read whole up to a size limit, and refused above it") {
    test::TempDir dir;
    const auto path = dir / "ten.txt";
    test::writeFile(path, "0123456789");
    CHECK(InputFile(path, "test file", 10).readAll() == "0123456789");
    CHECK(InputFile(path, "test file").size() == 10);
    CHECK_THROWS_WITH(InputFile(path, "test file", 9),
                      Catch::StartsWith(path.string() + ": the test file is 10 bytes, more than "
                                                        "the 9 bytes limit for input files"));
    // Files that report size 0 (as /proc does) are still read to their end.
    CHECK_THAT(InputFile("/proc/self/status", "test file").readAll(), Catch::Contains("Name:"));
    CHECK(kMaxInputFileBytes == std::uint64_t(4) << 30);
}

TEST_CASE("a NUL byte in a JSON scene is named with its line, column and byte") {
    // Before, nlohmann stopped at the NUL: "1:1: ... unexpected end of input".
    const std::string text = std::string("{\"format\": \"hapto-scene\",\n  ") + '\0' +
                             "\"version\": 1, \"objects\": []}";
    CHECK(errorOf(text) == "bad.json:2:3: not valid JSON: a NUL byte (byte 28); a scene file is "
                           "JSON text or a binary hapto scene (HAPTOSCN)");
    // A whole scene before the NUL: the parser took the NUL for the end and ignored the rest.
    CHECK(errorOf(std::string(R"({"format": "hapto-scene", "version": 1, "objects": []})") + '\0' +
                  "anything") ==
          "bad.json:1:55: not valid JSON: a NUL byte (byte 54); a scene file is JSON text or a "
          "binary hapto scene (HAPTOSCN)");
}

TEST_CASE("a 2 GB scene file of zeros is refused from its first bytes, not read whole") {
    // Before, it was read whole (2.1 GB) and refused as "1:1: unexpected end of input".
    test::TempDir dir;
    const auto path = dir / "zeros.json";
    test::writeFile(path, "");
    std::filesystem::resize_file(path, std::uint64_t(2) << 30);
    rusage before{};
    getrusage(RUSAGE_SELF, &before);
    CHECK(loadError(path) == path.string() +
                                 ":1:1: not valid JSON: a NUL byte (byte 0); a scene file is JSON "
                                 "text or a binary hapto scene (HAPTOSCN)");
    rusage after{};
    getrusage(RUSAGE_SELF, &after);
    CHECK(after.ru_maxrss - before.ru_maxrss < 64 * 1024); // KiB: less than 64 MiB more
}

TEST_CASE("InputFile reads a file's head without moving where readAll starts") {
    test::TempDir dir;
    const auto path = dir / "ten.txt";
    test::writeFile(path, "0123456789");
    InputFile file(path, "test file");
    CHECK(file.readHead(4) == "0123");
    CHECK(file.readHead(40) == "0123456789");
    CHECK(file.readAll() == "0123456789");
    // A path holding a NUL byte is refused, not cut short at it.
    const std::string nul = (dir / "ten.txt").string() + std::string(1, '\0') + ".json";
    CHECK_THROWS_WITH(InputFile(nul, "test file"),
                      Catch::Contains("ten.txt\\0.json: a NUL byte (\\0) in the test file's path"));
}
