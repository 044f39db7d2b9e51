// The checks made on model files before assimp reads them. Design note: assimp 5.2.5 validates
// little of what it reads (see docs/DESIGN.md, "Model files"): it keeps NaN vertices (and
// its JoinIdenticalVertices merges them with unrelated ones), reads PLY face indices past the
// vertex array and crashes on a truncated binary PLY, cuts an STL facet of four vertices to a
// triangle, and names no line or byte in the errors it does find. So each format is walked
// once here, cheaply and without building anything, and the first bad thing is refused with its
// place; what gets through is read by assimp. The walks follow the format specifications,
// cited at each function.

#include "MeshFileChecks.h"

#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"
#include "hapto/scenes/TriangleMesh.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <optional>
#include <vector>

namespace hapto::detail {
namespace {

[[noreturn]] void fail(const std::string& what) {
    throw InputError(what);
}

std::string atLine(const std::string& name, std::size_t line) {
    return name + ":" + std::to_string(line) + ": ";
}

std::string atByte(const std::string& name, std::uint64_t byte) {
    return name + ": byte " + std::to_string(byte) + ": ";
}

std::string quoted(std::string_view token) {
    return "'" + std::string(token.substr(0, 40)) + (token.size() > 40 ? "...'" : "'");
}

/// A number as text ("+1", "-2.5e3", "nan", "inf"); nullopt when it is not one. Out of range
/// values read as the infinity or zero they round to.
std::optional<double> parseNumber(std::string_view t) {
    if (!t.empty() && t.front() == '+') {
        t.remove_prefix(1);
    }
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ptr != t.data() + t.size() || t.empty()) {
        return std::nullopt;
    }
    if (ec == std::errc::result_out_of_range) {
        const std::string copy(t);
        return std::strtod(copy.c_str(), nullptr);
    }
    if (ec != std::errc()) {
        return std::nullopt;
    }
    return v;
}

/// A whole number as text; nullopt when it is not one (or does not fit 64 bits).
std::optional<std::int64_t> parseInteger(std::string_view t) {
    if (!t.empty() && t.front() == '+') {
        t.remove_prefix(1);
    }
    std::int64_t v = 0;
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || ptr != t.data() + t.size() || t.empty()) {
        return std::nullopt;
    }
    return v;
}

bool isSpace(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/// Splits a line into whitespace-separated tokens (into `out`, reused).
void tokens(std::string_view line, std::vector<std::string_view>& out) {
    out.clear();
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSpace(line[i])) {
            ++i;
        }
        const std::size_t start = i;
        while (i < line.size() && !isSpace(line[i])) {
            ++i;
        }
        if (i > start) {
            out.push_back(line.substr(start, i - start));
        }
    }
}

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

void refuseNul(std::string_view text, const std::string& name, const char* what) {
    if (const void* p = std::memchr(text.data(), '\0', text.size())) {
        const auto at = static_cast<std::uint64_t>(static_cast<const char*>(p) - text.data());
        fail(atByte(name, at) + "a NUL byte: not " + what);
    }
}

/// What is wrong with a number assimp reads as a 32-bit float, or "": not finite, or past the
/// largest float (assimp would make it infinite). The text follows the number's name.
std::string floatProblem(double v) {
    if (!std::isfinite(v)) {
        return "is not finite";
    }
    if (std::abs(v) > std::numeric_limits<float>::max()) {
        return "is beyond the largest 32-bit float, 3.4e+38 (assimp reads coordinates as floats "
               "and would make it infinite)";
    }
    return "";
}

/// What is wrong with a vertex coordinate `v` as the file gives it, or "": floatProblem, or,
/// times `scale`, farther than TriangleMesh::kMaxCoordinate from the origin.
std::string coordinateProblem(double v, double scale) {
    if (std::string p = floatProblem(v); !p.empty()) {
        return p;
    }
    const double scaled = v * scale;
    if (!std::isfinite(scaled)) {
        return "times the scale " + json::show(scale) + " is not finite";
    }
    if (std::abs(scaled) > TriangleMesh::kMaxCoordinate) {
        return "times the scale " + json::show(scale) + " is " + json::show(scaled) +
               " m, beyond the " + json::show(TriangleMesh::kMaxCoordinate) +
               " m a mesh vertex may lie from its origin";
    }
    return "";
}

/// Refuses a face (or line, or point) of more vertices than assimp reads.
void checkFaceSize(std::uint64_t vertices, const std::string& place, const char* what) {
    if (vertices > kMaxFaceVertices) {
        fail(place + "a " + what + " of " + std::to_string(vertices) +
             " vertices; assimp reads at most " + std::to_string(kMaxFaceVertices) +
             " (split it into smaller polygons)");
    }
}

void checkTriangleLimit(std::uint64_t triangles, const std::string& name) {
    if (triangles > TriangleMesh::kMaxTriangles) {
        fail(name + ": more than " + std::to_string(TriangleMesh::kMaxTriangles) +
             " triangles; a mesh may have at most " + std::to_string(TriangleMesh::kMaxTriangles));
    }
}

