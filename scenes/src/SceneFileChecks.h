#pragma once
/// The checks every scene reader makes on an object's values and on the scene as a whole, one
/// home for the JSON loader (SceneFile.cpp) and the binary reader (BinaryScene.cpp), so both
/// refuse the same scenes with the same words. Each names the place through a json::Source and
/// json::Path and throws InputError. All [control].

#include "hapto/io/JsonInput.h"
#include "hapto/scenes/Scene.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hapto::detail {

/// A box's half extent on one axis: > 0 (m).
double checkHalfExtent(const json::Source& s, double v, const json::Path& path);
/// A sphere's radius: > 0 (m).
double checkRadius(const json::Source& s, double v, const json::Path& path);
/// A mesh's uniform scale: > 0.
double checkMeshScale(const json::Source& s, double v, const json::Path& path);
/// A stiffness: 0 < k <= Material::kMaxStiffness (N/m).
double checkStiffness(const json::Source& s, double v, const json::Path& path);
/// Friction [static, dynamic]: each in 0..Material::kMaxFriction, dynamic <= static.
void checkFriction(const json::Source& s, double staticMu, double dynamicMu,
                   const json::Path& path);
/// The object's bounding box must be finite: its finite centre plus its reach (a sphere's
/// radius, a box's summed half extents, a mesh's bounding radius) on every axis.
void checkReach(const json::Source& s, const SceneObject& o, const json::Path& path);
/// Explicit bounds: min < max on every axis and every size finite.
void checkBounds(const json::Source& s, const Aabb& b, const json::Path& path);
/// No two objects share an id (the second named, and the first's place). `objectsPath` is the
/// objects' array.
void checkUniqueIds(const json::Source& s, std::span<const SceneObject> objects,
                    const json::Path& objectsPath);
/// The scene from its checked objects (checkUniqueIds first): every object within a finite
/// span of the bounds, and default bounds (when `bounds` is empty) that can be padded around
/// the objects.
Scene finishScene(const json::Source& s, std::vector<SceneObject> objects,
                  const std::optional<Aabb>& bounds, const json::Path& objectsPath);

/// The version-3 fields of one object, as a file gave them (each value already read as a
/// finite number), before any check.
struct BodyFields {
    std::optional<bool> dynamic;                  ///< "dynamic"
    std::optional<double> massKg;                 ///< "mass_kg"
    std::optional<double> densityKgPerM3;         ///< "density_kg_per_m3"
    std::optional<std::array<double, 9>> inertia; ///< "inertia", row-major 3x3
    bool inertiaPrincipal = false;                ///< "inertia" was 3 principal moments
    std::optional<double> restitution;            ///< "restitution"
    std::optional<Vec3> velocity;                 ///< "velocity" (m/s)
    std::optional<Vec3> angularVelocity;          ///< "angular_velocity" (rad/s)
};
/// An object's version-3 keys (the first given is the one a version check names).
inline constexpr std::array<const char*, 7> kBodyKeys = {
    "dynamic",     "mass_kg",  "density_kg_per_m3", "inertia",
    "restitution", "velocity", "angular_velocity"};
/// The scene's version-3 top-level keys.
inline constexpr std::array<const char*, 2> kPhysicsKeys = {"gravity", "dynamics"};
/// Refuses a version-3 field (`fieldPath`, named `key`) in a file of an older version.
[[noreturn]] void refuseBeforeVersion3(const json::Source& s, const json::Path& fieldPath,
                                       const char* key);
/// Checks an object's version-3 fields and applies them to `o` (its shape, size and mesh
/// already read): mass or density (exactly one, dynamic only), inertia (3 positive principal
/// moments or a symmetric positive definite 3x3, either obeying the triangle inequality),
/// restitution in [0, 1], velocities within BodyProperties' limits; then the mass properties
/// (MassProperties.h) and a mesh's hull.
void applyBodyFields(const json::Source& s, SceneObject& o, const BodyFields& f,
                     const json::Path& path);
/// The scene's physics from its "gravity" (|g| <= ScenePhysics::kMaxGravity) and
/// "dynamics"."rate_hz" (kMinRateHz..kMaxRateHz), defaults where not given; `top` is the root.
ScenePhysics checkPhysics(const json::Source& s, const std::optional<Vec3>& gravity,
                          const std::optional<double>& rateHz, const json::Path& top);

/// An inline mesh at `path` from its vertices (before `scale`) and triangles: every scaled
/// vertex finite, every index in range (an index equal to `farMark` is reported as `farValue`
/// when that is given: the JSON loader's mark for an index too large for 32 bits), then
/// TriangleMesh::make's checks.
std::shared_ptr<const TriangleMesh> makeInlineMesh(const json::Source& s, const json::Path& path,
                                                   std::vector<Vec3> vertices,
                                                   std::vector<TriangleIndices> triangles,
                                                   double scale, std::uint32_t farMark,
                                                   std::optional<std::int64_t> farValue);

/// The model files a scene has read, by (file as named, scale): a file placed twice at one
/// scale is read once and shared.
using ModelCache = std::map<std::pair<std::string, double>, std::shared_ptr<const TriangleMesh>>;
/// The model `file` (relative to `baseDir` unless absolute) at `scale`, read once per cache.
/// Throws loadMeshFile's InputError, for the caller to place.
std::shared_ptr<const TriangleMesh> loadModel(ModelCache& models,
                                              const std::filesystem::path& baseDir,
                                              const std::string& file, double scale);

/// The JSON loader's fast path (SceneJsonFast.cpp): the scene when simdjson reads `text` as a
/// box-and-sphere scene every check accepts, else nothing (the checked loader then reads it).
/// `capacity` is how many bytes may be read at `text` (simdjson reads up to 64 past the end;
/// the text is copied when there is not that much room).
std::optional<Scene> parseSceneFast(std::string_view text, std::size_t capacity,
                                    std::string_view sourceName);

} // namespace hapto::detail
