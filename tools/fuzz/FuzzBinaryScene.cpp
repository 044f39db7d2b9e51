// libFuzzer target: the binary scene reader. Any input either loads or is refused with an
// InputError; nothing else may escape, crash, hang or leak, and a header's counts never make it
// allocate more than the input holds.

#include "hapto/io/InputError.h"
#include "hapto/scenes/BinaryScene.h"
#include "hapto/scenes/SceneFile.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        const hapto::Scene scene = hapto::parseBinaryScene(
            std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.hsb");
        // A scene that loaded holds only valid values: written again it reads back to the same
        // bytes, and its JSON reads back with the JSON loader to the same JSON.
        const std::string bytes = hapto::sceneToBinary(scene);
        const hapto::Scene again = hapto::parseBinaryScene(bytes, "again.hsb");
        const std::string json = hapto::sceneToJson(again);
        if (hapto::sceneToBinary(again) != bytes ||
            hapto::sceneToJson(hapto::parseScene(json, "again.json")) != json) {
            __builtin_trap();
        }
    } catch (const hapto::InputError&) {
    }
    return 0;
}
