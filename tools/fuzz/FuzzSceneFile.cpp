// libFuzzer target: the scene file loader. Any input either loads or is refused with an
// InputError; nothing else may escape, crash, hang or leak; and its simdjson fast path gives
// the checked loader's answer (the same scene or the same message) on every input.

#include "hapto/io/InputError.h"
#include "hapto/scenes/SceneFile.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace {

/// What the checked loader alone makes of the text: the scene's JSON, or the message.
std::string checkedOutcome(std::string_view text) {
    try {
        return hapto::sceneToJson(hapto::parseSceneChecked(text, "fuzz.json"));
    } catch (const hapto::InputError& e) {
        return std::string("refused: ") + e.what();
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view input(reinterpret_cast<const char*>(data), size);
    const std::string checked = checkedOutcome(input);
    try {
        const hapto::Scene scene = hapto::parseScene(input, "fuzz.json");
        // The simdjson fast path and the checked loader agree on every input.
        if (hapto::sceneToJson(scene) != checked) {
            __builtin_trap();
        }
        // A scene that loaded must write back and load again to the same thing: equal objects
        // (a mesh object compares its mesh by identity, so meshes by the text written), and
        // the same text written again.
        const std::string text = hapto::sceneToJson(scene);
        const hapto::Scene again = hapto::parseScene(text, "again.json");
        if (hapto::sceneToJson(again) != text ||
            (scene.triangleCount() == 0 && !(again == scene))) {
            __builtin_trap();
        }
    } catch (const hapto::InputError& e) {
        if (checked != std::string("refused: ") + e.what()) {
            __builtin_trap();
        }
    }
    return 0;
}
