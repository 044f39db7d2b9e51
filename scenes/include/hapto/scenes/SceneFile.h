#pragma once
/// Scene files: the versioned JSON format "hapto-scene" (documented in README.md).

#include "hapto/scenes/Scene.h"

#include <filesystem>
#include <string>
#include <string_view>

namespace hapto {

/// The scene file format version this build reads and writes.
inline constexpr int kSceneFormatVersion = 1;

/// Loads a scene file. Streams the objects, so 10^7 objects load in bounded extra memory.
/// Throws InputError naming the file and the JSON path (e.g. `objects[12].half_extents[1]`) on
/// any bad input; never returns a partial scene. [control]
Scene loadSceneFile(const std::filesystem::path& path);

/// Parses scene JSON text; `sourceName` names it in messages. Throws InputError. [control]
Scene parseScene(std::string_view text, std::string_view sourceName);

/// Writes the scene as JSON, every field explicit; the same scene gives the same bytes. [control]
void saveSceneFile(const Scene& scene, const std::filesystem::path& path);

/// The JSON text `saveSceneFile` writes. [control]
std::string sceneToJson(const Scene& scene);

} // namespace hapto
