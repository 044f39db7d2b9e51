#include "hapto/io/JsonInput.h"

#include "hapto/io/InputError.h"
#include "hapto/io/InputFile.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <unordered_set>
#include <vector>

namespace hapto::json {

std::string Path::str() const {
    std::string head = parent ? parent->str() : std::string();
    if (key) {
        return head.empty() ? std::string(key) : head + "." + key;
    }
    if (index >= 0) {
        return head + "[" + std::to_string(index) + "]";
    }
    return head;
}

void Source::fail(const Path& path, const std::string& what) const {
    const std::string p = path.str();
    throw InputError(std::string(mName) + ": " + (p.empty() ? "(top level)" : p) + ": " + what);
}

namespace {

// Line and column (1-based) of a byte offset, for syntax errors.
std::pair<std::size_t, std::size_t> lineColumn(std::string_view text, std::size_t byte) {
    byte = std::min(byte, text.size());
    std::size_t line = 1, col = 1;
    for (std::size_t i = 0; i < byte; ++i) {
        if (text[i] == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }
    return {line, col};
}

/// The byte order mark `text` starts with when it is UTF-16 or UTF-32 (JSON files are UTF-8),
/// else nullptr.
const char* utf16Or32(std::string_view text) {
    using namespace std::string_view_literals;
    if (text.starts_with("\xFF\xFE\0\0"sv) || text.starts_with("\0\0\xFE\xFF"sv)) {
        return "a UTF-32 byte order mark";
    }
    if (text.starts_with("\xFF\xFE"sv) || text.starts_with("\xFE\xFF"sv)) {
        return "a UTF-16 byte order mark";
    }
    return nullptr;
}

} // namespace

namespace {

// Refuses a key that appears twice in one object (nlohmann would keep the last one silently),
// naming the JSON path of the object. It follows the parser's callback events: a frame per open
// object or array, holding the keys seen so far (an object) or the index of the element being
// read (an array). Depths as nlohmann reports them: a container's start and end, and a scalar,
// at the value's own depth (the document is depth 0); a key at its object's depth + 1. Every
// event must be seen, so the wrapped callback must not discard a container at its start or a
// key (events inside are then not reported); discarding at the end, as the scene loader does,
// is fine.
class DuplicateKeyCheck {
public:
    explicit DuplicateKeyCheck(const Source& source) : mSource(source) {}

    void onEvent(Json::parse_event_t event, const Json& parsed) {
        switch (event) {
        case Json::parse_event_t::object_start:
        case Json::parse_event_t::array_start:
            mFrames.push_back(Frame{event == Json::parse_event_t::object_start, 0, {}, {}, {}});
            return;
        case Json::parse_event_t::key:
            if (!mFrames.empty() && mFrames.back().object) {
                addKey(parsed.get_ref<const std::string&>());
            }
            return;
        case Json::parse_event_t::object_end:
        case Json::parse_event_t::array_end:
            if (!mFrames.empty()) {
                mFrames.pop_back();
            }
            elementDone();
            return;
        case Json::parse_event_t::value:
            elementDone();
            return;
        }
    }

private:
    struct Frame {
        bool object = false;
        long index = 0;                       // array: the element being read
        std::string key;                      // object: the field being read
        std::vector<std::string> keys;        // object: keys so far (few: a linear search)
        std::unordered_set<std::string> many; // object: all keys, once there are many
    };
    static constexpr std::size_t kLinearKeys = 32;

    void elementDone() {
        if (!mFrames.empty() && !mFrames.back().object) {
            ++mFrames.back().index;
        }
    }

    void addKey(const std::string& key) {
        Frame& f = mFrames.back();
        bool seen = false;
        if (f.many.empty()) {
            seen = std::find(f.keys.begin(), f.keys.end(), key) != f.keys.end();
            if (!seen) {
                f.keys.push_back(key);
                if (f.keys.size() > kLinearKeys) {
                    f.many.insert(f.keys.begin(), f.keys.end());
                    f.keys.clear();
                }
            }
        } else {
            seen = !f.many.insert(key).second;
        }
        if (seen) {
            std::string path;
            for (std::size_t i = 0; i + 1 < mFrames.size(); ++i) {
                const Frame& up = mFrames[i];
                path += up.object ? (path.empty() ? "" : ".") + up.key
                                  : "[" + std::to_string(up.index) + "]";
            }
            throw InputError(std::string(mSource.name()) + ": " +
                             (path.empty() ? "(top level)" : path) + ": duplicate field '" +
                             printable(key) +
                             "' (each field may appear once; JSON readers differ on which copy "
                             "they keep)");
        }
        f.key = key;
    }

