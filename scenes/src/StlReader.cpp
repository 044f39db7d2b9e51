// STL, binary or ASCII, read into faces (MeshReading.h). Design note: binary and ASCII are told
// apart from the first bytes and the size alone (stlKind, also run on a file's head before it is
// read whole), every value is checked where it is read and refused with its byte or line, and
// the normals are read past (hapto takes a facet's orientation from its corners' order).
// Positions are 32-bit floats, as the format stores them.
//
// STL as in the StereoLithography Interface Specification (3D Systems, 1989), also Burns,
// "Automated Fabrication" (1993), section 6.5. Binary: an 80-byte header, a little-endian
// uint32 facet count n, then n records of 50 bytes (normal, three vertices, each three
// little-endian float32, and a 2-byte attribute count), so exactly 84 + 50 n bytes. ASCII:
// `solid name`, then per facet `facet normal nx ny nz`, `outer loop`, three `vertex x y z`,
// `endloop`, `endfacet`, and `endsolid name`.

#include "MeshReading.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <numeric>

namespace hapto::detail {
namespace {

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

/// A coordinate already checked by parseNumber, as the 32-bit float the model keeps.
double asFloat(std::string_view t) {
    return static_cast<float>(*parseNumber(t));
}

void readBinaryStl(std::string_view b, std::uint32_t count, const std::string& name, double scale,
                   ModelFaces& out) {
    out.vertices.reserve(3 * static_cast<std::size_t>(count));
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
            const char* p = b.data() + facet + 12 + 12 * v;
            out.vertices.emplace_back(readF32le(p), readF32le(p + 4), readF32le(p + 8));
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

void readAsciiStl(std::string_view text, const std::string& name, double scale, ModelFaces& out) {
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
        // Every line is one of the grammar's (Burns 6.5; assimp 5.2.5's reader instead skipped any
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
            out.vertices.emplace_back(asFloat(tok[1]), asFloat(tok[2]), asFloat(tok[3]));
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

/// Tells binary STL from ASCII as assimp 5.2.5's STLImporter did, from the first bytes and size
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

ModelFaces readStl(std::string_view bytes, const std::string& name, double scale) {
    ModelFaces out;
    if (stlKind(bytes, bytes.size(), name) == StlKind::Binary) {
        readBinaryStl(bytes, readU32le(bytes.data() + 80), name, scale, out);
    } else {
        readAsciiStl(bytes, name, scale, out);
    }
    // Every facet is a triangle of its own three corners.
    out.corners.resize(out.vertices.size());
    std::iota(out.corners.begin(), out.corners.end(), 0u);
    out.faceSizes.assign(out.vertices.size() / 3, 3);
    return out;
}

void checkStlHead(std::string_view head, std::uint64_t size, const std::string& name) {
    stlKind(head, size, name);
}

} // namespace hapto::detail