// ---- OBJ ----------------------------------------------------------------------------------
// Wavefront OBJ, as in "Object Files (.obj)", Appendix B1 of the Advanced Visualizer manual
// (Wavefront Technologies): `v x y z [w]` (assimp also reads `v x y z r g b`), `vt`, `vn`,
// `f v1[/vt1][/vn1] v2... ` with 1-based indices or negative ones counting back from the last
// vertex defined so far; a line ending with '\' continues on the next one; '#' starts a comment.

struct ObjCounts {
    std::int64_t v = 0, vt = 0, vn = 0;
};

/// Calls f(firstLine, logicalLine) per logical line (continuations joined, comment cut).
template <class F> void forEachObjLine(std::string_view text, F&& f) {
    std::string joined;
    std::size_t joinedFrom = 0;
    forEachLine(text, [&](std::size_t line, std::string_view l) {
        if (!l.empty() && l.back() == '\r') {
            l.remove_suffix(1);
        }
        if (!l.empty() && l.back() == '\\') {
            if (joined.empty()) {
                joinedFrom = line;
            }
            joined.append(l.substr(0, l.size() - 1)).push_back(' ');
            return;
        }
        std::string_view logical = l;
        std::size_t from = line;
        if (!joined.empty()) {
            joined.append(l);
            logical = joined;
            from = joinedFrom;
        }
        if (const std::size_t hash = logical.find('#'); hash != std::string_view::npos) {
            logical = logical.substr(0, hash);
        }
        f(from, logical);
        joined.clear();
    });
    if (!joined.empty()) {
        f(joinedFrom, std::string_view(joined));
    }
}

void checkObjIndex(std::string_view token, std::string_view part, const char* what,
                   const char* plural, std::int64_t total, std::int64_t soFar,
                   const std::string& name, std::size_t line) {
    const auto place = [&] { return atLine(name, line); };
    const auto i = parseInteger(part);
    if (!i) {
        fail(place() + "'" + std::string(part) + "' in " + quoted(token) + " is not a " + what +
             " index (a whole number)");
    }
    if (*i == 0) {
        fail(place() + what + " index 0 in " + quoted(token) + ": indices start at 1");
    }
    if (*i > total) {
        fail(place() + what + " index " + std::to_string(*i) + " is out of range (the file has " +
             std::to_string(total) + " " + plural + ")");
    }
    if (*i < 0 && *i < -soFar) { // not -*i: INT64_MIN has no negation
        fail(place() + "relative " + what + " index " + std::to_string(*i) +
             " is out of range (only " + std::to_string(soFar) + " " + plural +
             " come before this line)");
    }
}

/// Refuses a line that assimp 5.2.5's OBJ reader would read otherwise than the specification:
/// it takes a statement from the line's first character, with no space skipped, so it drops an
/// indented `v` or `f` (shifting every index after it), reads any word that begins with `f`, `l`
/// or `p` as a face, line or point and one that begins with `vt` or `vn` as those, and takes a
/// vertex only when a space or a tab follows the `v`.
template <class Place>
void readAsAssimpDoes(std::string_view line, std::string_view key, const Place& place) {
    const bool geometry =
        key == "v" || key == "vt" || key == "vn" || key == "f" || key == "l" || key == "p";
    if (key.data() != line.data()) {
        if (geometry) {
            fail(place() + "an indented '" + std::string(key) +
                 "' statement (assimp skips a line that does not begin with its statement, "
                 "which would lose it): remove the indentation");
        }
        return;
    }
    if (!geometry && key != "vp" &&
        (key[0] == 'f' || key[0] == 'l' || key[0] == 'p' || key.starts_with("vt") ||
         key.starts_with("vn"))) {
        fail(place() + quoted(key) +
             " is not an OBJ geometry statement, but assimp would read it as one (a word "
             "beginning with f, l, p, vt or vn)");
    }
    if (key == "v" && line.size() > 1 && line[1] != ' ' && line[1] != '\t') {
        fail(place() + "'v' must be followed by a space or a tab");
    }
}

/// A `v` line's x y z [w], already read as numbers: each coordinate passes floatProblem, a
/// weight w is not 0 as a float (assimp divides x y z by it, in floats), and every x / w
/// passes coordinateProblem at `scale`.
template <class Place>
void checkObjVertex(const std::vector<std::string_view>& tok, double scale, const Place& place) {
    double w = 1.0;
    if (tok.size() == 5) {
        w = *parseNumber(tok[4]);
        if (const std::string p = floatProblem(w); !p.empty()) {
            fail(place() + "the vertex's weight w " + quoted(tok[4]) + " " + p);
        }
        if (static_cast<float>(w) == 0.0f) {
            fail(place() + "the vertex's weight w is 0" +
                 (w == 0.0 ? std::string() : " as a 32-bit float (" + quoted(tok[4]) + ")") +
                 " (x y z are divided by it)");
        }
    }
    for (std::size_t k = 1; k <= 3; ++k) {
        const double v = *parseNumber(tok[k]);
        std::string p = floatProblem(v);
        if (p.empty()) {
            p = coordinateProblem(v / w, scale);
            if (!p.empty() && tok.size() == 5) {
                p = "divided by the weight w " + quoted(tok[4]) + " " + p;
            }
        }
        if (!p.empty()) {
            fail(place() + "vertex coordinate " + quoted(tok[k]) + " " + p);
        }
    }
}

