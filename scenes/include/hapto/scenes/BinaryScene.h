#pragma once
/// The binary scene file: the same scenes as the JSON format, for large scenes that must load at
/// disk speed (`hapto scene convert` writes it; every --scene reads it, told apart by its magic).
///
/// Little-endian throughout, fixed-size fields, no implicit padding. This build reads and writes
/// version 1. Header, 96 bytes:
///
///   offset size  field
///        0    8  magic "HAPTOSCN"
///        8    4  u32 version (kBinarySceneVersion = 1)
///       12    4  u32 header size in bytes (96)
///       16    4  u32 object record size in bytes (112)
///       20    4  u32 flags (0; reserved)
///       24    8  u64 object count N (at most 2^32 - 1, and the file must hold them)
///       32    8  u64 mesh section size in bytes M
///       40   24  3 x f64 bounds min (m)
///       64   24  3 x f64 bounds max (m)
///       88    8  zero (reserved)
///
/// The file is exactly 96 + 112 N + M bytes. Then N object records of 112 bytes, in slot order:
///
///        0    4  u32 id (at most kMaxObjectId; unique in the scene)
///        4    1  u8 shape: 0 box, 1 sphere, 2 mesh
///        5    3  zero
///        8   24  3 x f64 centre (m)
///       32   24  3 x f64 half extents (m): a box's, a sphere's radius thrice, zero for a mesh
///       56   32  4 x f64 rotation, unit quaternion (w, x, y, z)
///       88    8  f64 stiffness (N/m)
///       96   16  2 x f64 friction: static, dynamic coefficient
///
/// Then the mesh section: one entry per mesh object, in slot order, not padded:
///
///        0    4  u32 kind: 0 a model file, 1 inline vertices and triangles
///        4    4  zero
///        8    8  f64 scale (> 0)
///   kind 0:
///       16    8  u64 path length L (1..4096)
///       24    L  the model file's path, as the JSON format's "file": relative to the scene
///                file's folder unless absolute
///   kind 1:
///       16    8  u64 vertex count V (at most TriangleMesh::kMaxVertices)
///       24    8  u64 triangle count T (at most TriangleMesh::kMaxTriangles)
///       32  24V  V x (3 x f64) vertices (m, before the scale)
///   32+24V  12T  T x (3 x u32) vertex indices
///
/// Meshes follow the JSON format: a mesh from a model file is a reference to that file (the
/// model formats are compact binary already, and one model placed many times is read once),
/// any other mesh is inline. Every value is checked on read with the JSON loader's own checks
/// (SceneFileChecks.h), so both formats accept the same scenes; a refusal names the file, the
/// byte offset of the header field, object record or mesh entry, and the JSON path of the
/// value ("s.hsb: byte 208: objects[1].half_extents[2]: a half extent must be > 0 (got 0)").
/// A 10^6-object scene is 112 MB.

#include "hapto/scenes/Scene.h"

#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>
#include <string_view>

namespace hapto {

/// The first 8 bytes of every binary scene file.
inline constexpr std::string_view kBinarySceneMagic{"HAPTOSCN", 8};
/// The binary scene format version this build reads and writes.
inline constexpr std::uint32_t kBinarySceneVersion = 1;
/// Header size (bytes).
inline constexpr std::uint32_t kBinarySceneHeaderBytes = 96;
/// Object record size (bytes).
inline constexpr std::uint32_t kBinarySceneRecordBytes = 112;

/// True when `bytes` start with the binary scene magic. [any thread]
bool isBinaryScene(std::string_view bytes);

/// Reads a binary scene; `sourceName` names it in messages, and model files are read relative
/// to `baseDir` (the current folder when empty). Checks the header, every size against the
/// file's size before allocating, every value as the JSON loader does. Throws InputError
/// naming the file, the byte offset and the JSON path; never returns a partial scene.
/// [control]
Scene parseBinaryScene(std::string_view bytes, std::string_view sourceName,
                       const std::filesystem::path& baseDir = {});

/// Writes the scene in the binary format; the same scene gives the same bytes. Meshes as the
/// JSON writer writes them: a mesh from a model file by its file (so the scene must be written
/// to the same folder or the path must be absolute) and scale; any other mesh inline, its
/// vertices as held (scale applied) with scale 1. A scene that needs JSON version 3 (dynamic
/// bodies, restitution, non-default physics: sceneFormatVersionOf) is refused with an
/// InputError before anything is written. [control]
void writeBinaryScene(const Scene& scene, std::ostream& out);

/// The bytes writeBinaryScene writes. [control]
std::string sceneToBinary(const Scene& scene);

} // namespace hapto
