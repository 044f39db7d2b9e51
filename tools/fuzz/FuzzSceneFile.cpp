// libFuzzer target: the scene file loader. Any input either loads or is refused with an
// InputError; nothing else may escape, crash, hang or leak.

#include "hapto/scenes/InputError.h"
#include "hapto/scenes/SceneFile.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        const hapto::Scene scene = hapto::parseScene(
            std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.json");
        // A scene that loaded must write back and load again to the same thing: equal objects
        // (a mesh object compares its mesh by identity, so meshes by the text written), and
        // the same text written again.
        const std::string text = hapto::sceneToJson(scene);
        const hapto::Scene again = hapto::parseScene(text, "again.json");
        if (hapto::sceneToJson(again) != text ||
            (scene.triangleCount() == 0 && !(again == scene))) {
            __builtin_trap();
        }
    } catch (const hapto::InputError&) {
    }
    return 0;
}