/// Refuses the characters assimp reads otherwise than the checks: it ends an OBJ line at a
/// carriage return or a form feed, so one inside a line would split its statement, and does
/// not take a vertical tab for a space, so one would join two words.
void checkObjCharacters(std::string_view text, const std::string& name) {
    for (std::size_t i = text.find_first_of("\r\f\v"); i != std::string_view::npos;
         i = text.find_first_of("\r\f\v", i + 1)) {
        if (text[i] != '\r' || (i + 1 < text.size() && text[i + 1] != '\n')) {
            const auto line = 1 + std::count(text.begin(), text.begin() + i, '\n');
            fail(atLine(name, static_cast<std::size_t>(line)) +
                 (text[i] == '\v'   ? "a vertical tab (assimp would not read it as a space but "
                                      "as part of a word; separate values with spaces or tabs)"
                  : text[i] == '\f' ? "a form feed inside a line (assimp would end the line "
                                      "there; lines end with \\n or \\r\\n)"
                                    : "a carriage return inside a line (assimp would end the "
                                      "line there; lines end with \\n or \\r\\n)"));
        }
    }
}

} // namespace

void blankObjComments(std::string& text) {
    for (std::size_t i = text.find('#'); i != std::string::npos; i = text.find('#', i)) {
        for (; i < text.size() && text[i] != '\n' && text[i] != '\r' && text[i] != '\0'; ++i) {
            text[i] = ' ';
        }
    }
}

void checkObj(std::string_view text, const std::string& name, double scale) {
    refuseNul(text, name, "an OBJ text file");
    checkObjCharacters(text, name);
    std::vector<std::string_view> tok;
    ObjCounts total;
    forEachObjLine(text, [&](std::size_t, std::string_view line) {
        tokens(line, tok);
        if (tok.empty()) {
            return;
        }
        total.v += tok[0] == "v";
        total.vt += tok[0] == "vt";
        total.vn += tok[0] == "vn";
    });
    if (total.v > static_cast<std::int64_t>(TriangleMesh::kMaxVertices)) {
        fail(name + ": " + std::to_string(total.v) + " vertices; a mesh may have at most " +
             std::to_string(TriangleMesh::kMaxVertices));
    }
    ObjCounts seen;
    std::uint64_t triangles = 0;
    forEachObjLine(text, [&](std::size_t lineNo, std::string_view line) {
        tokens(line, tok);
        if (tok.empty()) {
            return;
        }
        const auto place = [&] { return atLine(name, lineNo); };
        const std::string_view key = tok[0];
        readAsAssimpDoes(line, key, place);
        // x y z, x y z w or x y z r g b (assimp skips a vertex of any other count, which
        // shifts every index after it); u [v [w]] with v (assimp throws on one); i j k.
        const auto numbers = [&](std::initializer_list<std::size_t> counts, const char* forms) {
            const std::size_t n = tok.size() - 1;
            if (std::find(counts.begin(), counts.end(), n) == counts.end()) {
                fail(place() + "'" + std::string(key) + "' takes " + forms + ", got " +
                     std::to_string(n) + " numbers");
            }
            for (std::size_t k = 1; k < tok.size(); ++k) {
                const auto v = parseNumber(tok[k]);
                if (!v) {
                    fail(place() + quoted(tok[k]) + " is not a number");
                }
                // assimp counts the numbers of a v or vt only when they begin with a digit or
                // a sign (or are NaN or infinite): ".5" would make it one number short.
                const char c = tok[k][0];
                if (key != "vn" && std::isfinite(*v) && (c < '0' || c > '9') && c != '+' &&
                    c != '-') {
                    fail(place() + quoted(tok[k]) +
                         " does not begin with a digit or a sign (assimp would not count it; "
                         "write 0.5 for .5)");
                }
            }
        };
        if (key == "v") {
            numbers({3, 4, 6}, "x y z, x y z w or x y z r g b");
            checkObjVertex(tok, scale, place);
            ++seen.v;
        } else if (key == "vt") {
            numbers({2, 3}, "u v or u v w");
            ++seen.vt;
        } else if (key == "vn") {
            numbers({3}, "i j k");
            ++seen.vn;
        } else if (key == "f" || key == "l" || key == "p") {
            // Lines and points make no triangles, but assimp reads their indices too.
            const std::size_t least = key == "f" ? 3 : key == "l" ? 2 : 1;
            const char* what = key == "f" ? "face" : key == "l" ? "line" : "point";
            if (tok.size() < least + 1) {
                fail(place() + "a " + what + " needs at least " + std::to_string(least) +
                     " vertices, got " + std::to_string(tok.size() - 1));
            }
            checkFaceSize(tok.size() - 1, place(), what);
            for (std::size_t k = 1; k < tok.size(); ++k) {
                const std::string_view t = tok[k];
                const std::size_t s1 = t.find('/');
                checkObjIndex(t, t.substr(0, s1), "vertex", "vertices", total.v, seen.v, name,
                              lineNo);
                if (s1 == std::string_view::npos) {
                    continue;
                }
                const std::size_t s2 = t.find('/', s1 + 1);
                const std::string_view vt = t.substr(s1 + 1, s2 - (s1 + 1));
                if (!vt.empty()) {
                    checkObjIndex(t, vt, "texture coordinate", "texture coordinates", total.vt,
                                  seen.vt, name, lineNo);
                }
                if (s2 != std::string_view::npos) {
                    checkObjIndex(t, t.substr(s2 + 1), "normal", "normals", total.vn, seen.vn, name,
                                  lineNo);
                }
            }
            if (key == "f") {
                triangles += tok.size() - 3;
                checkTriangleLimit(triangles, name);
            }
        }
    });
    if (triangles == 0) {
        fail(name + ": no triangles (no 'f' line)");
    }
}

