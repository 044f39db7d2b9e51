#pragma once
/// Scene files: the versioned JSON format "hapto-scene" (documented in docs/guide/scenes.md).

#include "hapto/scenes/Scene.h"

#include <filesystem>
#include <string>
#include <string_view>

namespace hapto {

/// The newest scene file format version this build reads and writes: 3, which adds dynamic
/// bodies (`"dynamic": true`, mass, inertia, restitution, initial velocities) and the scene's
/// `"gravity"` and `"dynamics"`. Version 2 added mesh objects (`"shape": "mesh"`); version 1 and
/// 2 files still load unchanged.
inline constexpr int kSceneFormatVersion = 3;
/// The version a scene with meshes but nothing of version 3 is written as.
inline constexpr int kSceneFormatVersionWithMeshes = 2;
/// The version a scene without meshes is written as, so its file is byte-identical to what
/// builds before version 2 wrote.
inline constexpr int kSceneFormatVersionWithoutMeshes = 1;

/// The oldest version that holds the scene: 3 when an object is dynamic or has a restitution,
/// or the physics is not the default; else 2 when it has meshes; else 1. [any thread]
int sceneFormatVersionOf(const Scene& scene);

/// Loads a scene file, JSON or binary (BinaryScene.h; told apart by its magic, not its name).
/// Streams the objects, so 10^7 objects load in bounded extra memory.
/// Model files named by mesh objects are read relative to the scene file's folder (MeshFile.h).
/// Throws InputError naming the file and the JSON path (e.g. `objects[12].half_extents[1]`) on
/// any bad input, and for a bad model file the model file and its place too (`objects[3].file:
/// m.obj:12: vertex index 9 is out of range ...`); never returns a partial scene. [control]
Scene loadSceneFile(const std::filesystem::path& path);

/// Parses scene JSON text; `sourceName` names it in messages, and model files are read
/// relative to `baseDir` (the current folder when empty). Throws InputError. [control]
Scene parseScene(std::string_view text, std::string_view sourceName,
                 const std::filesystem::path& baseDir = {});

/// parseScene without its simdjson fast path: the checked (nlohmann) loader alone, which gives
/// every refusal's message and reads mesh scenes. The same scenes and messages as parseScene;
/// for the tests and the fuzzer that hold the two to that. [control]
Scene parseSceneChecked(std::string_view text, std::string_view sourceName,
                        const std::filesystem::path& baseDir = {});

/// Writes the scene as JSON, every field explicit; the same scene gives the same bytes, in the
/// version sceneFormatVersionOf gives (a dynamic body with its mass and full inertia tensor, so
/// it reads back to the same values bit for bit). A mesh from a model file
/// by its file (as the scene that loaded it named it, so the scene must be written to the same
/// folder or the path must be absolute) and scale; any other mesh inline, its vertices as held
/// (scale applied) with scale 1. [control]
void saveSceneFile(const Scene& scene, const std::filesystem::path& path);

/// The JSON text `saveSceneFile` writes. [control]
std::string sceneToJson(const Scene& scene);

} // namespace hapto
