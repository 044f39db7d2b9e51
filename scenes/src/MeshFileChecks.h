#pragma once
/// The checks made on a model file's bytes before assimp reads them: the bad input assimp 5.2.5
/// lets through, mangles or crashes on, refused with the place (line, byte, element).

#include <string>
#include <string_view>

namespace hapto::detail {

/// The model formats hapto reads.
enum class MeshFormat { Obj, Stl, Ply };

/// Checks a Wavefront OBJ text: every `v` has finite x y z (and a finite, non-zero w), every
/// `f` has at least three vertices whose indices (1-based, or negative relative to the vertices
/// so far) name an existing `v` (and `vt`, `vn`), no NUL byte, at most the triangle and vertex
/// limits. Throws InputError "NAME:LINE: what". [control]
void checkObj(std::string_view text, const std::string& name);

/// Checks an STL file, ASCII or binary (told apart as assimp does: binary when its size is
/// 84 + 50 n for the header's count n): a binary file's size and count, every vertex finite
/// (naming its byte), at most the triangle limit; an ASCII file's facets of three finite
/// vertices (naming the line). Throws InputError. [control]
void checkStl(std::string_view bytes, const std::string& name);

/// Checks a PLY file (ASCII, binary little or big endian) whole: the header, a `vertex` element
/// with x, y, z, a `face` element with a `vertex_indices` list, every element the header
/// declares present and nothing after them, every vertex finite, every face with at least
/// three indices in range (naming the element and its line or byte). Throws InputError.
/// [control]
void checkPly(std::string_view bytes, const std::string& name);

} // namespace hapto::detail
