#pragma once
/// The checks made on a model file's bytes before assimp reads them: the bad input assimp 5.2.5
/// lets through, mangles or crashes on, refused with the place (line, byte, element).

#include <cstdint>
#include <string>
#include <string_view>

namespace hapto::detail {

/// The model formats hapto reads.
enum class MeshFormat { Obj, Stl, Ply };

/// What the checks say of every vertex coordinate: finite, within a 32-bit float (assimp reads
/// coordinates as float, so 1e39 would become infinite), and, times the model's scale, within
/// TriangleMesh::kMaxCoordinate; named with its place like every other refusal.

/// The most vertices one face may have: assimp's AI_MAX_FACE_INDICES (assimp/mesh.h, 0x7fff),
/// past which its ValidateDataStructure step refuses the face without a line.
inline constexpr std::uint64_t kMaxFaceVertices = 0x7fff;

/// Refuses a model file from its first bytes and its size, before it is read whole: an STL
/// that is neither ASCII (begins with 'solid') nor binary of a size matching its header's count
/// (84 + 50 n bytes, n within the triangle limit); an OBJ with a NUL byte in `head`; a PLY with
/// a NUL byte before its header ends. `head` is the file's first bytes (the whole file when it
/// is that short), `size` its size in bytes. Throws InputError. [control]
void checkHead(MeshFormat format, std::string_view head, std::uint64_t size,
               const std::string& name);

/// Blanks every OBJ comment (from '#' to the end of its line, or to a NUL byte, which checkObj
/// then refuses) with spaces, so assimp 5.2.5, which reads a '#' after a face's indices as
/// another index, reads the file as the specification does; lines and byte offsets stay as
/// they were. Called before checkObj, so both read the same text. [control]
void blankObjComments(std::string& text);

/// Checks a Wavefront OBJ text: every `v` has x y z (and a w, non-zero as a float) whose
/// coordinates pass the checks above at `scale`, every `f` has 3 to kMaxFaceVertices vertices
/// whose indices (1-based, or negative relative to the vertices so far) name an existing `v`
/// (and `vt`, `vn`), no NUL byte, vertical tab, form feed or lone carriage return, at most the
/// triangle and vertex limits. Throws InputError "NAME:LINE: what". [control]
void checkObj(std::string_view text, const std::string& name, double scale);

/// Checks an STL file, ASCII or binary (told apart as assimp does: binary when its size is
/// 84 + 50 n for the header's count n): a binary file's size and count, every vertex's
/// coordinates (naming its byte), at most the triangle limit; an ASCII file's facets of three
/// vertices whose coordinates pass (naming the line). Throws InputError. [control]
void checkStl(std::string_view bytes, const std::string& name, double scale);

/// Checks a PLY file (ASCII, binary little or big endian) whole: the header (no blank line), a
/// `vertex` element with x, y, z, a `face` element with a `vertex_indices` list, every element
/// the header declares present and nothing after them, every vertex's coordinates, every face
/// with 3 to kMaxFaceVertices indices in range (naming the element and its line or byte).
/// Throws InputError. [control]
void checkPly(std::string_view bytes, const std::string& name, double scale);

} // namespace hapto::detail