    const Source& mSource;
    std::vector<Frame> mFrames;
};

} // namespace

Json parseText(std::string_view text, const Source& source,
               const Json::parser_callback_t& callback) {
    DuplicateKeyCheck duplicates(source);
    const Json::parser_callback_t checked = [&](int depth, Json::parse_event_t event,
                                                Json& parsed) {
        duplicates.onEvent(event, parsed);
        return callback ? callback(depth, event, parsed) : true;
    };
    try {
        return Json::parse(text.begin(), text.end(), checked);
    } catch (const Json::parse_error& e) {
        if (const char* mark = utf16Or32(text)) {
            throw InputError(std::string(source.name()) +
                             ": not UTF-8 text: the file starts with " + mark +
                             "; save it as UTF-8");
        }
        const std::size_t at = e.byte == 0 ? 0 : e.byte - 1;
        const auto [line, col] = lineColumn(text, at);
        std::string what = e.what();
        // Drop nlohmann's "[json.exception.parse_error.101] parse error at line 1, column 2: ".
        if (const auto p = what.find(": "); p != std::string::npos && what.rfind("[json", 0) == 0) {
            what = what.substr(p + 2);
        }
        if (const std::size_t nul = text.substr(0, at + 1).find('\0'); nul != text.npos) {
            what = "a NUL byte (byte " + std::to_string(nul) +
                   "); JSON is UTF-8 text: is the file UTF-16 or binary?";
        }
        throw InputError(std::string(source.name()) + ":" + std::to_string(line) + ":" +
                         std::to_string(col) + ": not valid JSON: " + printable(what));
    } catch (const Json::exception& e) {
        throw InputError(std::string(source.name()) + ": not valid JSON: " + printable(e.what()));
    }
}

std::string readFile(const std::filesystem::path& path, std::string_view what) {
    return InputFile(path, what).readAll();
}

std::string typeName(const Json& j) {
    if (j.is_number_float()) {
        return "a number";
    }
    if (j.is_number()) {
        return "an integer";
    }
    const std::string t = j.type_name();
    return (t == "array" || t == "object") ? "an " + t : "a " + t;
}

std::string show(double v) {
    char text[32];
    for (int digits = 6;; ++digits) {
        std::snprintf(text, sizeof text, "%.*g", digits, v);
        if (digits >= 17 || !std::isfinite(v) || std::strtod(text, nullptr) == v) {
            return text; // 17 significant digits always read back as the same double
        }
    }
}

std::string printable(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    const auto escape = [&out](unsigned char c) {
        static constexpr char kHex[] = "0123456789ABCDEF";
        switch (c) {
        case '\n':
            out += "\\n";
            break;
        case '\t':
            out += "\\t";
            break;
        case '\r':
            out += "\\r";
            break;
        default:
            out += {'\\', 'x', kHex[c >> 4], kHex[c & 15]};
        }
    };
    for (std::size_t i = 0; i < text.size();) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c < 0x80) {
            if (c < 0x20 || c == 0x7F) {
                escape(c);
            } else {
                out += static_cast<char>(c);
            }
            ++i;
            continue;
        }
        // A whole UTF-8 sequence is kept, except a C1 control (U+0080..U+009F: C2 80..C2 9F).
        const std::size_t n = c >= 0xC2 && c <= 0xDF   ? 2
                              : c >= 0xE0 && c <= 0xEF ? 3
                              : c >= 0xF0 && c <= 0xF4 ? 4
                                                       : 0;
        bool whole = n > 0 && i + n <= text.size();
        for (std::size_t k = 1; whole && k < n; ++k) {
            whole = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
        }
        if (whole && !(c == 0xC2 && static_cast<unsigned char>(text[i + 1]) < 0xA0)) {
            out.append(text.substr(i, n));
            i += n;
        } else {
            escape(c);
            ++i;
        }
    }
    return out;
}

std::string describe(const Json& j) {
    if (j.is_structured()) {
        return typeName(j);
    }
    std::string text = j.dump();
    constexpr std::size_t kMax = 64;
    if (text.size() > kMax) {
        std::size_t cut = kMax;
        while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) {
            --cut; // not inside a UTF-8 sequence
        }
        text = text.substr(0, cut) + "...";
    }
    return text;
}

