#pragma once
/// What the three model readers (ObjReader.cpp, StlReader.cpp, PlyReader.cpp) share: the mesh
/// they produce, how they name a place and a problem, and how they read numbers and words.

#include "hapto/scenes/TriangleMesh.h"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace hapto::detail {

/// The coordinate names, by axis, for messages.
inline constexpr const char* kAxis[3] = {"x", "y", "z"};

/// The model formats hapto reads.
enum class MeshFormat { Obj, Stl, Ply };

/// The most vertices one face may have: 0x7fff, the limit assimp 5.2.5 (AI_MAX_FACE_INDICES in
/// assimp/mesh.h) put on a face when hapto read models with it, kept so the same files load.
inline constexpr std::uint64_t kMaxFaceVertices = 0x7fff;

/// A model as its file gives it, before scaling and welding: the positions (each coordinate
/// rounded to a 32-bit float, as the formats store them and as hapto has always read them) and
/// the faces, each a polygon of 3 to kMaxFaceVertices indices into `vertices`.
struct ModelFaces {
    std::vector<Vec3> vertices;
    std::vector<std::uint32_t> corners;   ///< Every face's vertex indices, face after face.
    std::vector<std::uint16_t> faceSizes; ///< How many of `corners` each face takes.
};

/// Throws InputError(what).
[[noreturn]] void fail(const std::string& what);
/// "NAME:LINE: "
std::string atLine(const std::string& name, std::size_t line);
/// "NAME: byte N: "
std::string atByte(const std::string& name, std::uint64_t byte);
/// The token in single quotes, cut after 40 characters.
std::string quoted(std::string_view token);

/// A number as text ("+1", "-2.5e3", "nan", "inf"); nullopt when it is not one. Out of range
/// values read as the infinity or zero they round to.
std::optional<double> parseNumber(std::string_view t);
/// A whole number as text; nullopt when it is not one (or does not fit 64 bits).
std::optional<std::int64_t> parseInteger(std::string_view t);
/// Space, tab, carriage return, vertical tab or form feed (not '\n', which ends a line).
bool isSpace(char c);
/// Splits a line into whitespace-separated tokens (into `out`, reused).
void tokens(std::string_view line, std::vector<std::string_view>& out);
/// Refuses a NUL byte in `text`, naming its byte: "a NUL byte: not WHAT".
void refuseNul(std::string_view text, const std::string& name, const char* what);

/// What is wrong with a number stored as a 32-bit float, or "": not finite, or past the
/// largest float. The text follows the number's name.
std::string floatProblem(double v);
/// What is wrong with a vertex coordinate `v` as the file gives it, or "": floatProblem, or,
/// times `scale`, farther than TriangleMesh::kMaxCoordinate from the origin.
std::string coordinateProblem(double v, double scale);
/// Refuses a face (or line, or point) of more than kMaxFaceVertices vertices.
void checkFaceSize(std::uint64_t vertices, const std::string& place, const char* what);
/// Refuses more than TriangleMesh::kMaxTriangles triangles.
void checkTriangleLimit(std::uint64_t triangles, const std::string& name);

/// Calls f(lineNumber, line) for every line of `text` (without its '\n').
template <class F> void forEachLine(std::string_view text, F&& f) {
    std::size_t line = 1;
    std::size_t start = 0;
    while (start < text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string_view::npos) {
            end = text.size();
        }
        f(line, text.substr(start, end - start));
        start = end + 1;
        ++line;
    }
}

/// Refuses an STL from its first bytes and its size, before it is read whole: neither ASCII
/// (begins with 'solid') nor binary of a size matching its header's count (84 + 50 n bytes, n
/// from 1 to the triangle limit). `head` is the file's first bytes (at least 84, or the whole
/// file), `size` its size in bytes. Throws InputError. [control]
void checkStlHead(std::string_view head, std::uint64_t size, const std::string& name);

/// Blanks every OBJ comment (from '#' to the end of its line, or to a NUL byte, which readObj
/// then refuses) with spaces; lines and byte offsets stay as they were. [control]
void blankObjComments(std::string& text);

/// Reads a Wavefront OBJ text: every `v` has x y z (and a w, non-zero as a float, dividing
/// them) whose coordinates pass the checks above at `scale`, every `f` has 3 to
/// kMaxFaceVertices vertices whose indices (1-based, or negative relative to the vertices so
/// far) name an existing `v` (and `vt`, `vn`), no NUL byte, vertical tab, form feed or lone
/// carriage return, at most the triangle and vertex limits. The model keeps the vertices that a
/// face, line or point names, and the faces. Throws InputError "NAME:LINE: what". [control]
ModelFaces readObj(std::string_view text, const std::string& name, double scale);

/// Reads an STL file, ASCII or binary (binary when its size is 84 + 50 n for the header's count
/// n): a binary file's size and count, every vertex's coordinates (naming its byte), at most the
/// triangle limit; an ASCII file's facets of three vertices whose coordinates pass (naming the
/// line). Normals are read past. Throws InputError. [control]
ModelFaces readStl(std::string_view bytes, const std::string& name, double scale);

/// Reads a PLY file (ASCII, binary little or big endian) whole: the header (no blank line), a
/// `vertex` element with x, y, z, a `face` element with a `vertex_indices` list, every element
/// the header declares present and nothing after them, every vertex's coordinates, every face
/// with 3 to kMaxFaceVertices indices in range (naming the element and its line or byte); other
/// elements and properties are read past. Throws InputError. [control]
ModelFaces readPly(std::string_view bytes, const std::string& name, double scale);

/// Where assimp 5.2.5's n-gon encoding rotated a triangle's corners (its first corner the same
/// vertex as the previous triangle's), in a mesh holding polygons: never (STL: triangles only),
/// within a face (OBJ, whose faces assimp gave corners of their own), across faces (PLY).
enum class NgonRotation { None, WithinFace, AcrossFaces };

/// The triangles of the model's faces, in face order: a triangle as it is, a quadrilateral cut
/// along the diagonal from its concave corner (if any), a larger polygon by ear cutting on its
/// projection, corners rotated as `rotation` says (PolygonTriangulation.cpp). [control]
std::vector<TriangleIndices> triangulate(const ModelFaces& model, NgonRotation rotation);

} // namespace hapto::detail