namespace {

// ---- STL ----------------------------------------------------------------------------------
// STL as in the StereoLithography Interface Specification (3D Systems, 1989), also Burns,
// "Automated Fabrication" (1993), section 6.5. Binary: an 80-byte header, a little-endian
// uint32 facet count n, then n records of 50 bytes (normal, three vertices, each three
// little-endian float32, and a 2-byte attribute count), so exactly 84 + 50 n bytes. ASCII:
// `solid name`, then per facet `facet normal nx ny nz`, `outer loop`, three `vertex x y z`,
// `endloop`, `endfacet`, and `endsolid name`.

std::uint32_t readU32le(const char* p) {
    std::uint32_t v = 0;
    std::memcpy(&v, p, 4);
    if constexpr (std::endian::native == std::endian::big) {
        v = (v >> 24) | ((v >> 8) & 0xFF00u) | ((v << 8) & 0xFF0000u) | (v << 24);
    }
    return v;
}

float readF32le(const char* p) {
    return std::bit_cast<float>(readU32le(p));
}

constexpr const char* kAxis[3] = {"x", "y", "z"};

void checkBinaryStl(std::string_view b, std::uint32_t count, const std::string& name,
                    double scale) {
    for (std::uint64_t f = 0; f < count; ++f) {
        const std::uint64_t facet = 84 + 50 * f;
        for (int v = 0; v < 3; ++v) {
            for (int c = 0; c < 3; ++c) {
                const std::uint64_t at = facet + 12 + 12 * v + 4 * c;
                const float x = readF32le(b.data() + at);
                if (const std::string p = coordinateProblem(x, scale); !p.empty()) {
                    fail(atByte(name, at) + "facet " + std::to_string(f) + ", vertex " +
                         std::to_string(v) + ": " + kAxis[c] + " " + p +
                         (std::isfinite(x) ? ""
                          : std::isnan(x)  ? " (NaN)"
                                           : " (infinite)"));
                }
            }
        }
    }
}

/// Throws at the first byte of `text` no ASCII STL holds (a NUL or a control character).
void checkAsciiStlBytes(std::string_view text, const std::string& name) {
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c == 0 || (c < 32 && !isSpace(static_cast<char>(c)) && c != '\n')) {
            fail(atByte(name, i) +
                 "a binary byte in a file that begins with 'solid' (ASCII STL); as binary STL "
                 "its size does not match its header's facet count (84 + 50 x count bytes)");
        }
    }
}

void checkAsciiStl(std::string_view text, const std::string& name, double scale) {
    checkAsciiStlBytes(text, name);
    std::vector<std::string_view> tok;
    std::size_t facetLine = 0; // the open facet's line, 0 outside a facet
    int vertices = 0;
    std::uint64_t facets = 0;
    forEachLine(text, [&](std::size_t lineNo, std::string_view line) {
        tokens(line, tok);
        if (tok.empty()) {
            return;
        }
        const auto place = [&] { return atLine(name, lineNo); };
        // Every line is one of the grammar's (Burns 6.5; assimp's reader instead skips any
        // byte it does not know and finds keywords anywhere, even inside other text).
        const auto expect = [&](std::size_t count, const char* form) {
            if (tok.size() != count) {
                fail(place() + "expected '" + form + "', got " + std::to_string(tok.size()) +
                     " words");
            }
        };
        const auto numbers = [&](std::size_t first, const char* what, bool finite) {
            for (int c = 0; c < 3; ++c) {
                const std::string_view t = tok[first + c];
                const auto v = parseNumber(t);
                if (!v) {
                    fail(place() + what + std::string(kAxis[c]) + " " + quoted(t) +
                         " is not a number");
                }
                if (const std::string p = finite ? coordinateProblem(*v, scale) : ""; !p.empty()) {
                    fail(place() + what + std::string(kAxis[c]) + " " + quoted(t) + " " + p);
                }
            }
        };
        const bool inFacet = facetLine != 0;
        if (tok[0] == "solid" || tok[0] == "endsolid") {
            if (inFacet) {
                fail(place() + quoted(tok[0]) + " inside the facet of line " +
                     std::to_string(facetLine) + " (no endfacet)");
            }
        } else if (tok[0] == "facet") {
            if (inFacet) {
                fail(place() + "a facet begins inside the facet of line " +
                     std::to_string(facetLine) + " (no endfacet)");
            }
            expect(5, "facet normal nx ny nz");
            if (tok[1] != "normal") {
                fail(place() + "expected 'facet normal nx ny nz', got " + quoted(tok[1]) +
                     " after 'facet'");
            }
            numbers(2, "normal ", false); // not used (hapto takes the corners' order), but read
            facetLine = lineNo;
            vertices = 0;
        } else if (tok[0] == "outer" || tok[0] == "endloop") {
            if (!inFacet) {
                fail(place() + quoted(tok[0]) + " outside a facet");
            }
            if (tok[0] == "outer") {
                expect(2, "outer loop");
                if (tok[1] != "loop") {
                    fail(place() + "expected 'outer loop', got " + quoted(tok[1]));
                }
            } else {
                expect(1, "endloop");
            }
        } else if (tok[0] == "vertex") {
            if (facetLine == 0) {
                fail(place() + "a vertex outside a facet");
            }
            if (tok.size() != 4) {
                fail(place() + "expected 'vertex x y z', got " + std::to_string(tok.size() - 1) +
                     " numbers");
            }
            numbers(1, "", true);
            ++vertices;
        } else if (tok[0] == "endfacet") {
            if (facetLine == 0) {
                fail(place() + "endfacet without a facet");
            }
            expect(1, "endfacet");
            if (vertices != 3) {
                fail(atLine(name, facetLine) + "the facet has " + std::to_string(vertices) +
                     " vertices; an STL facet is a triangle (3)");
            }
            facetLine = 0;
            checkTriangleLimit(++facets, name);
        } else {
            fail(place() + quoted(tok[0]) +
                 " is not an ASCII STL keyword (solid, facet normal, outer loop, vertex, "
                 "endloop, endfacet, endsolid)");
        }
    });
    if (facetLine != 0) {
        fail(atLine(name, facetLine) + "the file ends inside this facet (no endfacet)");
    }
    if (facets == 0) {
        fail(name + ": no triangles (the ASCII STL has no facet)");
    }
}

