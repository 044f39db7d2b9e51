// libFuzzer target: the scene file loader. Any input either loads or is refused with an
// InputError; nothing else may escape, crash, hang or leak.

#include "hapto/scenes/InputError.h"
#include "hapto/scenes/SceneFile.h"

#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        const hapto::Scene scene = hapto::parseScene(
            std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.json");
        // A scene that loaded must write back and load again to the same thing.
        if (!(hapto::parseScene(hapto::sceneToJson(scene), "again.json") == scene)) {
            __builtin_trap();
        }
    } catch (const hapto::InputError&) {
    }
    return 0;
}
