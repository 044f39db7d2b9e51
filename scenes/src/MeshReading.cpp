// What the model readers share: places, problems, numbers and words (MeshReading.h).

#include "MeshReading.h"

#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"
#include "hapto/scenes/TriangleMesh.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>

namespace hapto::detail {

void fail(const std::string& what) {
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

void refuseNul(std::string_view text, const std::string& name, const char* what) {
    if (const void* p = std::memchr(text.data(), '\0', text.size())) {
        const auto at = static_cast<std::uint64_t>(static_cast<const char*>(p) - text.data());
        fail(atByte(name, at) + "a NUL byte: not " + what);
    }
}

/// What is wrong with a number kept as a 32-bit float, or "": not finite, or past the largest
/// float (assimp 5.2.5 made it infinite; the messages still say so). The text follows the
/// number's name.
std::string floatProblem(double v) {
    if (!std::isfinite(v)) {
        return "is not finite";
    }
    if (std::abs(v) > std::numeric_limits<float>::max()) {
        return "is beyond the largest 32-bit float, 3.4e+38 (model coordinates are kept as "
               "32-bit floats)";
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

/// Refuses a face (or line, or point) of more than kMaxFaceVertices vertices.
void checkFaceSize(std::uint64_t vertices, const std::string& place, const char* what) {
    if (vertices > kMaxFaceVertices) {
        fail(place + "a " + what + " of " + std::to_string(vertices) +
             " vertices; hapto reads at most " + std::to_string(kMaxFaceVertices) +
             " (split it into smaller polygons)");
    }
}

void checkTriangleLimit(std::uint64_t triangles, const std::string& name) {
    if (triangles > TriangleMesh::kMaxTriangles) {
        fail(name + ": more than " + std::to_string(TriangleMesh::kMaxTriangles) +
             " triangles; a mesh may have at most " + std::to_string(TriangleMesh::kMaxTriangles));
    }
}

} // namespace hapto::detail