enum class StlKind { Binary, Ascii };

/// Tells binary STL from ASCII as assimp's STLImporter does, from the first bytes and the size
/// alone: binary when the size is 84 + 50 n for the header's count n (which must be 1 to the
/// triangle limit), else ASCII when it begins with 'solid' (after white space). `head` holds
/// the first bytes (at least 84 of them, or the whole file); a head of only white space, when
/// more follows, is taken for ASCII, for the whole file's check to decide.
StlKind stlKind(std::string_view head, std::uint64_t size, const std::string& name) {
    if (size >= 84 && head.size() >= 84) {
        const std::uint32_t count = readU32le(head.data() + 80);
        if (size == 84 + 50 * static_cast<std::uint64_t>(count)) {
            if (count == 0) {
                fail(name + ": no triangles (the binary STL header declares 0 facets)");
            }
            checkTriangleLimit(count, name);
            return StlKind::Binary;
        }
    }
    std::size_t i = 0;
    while (i < head.size() && (isSpace(head[i]) || head[i] == '\n')) {
        ++i;
    }
    if (head.substr(i, 5) == "solid" || (i == head.size() && head.size() < size)) {
        return StlKind::Ascii;
    }
    if (size < 84) {
        fail(name + ": " + std::to_string(size) +
             " bytes: not ASCII STL (it does not begin with 'solid') and too short for binary "
             "STL (an 84-byte header, then 50 bytes per facet)");
    }
    const std::uint32_t count = readU32le(head.data() + 80);
    fail(name + ": not ASCII STL (it does not begin with 'solid'), and as binary STL its size, " +
         std::to_string(size) + " bytes, is not the 84 + 50 x " + std::to_string(count) + " = " +
         std::to_string(84 + 50 * static_cast<std::uint64_t>(count)) +
         " bytes its header's facet count (bytes 80..83) declares (truncated or padded?)");
}

} // namespace

void checkStl(std::string_view bytes, const std::string& name, double scale) {
    if (stlKind(bytes, bytes.size(), name) == StlKind::Binary) {
        checkBinaryStl(bytes, readU32le(bytes.data() + 80), name, scale);
    } else {
        checkAsciiStl(bytes, name, scale);
    }
}

namespace {

// ---- PLY ----------------------------------------------------------------------------------
// PLY as in Greg Turk, "The PLY Polygon File Format" (1994; paulbourke.net/dataformats/ply):
// a header `ply`, `format ascii|binary_little_endian|binary_big_endian 1.0`, `comment` and
// `obj_info` lines, `element NAME COUNT` each followed by its `property TYPE NAME` or
// `property list COUNT_TYPE ITEM_TYPE NAME` lines, and `end_header`; then every element's
// instances in header order, each property in order (ASCII: numbers separated by white space,
// binary: packed values of the declared types). Types: char uchar short ushort int uint float
// double, or int8 uint8 int16 uint16 int32 uint32 float32 float64.

enum class PlyType : std::uint8_t { I8, U8, I16, U16, I32, U32, F32, F64 };

std::optional<PlyType> plyType(std::string_view t) {
    static constexpr std::pair<const char*, PlyType> kNames[] = {
        {"char", PlyType::I8},     {"int8", PlyType::I8},     {"uchar", PlyType::U8},
        {"uint8", PlyType::U8},    {"short", PlyType::I16},   {"int16", PlyType::I16},
        {"ushort", PlyType::U16},  {"uint16", PlyType::U16},  {"int", PlyType::I32},
        {"int32", PlyType::I32},   {"uint", PlyType::U32},    {"uint32", PlyType::U32},
        {"float", PlyType::F32},   {"float32", PlyType::F32}, {"double", PlyType::F64},
        {"float64", PlyType::F64},
    };
    for (const auto& [n, type] : kNames) {
        if (t == n) {
            return type;
        }
    }
    return std::nullopt;
}

std::size_t plySize(PlyType t) {
    switch (t) {
    case PlyType::I8:
    case PlyType::U8:
        return 1;
    case PlyType::I16:
    case PlyType::U16:
        return 2;
    case PlyType::I32:
    case PlyType::U32:
    case PlyType::F32:
        return 4;
    case PlyType::F64:
        return 8;
    }
    return 0;
}

bool plyIsFloat(PlyType t) {
    return t == PlyType::F32 || t == PlyType::F64;
}

struct PlyProperty {
    std::string name;
    bool list = false;
    PlyType countType = PlyType::U8;
    PlyType type = PlyType::F32;
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

enum class PlyFormat { Ascii, Little, Big };

/// Reads the body's values one by one, ASCII or binary, knowing where it is for messages.
class PlyReader {
public:
    PlyReader(std::string_view bytes, std::size_t bodyStart, std::size_t bodyLine, PlyFormat f,
              const std::string& name)
        : mBytes(bytes), mAt(bodyStart), mLine(bodyLine), mFormat(f), mName(name) {}

