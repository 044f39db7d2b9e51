// Pins the simulated hand's plans: every script's keyframes (time, target, phase, smooth,
// pressing), loop start, object and contact normal on seeded scenes, folded into one FNV-1a
// hash per case. The figures were taken before SimScript::plan was split into parts; a
// refactor of the planner must leave them unchanged.

#include "TestMeshes.h"
#include "TestSupport.h"

#include "hapto/devices/SimScript.h"
#include "hapto/scenes/Generators.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <sstream>
#include <string>

using namespace hapto;
using test::Fnv;

namespace {

std::string planLine(const SimConfig& config, const Scene& scene, const Vec3& start) {
    const SimScript s = SimScript::plan(config, scene, start);
    Fnv f;
    for (const ScriptKeyframe& k : s.keyframes()) {
        f.add(k.timeS);
        f.add(k.target);
        f.add(std::uint64_t(k.phase));
        f.add(std::uint64_t(k.smooth) | std::uint64_t(k.pressing) << 1);
    }
    f.add(std::uint64_t(s.loopStart().value_or(~std::size_t(0))));
    f.add(std::uint64_t(s.object().value_or(~ObjectId(0))));
    f.add(s.contactNormal());
    std::ostringstream out;
    out << s.keyframes().size() << ' ' << std::hex << f.h;
    return out.str();
}

// A sparse random scene with a sphere and a wavy mesh sheet added, so every script has boxes,
// a sphere and triangles to choose from.
Scene planScene() {
    RandomOptions opt;
    opt.count = 40;
    opt.seed = 7;
    opt.keepClear = 0.04;
    const Scene random = makeRandomScene(opt);
    std::vector<SceneObject> objects(random.objects().begin(), random.objects().end());
    objects.push_back(makeSphere(1001, Vec3(0.06, -0.06, 0.05), 0.02));
    objects.push_back(
        makeMesh(1002, Vec3(-0.05, 0.0, -0.09), test::makeWavySheet(12, 0.08, 0.005)));
    return Scene(random.bounds(), std::move(objects));
}

std::string planLines() {
    const Scene scene = planScene();
    std::string out;
    for (const char* script : {"walk", "free", "touch", "slide", "grasp-left", "grasp-right"}) {
        for (const std::optional<std::uint32_t> object :
             {std::optional<std::uint32_t>(), std::optional<std::uint32_t>(1001),
              std::optional<std::uint32_t>(1002)}) {
            for (const std::uint64_t seed : {1, 9}) {
                SimConfig c;
                c.script = parseHandScript(script).value();
                c.seed = seed;
                c.object = object;
                const Vec3 start(0.01 * double(seed), 0.0, 0.0);
                out += std::string(script) + " object " +
                       (object ? std::to_string(*object) : std::string("-")) + " seed " +
                       std::to_string(seed) + " | " + planLine(c, scene, start) + "\n";
            }
        }
    }
    return out;
}

// clang-format off
const char* const kPinned = R"(walk object - seed 1 | 603 f1057c10dff5a3
walk object - seed 9 | 604 adf70c71415198e2
walk object 1001 seed 1 | 603 f1057c10dff5a3
walk object 1001 seed 9 | 604 adf70c71415198e2
walk object 1002 seed 1 | 603 f1057c10dff5a3
walk object 1002 seed 9 | 604 adf70c71415198e2
free object - seed 1 | 1201 f34bc6fd2ffc087d
free object - seed 9 | 1201 7677749653c96bd5
free object 1001 seed 1 | 1201 f34bc6fd2ffc087d
free object 1001 seed 9 | 1201 7677749653c96bd5
free object 1002 seed 1 | 1201 f34bc6fd2ffc087d
free object 1002 seed 9 | 1201 7677749653c96bd5
touch object - seed 1 | 4 1b40515bc90b7d3a
touch object - seed 9 | 4 82d85d5fa556e434
touch object 1001 seed 1 | 4 b84cb0fcb749777c
touch object 1001 seed 9 | 4 f7367069e31a1d3
touch object 1002 seed 1 | 4 42d83040c667c463
touch object 1002 seed 9 | 4 48d06ae8ae2b27de
slide object - seed 1 | 6 56e6c9b6828ed5ad
slide object - seed 9 | 6 a593359149d9ba9a
slide object 1001 seed 1 | 75 b66d488806e2c20f
slide object 1001 seed 9 | 75 1adddcdcade6e27b
slide object 1002 seed 1 | 6 853571371f3dba79
slide object 1002 seed 9 | 6 93abb9635356c553
grasp-left object - seed 1 | 11 be79c7b1d6e4baaf
grasp-left object - seed 9 | 10 c0b7f8f60aa3bcef
grasp-left object 1001 seed 1 | 10 c1fdcf7d3ac98f28
grasp-left object 1001 seed 9 | 11 63f6adfb44f4f3bf
grasp-left object 1002 seed 1 | 10 b15f25d0bf5fc3d6
grasp-left object 1002 seed 9 | 11 6d7ed7a9c4d93f1c
grasp-right object - seed 1 | 10 cff7b41929844fe9
grasp-right object - seed 9 | 10 2683f2e0a63bbd46
grasp-right object 1001 seed 1 | 10 eb992191a9a165ce
grasp-right object 1001 seed 9 | 10 1755804f6b482e71
grasp-right object 1002 seed 1 | 11 6927016cd1a99033
grasp-right object 1002 seed 9 | 10 cbc1dd7e0ae7d099
)";
// clang-format on

} // namespace

TEST_CASE("sim scripts: every script plans the pinned keyframes on a seeded scene") {
    CHECK(planLines() == kPinned);
}
