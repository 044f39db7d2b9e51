#pragma once
/// Model files: OBJ, STL (ASCII and binary) and PLY (ASCII and binary) read into a TriangleMesh.

#include "hapto/scenes/TriangleMesh.h"

#include <filesystem>
#include <memory>
#include <string>

namespace hapto {

/// True when `path` names a model format hapto reads: its extension is .obj, .stl or .ply
/// (any case). [any thread]
bool isMeshFile(const std::filesystem::path& path);

/// Reads a model file into a mesh, every coordinate multiplied by `source.scale` (the file's
/// units times the scale must give metres). `path` is where to open it; `source.file` is how the
/// scene names it (kept for writing the scene back). Read in one pass by hapto's own reader
/// of each format (docs/DESIGN.md, "Model files"). Polygons are triangulated, points and lines
/// ignored, vertices at the same position merged (so triangles sharing an edge share its
/// vertex indices, across the file's groups and objects too), degenerate and duplicate
/// triangles dropped and counted (TriangleMesh::make). A file its first bytes and size refuse
/// (an STL neither ASCII nor of its header's size, a NUL byte in a text format) is refused
/// before it is read whole.
///
/// Throws InputError naming the file and, where the format has one, the place ("m.obj:12:
/// vertex index 9 is out of range (the file has 8 vertices)", "m.stl: byte 146: facet 1, vertex
/// 0: x is not finite (NaN)", "m.ply:14: face element 3: ...") for: a file that is missing,
/// unreadable or not a regular file (a folder, a FIFO...), an unknown extension, a file its
/// format's reader refuses, a vertex coordinate that is not finite, past a 32-bit float (as
/// which it is kept) or, times the scale, past TriangleMesh::kMaxCoordinate, a mesh less than
/// TriangleMesh::kMinSize across, an index out of range, a face of more than 32767 vertices, no
/// triangles, more than TriangleMesh::kMaxTriangles triangles. [control]
std::shared_ptr<const TriangleMesh> loadMeshFile(const std::filesystem::path& path,
                                                 MeshSource source);

/// What loadMeshFile does once the file is read: `bytes` are the file's contents, `path` names
/// it in messages and its extension gives the format. The same checks, the same messages (those
/// of opening a file aside). The fuzz target `mesh_file` drives it. [control]
std::shared_ptr<const TriangleMesh>
parseMeshFile(std::string bytes, const std::filesystem::path& path, MeshSource source);

} // namespace hapto