    /// Where a value starts: its byte and line.
    struct Mark {
        std::size_t at, line;
    };
    /// Where the next value starts (cheap: no text is made until a message needs it).
    Mark mark() {
        if (mFormat == PlyFormat::Ascii) {
            skipBlanks();
        }
        return {mAt, mLine};
    }
    /// Moves to the next element: in ASCII, one element is one line (assimp's reader is
    /// line-based, and misreads, then aborts on, an element split over lines).
    void beginElement() {
        if (mFormat == PlyFormat::Ascii) {
            skipSpace();
        }
    }
    /// True when an ASCII element's line has ended (next() returned nullopt before the end of
    /// the file).
    bool atLineEnd() const {
        return mFormat == PlyFormat::Ascii && mAt < mBytes.size() && mBytes[mAt] == '\n';
    }
    /// Refuses values left on an ASCII element's line. `what` names the element.
    template <class What> void endElement(const What& what) {
        if (mFormat == PlyFormat::Ascii) {
            skipBlanks();
            if (mAt < mBytes.size() && mBytes[mAt] != '\n') {
                fail(atLine(mName, mLine) + "more values on the line of " + what() +
                     " than its properties (an ASCII PLY element is one line)");
            }
        }
    }
    /// A mark for messages: "NAME:LINE: " (ASCII) or "NAME: byte N: " (binary).
    std::string place(Mark m) const {
        return mFormat == PlyFormat::Ascii ? atLine(mName, m.line) : atByte(mName, m.at);
    }
    /// The next value; nullopt at the end of the file (or, in ASCII, of the element's line).
    /// Throws for text that is not a number.
    std::optional<double> next(PlyType t) {
        if (mFormat == PlyFormat::Ascii) {
            skipBlanks();
            if (mAt >= mBytes.size() || mBytes[mAt] == '\n') {
                return std::nullopt;
            }
            const std::size_t start = mAt;
            while (mAt < mBytes.size() && !isSpace(mBytes[mAt]) && mBytes[mAt] != '\n') {
                ++mAt;
            }
            const std::string_view token = mBytes.substr(start, mAt - start);
            const auto v = plyIsFloat(t) ? parseNumber(token) : parseIntegerAsDouble(token);
            if (!v) {
                fail(atLine(mName, mLine) + quoted(token) + " is not " +
                     (plyIsFloat(t) ? "a number" : "a whole number"));
            }
            return v;
        }
        const std::size_t n = plySize(t);
        if (mBytes.size() - mAt < n) {
            return std::nullopt;
        }
        unsigned char raw[8];
        std::memcpy(raw, mBytes.data() + mAt, n);
        if ((mFormat == PlyFormat::Big) != (std::endian::native == std::endian::big)) {
            for (std::size_t i = 0; i < n / 2; ++i) {
                std::swap(raw[i], raw[n - 1 - i]);
            }
        }
        mAt += n;
        switch (t) {
        case PlyType::I8:
            return static_cast<double>(std::bit_cast<std::int8_t>(raw[0]));
        case PlyType::U8:
            return static_cast<double>(raw[0]);
        case PlyType::I16:
            return static_cast<double>(load<std::int16_t>(raw));
        case PlyType::U16:
            return static_cast<double>(load<std::uint16_t>(raw));
        case PlyType::I32:
            return static_cast<double>(load<std::int32_t>(raw));
        case PlyType::U32:
            return static_cast<double>(load<std::uint32_t>(raw));
        case PlyType::F32:
            return static_cast<double>(load<float>(raw));
        case PlyType::F64:
            return load<double>(raw);
        }
        return std::nullopt;
    }
    /// True when nothing but (ASCII) white space is left.
    bool atEnd() {
        if (mFormat == PlyFormat::Ascii) {
            skipSpace();
        }
        return mAt >= mBytes.size();
    }

private:
    template <class T> static T load(const unsigned char* raw) {
        T v;
        std::memcpy(&v, raw, sizeof v);
        return v;
    }
    static std::optional<double> parseIntegerAsDouble(std::string_view t) {
        const auto i = parseInteger(t);
        return i ? std::optional<double>(static_cast<double>(*i)) : std::nullopt;
    }
    void skipBlanks() {
        while (mAt < mBytes.size() && isSpace(mBytes[mAt])) {
            ++mAt;
        }
    }
    void skipSpace() {
        while (mAt < mBytes.size() && (isSpace(mBytes[mAt]) || mBytes[mAt] == '\n')) {
            mLine += mBytes[mAt] == '\n';
            ++mAt;
        }
    }