double number(const Source& s, const Json& j, const Path& path) {
    if (!j.is_number()) {
        s.fail(path, "expected a number, got " + typeName(j));
    }
    return finiteNumber(s, j.get<double>(), path);
}

double finiteNumber(const Source& s, double v, const Path& path) {
    if (!std::isfinite(v)) {
        s.fail(path, "expected a finite number");
    }
    return v;
}

void checkRange(const Source& s, double v, const Path& path, double lo, double hi, bool strictLow,
                const char* what) {
    if (strictLow ? !(v > lo) : !(v >= lo)) {
        s.fail(path, std::string(what) + " must be " + (strictLow ? "> " : ">= ") + show(lo) +
                         " (got " + show(v) + ")");
    }
    if (v > hi) {
        s.fail(path, std::string(what) + " must be <= " + show(hi) + " (got " + show(v) + ")");
    }
}

double ranged(const Source& s, const Json& j, const Path& path, double lo, double hi,
              bool strictLow, const char* what) {
    const double v = number(s, j, path);
    checkRange(s, v, path, lo, hi, strictLow, what);
    return v;
}

std::int64_t integer(const Source& s, const Json& j, const Path& path, std::int64_t lo,
                     std::int64_t hi) {
    if (!j.is_number_integer()) {
        s.fail(path, "expected an integer, got " + typeName(j));
    }
    const bool tooBig =
        j.is_number_unsigned() && j.get<std::uint64_t>() > static_cast<std::uint64_t>(hi);
    if (tooBig || j.get<std::int64_t>() < lo || j.get<std::int64_t>() > hi) {
        s.fail(path, "must be in " + std::to_string(lo) + ".." + std::to_string(hi) + " (got " +
                         j.dump() + ")");
    }
    return j.get<std::int64_t>();
}

std::string string(const Source& s, const Json& j, const Path& path) {
    if (!j.is_string()) {
        s.fail(path, "expected a string, got " + typeName(j));
    }
    return j.get<std::string>();
}

std::string printableString(const Source& s, const Json& j, const Path& path, const char* what) {
    std::string text = string(s, j, path);
    if (printable(text) != text) {
        s.fail(path, std::string(what) + " must not contain control characters (got " +
                         describe(j) + ")");
    }
    return text;
}

bool boolean(const Source& s, const Json& j, const Path& path) {
    if (!j.is_boolean()) {
        s.fail(path, "expected true or false, got " + typeName(j));
    }
    return j.get<bool>();
}

Vec3 vec3(const Source& s, const Json& j, const Path& path) {
    const auto a = numbers<3>(s, j, path);
    return {a[0], a[1], a[2]};
}

Quat quaternion(const Source& s, const Json& j, const Path& path) {
    return unitQuaternion(s, numbers<4>(s, j, path), path);
}

Quat unitQuaternion(const Source& s, const std::array<double, 4>& q, const Path& path) {
    const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (std::abs(len - 1.0) > 1e-3) {
        s.fail(path, "must be a unit quaternion (w, x, y, z); its length is " + show(len));
    }
    const double scale = std::abs(len - 1.0) < 1e-9 ? 1.0 : 1.0 / len;
    return Quat(q[0] * scale, q[1] * scale, q[2] * scale, q[3] * scale);
}

const Json& object(const Source& s, const Json& j, const Path& path) {
    if (!j.is_object()) {
        s.fail(path, "expected an object, got " + typeName(j));
    }
    return j;
}

void checkKeys(const Source& s, const Json& obj, const Path& path,
               std::initializer_list<std::string_view> allowed) {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
        if (std::find(allowed.begin(), allowed.end(), std::string_view(it.key())) ==
            allowed.end()) {
            std::string list;
            for (const auto a : allowed) {
                list += (list.empty() ? "" : ", ") + std::string(a);
            }
            s.fail(path,
                   "unknown field '" + printable(it.key()) + "' (expected one of: " + list + ")");
        }
    }
}

const Json& required(const Source& s, const Json& obj, const Path& path, const char* key) {
    const auto it = obj.find(key);
    if (it == obj.end()) {
        s.fail(path, std::string("missing required field '") + key + "'");
    }
    return *it;
}

const Json* optional(const Json& obj, const char* key) {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
}

} // namespace hapto::json
