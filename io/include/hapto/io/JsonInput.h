#pragma once
/// Reading hapto's JSON input files (scenes, device configurations) with messages that name the
/// file and the JSON path of every bad value. For hapto's own loaders; all [control].

#include "hapto/core/Geometry.h"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <string>
#include <string_view>

namespace hapto::json {

/// The JSON value type every reader here takes (nlohmann's).
using Json = nlohmann::json;

/// A JSON path such as `objects[12].half_extents[1]`, built only when a message needs it: each
/// level points at its parent on the stack, so a valid file costs no string work.
struct Path {
    const Path* parent = nullptr; ///< The enclosing level, or none at the top.
    const char* key = nullptr;    ///< A field name (must outlive the Path), or
    long index = -1;              ///< an array index.

    /// The field `k` of this level.
    Path operator/(const char* k) const { return {this, k, -1}; }
    /// The element `i` of this level.
    Path operator[](std::size_t i) const { return {this, nullptr, static_cast<long>(i)}; }
    /// The path as text ("" at the top).
    std::string str() const;
};

/// Where input comes from: every failure becomes an InputError "source: path: what".
class Source {
public:
    /// `name` names the file (or stream) in messages; it must outlive the Source.
    explicit Source(std::string_view name) : mName(name) {}
    /// Throws InputError "name: path: what" ("(top level)" for the empty path).
    [[noreturn]] void fail(const Path& path, const std::string& what) const;
    /// The source's name.
    std::string_view name() const { return mName; }

private:
    std::string_view mName;
};

/// Parses JSON text; a syntax error becomes "name:line:column: not valid JSON: ...", and a key
/// repeated in one object "name: path: duplicate field 'key' ...". `callback` is nlohmann's
/// parser callback (may be empty); it must not discard a container at its start or a key
/// (discarding at the end is fine). [control]
Json parseText(std::string_view text, const Source& source,
               const Json::parser_callback_t& callback = nullptr);
/// Reads a whole regular file of at most kMaxInputFileBytes (InputFile.h); throws InputError
/// naming it when it cannot be opened or read, or is a directory, FIFO, device... [control]
std::string readFile(const std::filesystem::path& path, std::string_view what);

/// "a number", "an integer", "a string", "an array", ... for messages.
std::string typeName(const Json& j);
/// A number for messages: as few significant digits as show it exactly (at least 6: "0.5",
/// "1e+06", but "100.0000001"), so a value just past a limit never reads as the limit.
std::string show(double v);
/// Text for messages and figures: control characters, DEL and bytes that are not UTF-8 written
/// as escapes (`\n`, `\t`, `\r`, `\xHH`), so a name or a file's bytes cannot break a line or a
/// terminal. [any thread]
std::string printable(std::string_view text);
/// A value for messages: a scalar as JSON text (a long string cut short), an array or object
/// only by its type, so a deeply nested value cannot exhaust the stack (dump() recurses).
std::string describe(const Json& j);

/// A finite number.
double number(const Source& s, const Json& j, const Path& path);
/// Checks an already read value is finite, with number()'s message; returns it.
double finiteNumber(const Source& s, double v, const Path& path);
/// A finite number with lo < v (strictLow) or lo <= v, and v <= hi; `what` names it.
double ranged(const Source& s, const Json& j, const Path& path, double lo, double hi,
              bool strictLow, const char* what);
/// Checks an already read value the same way.
void checkRange(const Source& s, double v, const Path& path, double lo, double hi, bool strictLow,
                const char* what);
/// An integer in lo..hi.
std::int64_t integer(const Source& s, const Json& j, const Path& path, std::int64_t lo,
                     std::int64_t hi);
/// A string.
std::string string(const Source& s, const Json& j, const Path& path);
/// A string without control characters (a name shown in messages, plots and file names);
/// `what` names it in the message.
std::string printableString(const Source& s, const Json& j, const Path& path, const char* what);
/// true or false.
bool boolean(const Source& s, const Json& j, const Path& path);
/// An array of exactly N finite numbers.
template <std::size_t N>
std::array<double, N> numbers(const Source& s, const Json& j, const Path& path) {
    if (!j.is_array() || j.size() != N) {
        s.fail(path, "expected an array of " + std::to_string(N) + " numbers, got " +
                         (j.is_array() ? "an array of " + std::to_string(j.size()) : typeName(j)));
    }
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) {
        out[i] = number(s, j[i], path[i]);
    }
    return out;
}
/// [x, y, z].
Vec3 vec3(const Source& s, const Json& j, const Path& path);
/// A unit quaternion [w, x, y, z], within 1e-3 of unit length; normalised (a quaternion
/// written from a normalised one reads back bit for bit).
Quat quaternion(const Source& s, const Json& j, const Path& path);
/// Checks already read finite components [w, x, y, z] the same way; returns the quaternion,
/// normalised.
Quat unitQuaternion(const Source& s, const std::array<double, 4>& q, const Path& path);

/// Checks that `j` is an object.
const Json& object(const Source& s, const Json& j, const Path& path);
/// Refuses fields not in `allowed`, listing the allowed ones.
void checkKeys(const Source& s, const Json& obj, const Path& path,
               std::initializer_list<std::string_view> allowed);
/// The field, or a "missing required field" failure.
const Json& required(const Source& s, const Json& obj, const Path& path, const char* key);
/// The field, or nullptr.
const Json* optional(const Json& obj, const char* key);

/// +infinity, for open upper ranges.
inline constexpr double kUnbounded = std::numeric_limits<double>::infinity();

} // namespace hapto::json