    std::string_view mBytes;
    std::size_t mAt;
    std::size_t mLine;
    PlyFormat mFormat;
    const std::string& mName;
};

/// A PLY header as read: its elements in order, its format, and where its body starts.
struct PlyHeader {
    std::vector<PlyElement> elements;
    PlyFormat format = PlyFormat::Ascii;
    std::size_t bodyStart = 0; ///< The byte after end_header's newline.
    std::size_t bodyLine = 0;  ///< The line the body starts on.
};

/// Reads the header: lines up to end_header, each one the specification's.
PlyHeader readPlyHeader(std::string_view bytes, const std::string& name) {
    std::vector<PlyElement> elements;
    std::optional<PlyFormat> format;
    std::vector<std::string_view> tok;
    std::size_t at = 0;
    std::size_t lineNo = 0;
    bool ended = false;
    while (!ended) {
        if (at >= bytes.size()) {
            fail(name + ": the PLY header has no end_header line");
        }
        std::size_t end = bytes.find('\n', at);
        if (end == std::string_view::npos) {
            end = bytes.size();
        }
        const std::string_view line = bytes.substr(at, end - at);
        at = std::min(end + 1, bytes.size()); // the body starts after end_header's newline
        ++lineNo;
        const auto place = [&] { return atLine(name, lineNo); };
        tokens(line, tok);
        if (lineNo == 1) {
            if (tok.size() != 1 || tok[0] != "ply") {
                fail(place() + "not a PLY file (the first line must be 'ply')");
            }
            continue;
        }
        if (tok.empty()) {
            fail(place() + "a blank line in the PLY header (the format has none, and assimp 5.2.5 "
                           "misreads some: remove it)");
        }
        if (tok[0] == "comment" || tok[0] == "obj_info") {
            continue;
        }
        if (tok[0] == "format") {
            if (tok.size() != 3 || tok[2] != "1.0") {
                fail(place() +
                     "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
            }
            if (tok[1] == "ascii") {
                format = PlyFormat::Ascii;
            } else if (tok[1] == "binary_little_endian") {
                format = PlyFormat::Little;
            } else if (tok[1] == "binary_big_endian") {
                format = PlyFormat::Big;
            } else {
                fail(place() + "unknown PLY format " + quoted(tok[1]));
            }
        } else if (tok[0] == "element") {
            const auto count = tok.size() == 3 ? parseInteger(tok[2]) : std::nullopt;
            if (!count || *count < 0) {
                fail(place() + "expected 'element NAME COUNT'");
            }
            elements.push_back({std::string(tok[1]), static_cast<std::uint64_t>(*count), {}});
        } else if (tok[0] == "property") {
            if (elements.empty()) {
                fail(place() + "a property before any element");
            }
            PlyProperty p;
            const bool list = tok.size() == 5 && tok[1] == "list";
            if (!list && tok.size() != 3) {
                fail(place() + "expected 'property TYPE NAME' or 'property list COUNT_TYPE "
                               "ITEM_TYPE NAME'");
            }
            const auto count = list ? plyType(tok[2]) : std::optional<PlyType>(PlyType::U8);
            const auto type = plyType(tok[list ? 3 : 1]);
            if (!count || !type || (list && plyIsFloat(*count))) {
                fail(place() + "unknown property type in " + quoted(line));
            }
            elements.back().properties.push_back(
                {std::string(tok[list ? 4 : 2]), list, *count, *type});
        } else if (tok[0] == "end_header") {
            if (tok.size() != 1) {
                fail(place() + "expected 'end_header' alone on its line (the body starts after "
                               "its newline)");
            }
            ended = true;
        } else {
            fail(place() + "unknown PLY header line " + quoted(line));
        }
    }
    if (!format) {
        fail(name + ": the PLY header has no format line");
    }
    return {std::move(elements), *format, at, lineNo + 1};
}

/// Where hapto's values are in a PLY file's elements: the vertex element and its x, y, z
/// properties, the face element and its vertex_indices list.
struct PlyLayout {
    const PlyElement* vertex = nullptr;
    const PlyElement* face = nullptr;
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
};

/// Finds the elements and properties hapto needs, and checks their counts against the limits.
PlyLayout plyLayout(const std::vector<PlyElement>& elements, const std::string& name) {
    const PlyElement* vertex = nullptr;
    const PlyElement* face = nullptr;
    int xyz[3] = {-1, -1, -1};
    int indices = -1;
    for (const PlyElement& e : elements) {
        vertex = e.name == "vertex" ? &e : vertex;
        face = e.name == "face" ? &e : face;
    }
    if (!vertex) {
        fail(name + ": the PLY header declares no 'vertex' element");
    }
    if (!face) {
        fail(name + ": no triangles (the PLY header declares no 'face' element)");
    }
    for (std::size_t i = 0; i < vertex->properties.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            if (vertex->properties[i].name == kAxis[c] && !vertex->properties[i].list) {
                xyz[c] = static_cast<int>(i);
            }
        }
    }
    for (int c = 0; c < 3; ++c) {
        if (xyz[c] < 0) {
            fail(name + ": the PLY vertex element has no property " + kAxis[c]);
        }
    }
    for (std::size_t i = 0; i < face->properties.size(); ++i) {
        const PlyProperty& p = face->properties[i];
        if (p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) {
            indices = static_cast<int>(i);
            if (plyIsFloat(p.type)) {
                fail(name + ": the PLY face list " + p.name + " must hold whole numbers");
            }
        }
    }
    if (indices < 0) {
        fail(name + ": the PLY face element has no 'vertex_indices' list");
    }
    if (vertex->count > TriangleMesh::kMaxVertices) {
        fail(name + ": " + std::to_string(vertex->count) + " vertices; a mesh may have at most " +
             std::to_string(TriangleMesh::kMaxVertices));
    }
    checkTriangleLimit(face->count, name);
    if (face->count == 0) {
        fail(name + ": no triangles (the PLY header declares 0 faces)");
    }
    return {vertex, face, {xyz[0], xyz[1], xyz[2]}, indices};
}

} // namespace

void checkPly(std::string_view bytes, const std::string& name, double scale) {
    const PlyHeader header = readPlyHeader(bytes, name);
    const std::vector<PlyElement>& elements = header.elements;
    const PlyLayout layout = plyLayout(elements, name);
    const PlyElement* vertex = layout.vertex;
    const PlyElement* face = layout.face;
    const int(&xyz)[3] = layout.xyz;
    const int indices = layout.indices;

    // The body, element by element.
    PlyReader r(bytes, header.bodyStart, header.bodyLine, header.format, name);
    std::uint64_t triangles = 0;
    for (const PlyElement& e : elements) {
        for (std::uint64_t i = 0; i < e.count; ++i) {
            const auto what = [&] { return e.name + " element " + std::to_string(i); };
            r.beginElement();
            for (std::size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& p = e.properties[k];
                auto mark = r.mark();
                const auto place = [&] { return r.place(mark); };
                const auto value = r.next(p.list ? p.countType : p.type);
                const auto truncated = [&] {
                    if (r.atLineEnd()) {
                        fail(place() + "the line ends inside " + what() +
                             " (an ASCII PLY element is one line, with a value for each of its "
                             "properties)");
                    }
                    fail(place() + "the file ends inside " + what() + ", but the header declares " +
                         std::to_string(e.count) + " " + e.name + " elements");
                };
                if (!value) {
                    truncated();
                }
                if (!p.list) {
                    if (&e == vertex &&
                        (static_cast<int>(k) == xyz[0] || static_cast<int>(k) == xyz[1] ||
                         static_cast<int>(k) == xyz[2])) {
                        if (const std::string problem = coordinateProblem(*value, scale);
                            !problem.empty()) {
                            fail(place() + what() + ": " + p.name + " " + problem);
                        }
                    }
                    continue;
                }
                const double n = *value;
                if (n < 0) {
                    fail(place() + what() + ": a negative list length");
                }
                const bool isIndices = &e == face && static_cast<int>(k) == indices;
                if (isIndices && n < 3) {
                    fail(place() + what() + ": a face needs at least 3 vertices, got " +
                         std::to_string(static_cast<long long>(n)));
                }
                if (isIndices) {
                    checkFaceSize(static_cast<std::uint64_t>(n), place() + what() + ": ", "face");
                }
                for (std::uint64_t j = 0; j < static_cast<std::uint64_t>(n); ++j) {
                    mark = r.mark();
                    const auto item = r.next(p.type);
                    if (!item) {
                        truncated();
                    }
                    if (isIndices && !(*item >= 0 && *item < static_cast<double>(vertex->count))) {
                        fail(place() + what() + ": vertex index " +
                             std::to_string(static_cast<long long>(*item)) +
                             " is out of range (the file has " + std::to_string(vertex->count) +
                             " vertices)");
                    }
                }
                if (isIndices) {
                    triangles += static_cast<std::uint64_t>(n) - 2;
                    checkTriangleLimit(triangles, name);
                }
            }
            r.endElement(what);
        }
    }
    if (!r.atEnd()) {
        fail(r.place(r.mark()) + "data after the last element the header declares (" +
             std::to_string(face->count) + " faces, " + std::to_string(vertex->count) +
             " vertices)");
    }
}

void checkHead(MeshFormat format, std::string_view head, std::uint64_t size,
               const std::string& name) {
    if (size == 0) {
        return; // empty, or a file that reports no size (/proc): the whole file's check decides
    }
    switch (format) {
    case MeshFormat::Obj:
        refuseNul(head, name, "an OBJ text file");
        break;
    case MeshFormat::Stl:
        stlKind(head, size, name);
        break;
    case MeshFormat::Ply:
        refuseNul(head.substr(0, head.find("end_header")), name, "a PLY file (its header is text)");
        break;
    }
}

} // namespace hapto::detail
