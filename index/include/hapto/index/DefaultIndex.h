#pragma once
/// The index a scene gets when none is asked for: the rule, and the one named default spec.

#include "hapto/index/IndexSpec.h"
#include "hapto/scenes/Scene.h"

#include <cstdint>
#include <string>
#include <string_view>

namespace hapto {

/// The default index over boxes and spheres: the paper's modified octree, at most 2 objects per
/// leaf down to 5 mm leaves. Every "the default index" in hapto is this text.
inline constexpr std::string_view kDefaultIndexSpec = "octree:2:0.005";
/// The default octree over mesh triangles holds at most this many items per leaf above its
/// smallest leaf size.
inline constexpr int kMeshIndexLeafItems = 8;
/// The default octree's smallest leaf over mesh triangles is the median triangle's longest edge
/// kept within these bounds (m).
inline constexpr double kMeshIndexMinLeafM = 1e-4;
inline constexpr double kMeshIndexMaxLeafM = 5e-3; ///< See kMeshIndexMinLeafM.

/// The index `scene` gets when none is asked for, as text: kDefaultIndexSpec over boxes and
/// spheres; over mesh triangles an octree of at most kMeshIndexLeafItems items per leaf whose
/// smallest leaf is the scene's median triangle's longest edge (two significant digits, within
/// kMeshIndexMinLeafM to kMeshIndexMaxLeafM), so that a leaf of a fine scan holds a few
/// triangles rather than hundreds (docs/DESIGN.md, "The default index over meshes"). [any thread]
std::string defaultIndexSpec(const Scene& scene);
/// The index a session over `scene` builds: `given` (a spec's text, e.g. a command's `--index`)
/// or, when it is empty, defaultIndexSpec(scene); its build may take at most `maxMegabytes` MB.
/// Throws InputError for a bad `given`. [any thread]
IndexSpec sessionIndexSpec(std::string_view given, const Scene& scene,
                           std::uint64_t maxMegabytes = IndexSpec::kDefaultMaxMegabytes);

} // namespace hapto
