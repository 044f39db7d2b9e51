// Scene files. Design note: the loader streams. nlohmann's callback parser hands us each
// element of the top-level "objects" array as soon as it is complete; we validate and convert
// it, then tell the parser to drop it. Peak memory is the file text plus the SceneObjects, not
// a DOM of 10^7 objects. Every message names the file and the JSON path of the bad value.

#include "hapto/scenes/SceneFile.h"

#include "hapto/scenes/InputError.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace hapto {
namespace {

using Json = nlohmann::json;

// A JSON path built only when a message needs it: each level points at its parent on the stack.
struct Path {
    const Path* parent = nullptr;
    const char* key = nullptr; // a field name, or
    long index = -1;           // an array index

    Path operator/(const char* k) const { return {this, k, -1}; }
    Path operator[](std::size_t i) const { return {this, nullptr, static_cast<long>(i)}; }
    std::string str() const {
        std::string head = parent ? parent->str() : std::string();
        if (key) {
            return head.empty() ? std::string(key) : head + "." + key;
        }
        if (index >= 0) {
            return head + "[" + std::to_string(index) + "]";
        }
        return head;
    }
};

// Builds "file: path: what" messages.
class Where {
public:
    explicit Where(std::string_view source) : mSource(source) {}
    [[noreturn]] void fail(const Path& path, const std::string& what) const {
        const std::string p = path.str();
        throw InputError(std::string(mSource) + ": " + (p.empty() ? "(top level)" : p) + ": " +
                         what);
    }

private:
    std::string_view mSource;
};

std::string typeName(const Json& j) {
    if (j.is_number_float()) {
        return "a number";
    }
    if (j.is_number()) {
        return "an integer";
    }
    return j.type_name() == std::string("array") || j.type_name() == std::string("object")
               ? std::string("an ") + j.type_name()
               : std::string("a ") + j.type_name();
}

double number(const Where& w, const Json& j, const Path& path) {
    if (!j.is_number()) {
        w.fail(path, "expected a number, got " + typeName(j));
    }
    const double v = j.get<double>();
    if (!std::isfinite(v)) {
        w.fail(path, "expected a finite number");
    }
    return v;
}

template <std::size_t N>
std::array<double, N> numbers(const Where& w, const Json& j, const Path& path) {
    if (!j.is_array() || j.size() != N) {
        w.fail(path, "expected an array of " + std::to_string(N) + " numbers, got " +
                         (j.is_array() ? "an array of " + std::to_string(j.size()) : typeName(j)));
    }
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) {
        out[i] = number(w, j[i], path[i]);
    }
    return out;
}

Vec3 vec3(const Where& w, const Json& j, const Path& path) {
    const auto a = numbers<3>(w, j, path);
    return {a[0], a[1], a[2]};
}

void positive(const Where& w, double v, const Path& path, const char* what) {
    if (!(v > 0.0)) {
        std::ostringstream s;
        s << what << " must be > 0 (got " << v << ")";
        w.fail(path, s.str());
    }
}

void checkKeys(const Where& w, const Json& obj, const Path& path,
               std::initializer_list<std::string_view> allowed, std::string_view hint = {}) {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
        if (std::find(allowed.begin(), allowed.end(), std::string_view(it.key())) ==
            allowed.end()) {
            std::string msg = "unknown field '" + it.key() + "'";
            if (!hint.empty()) {
                msg += " (" + std::string(hint) + ")";
            }
            w.fail(path, msg);
        }
    }
}

const Json& required(const Where& w, const Json& obj, const Path& path, const char* key) {
    const auto it = obj.find(key);
    if (it == obj.end()) {
        w.fail(path, std::string("missing required field '") + key + "'");
    }
    return *it;
}

SceneObject parseObject(const Where& w, const Json& j, const Path& path) {
    if (!j.is_object()) {
        w.fail(path, "expected an object, got " + typeName(j));
    }
    SceneObject o;
    const Json& id = required(w, j, path, "id");
    if (!id.is_number_integer()) {
        w.fail(path / "id", "expected a non-negative integer, got " + typeName(id));
    }
    if (id.is_number_unsigned() ? id.get<std::uint64_t>() > kMaxObjectId
                                : id.get<std::int64_t>() < 0) {
        w.fail(path / "id",
               "must be in 0.." + std::to_string(kMaxObjectId) + " (got " + id.dump() + ")");
    }
    o.id = static_cast<ObjectId>(id.get<std::uint64_t>());

    const Json& shape = required(w, j, path, "shape");
    if (!shape.is_string()) {
        w.fail(path / "shape", "expected a string (\"box\" or \"sphere\"), got " + typeName(shape));
    }
    const auto& shapeText = shape.get_ref<const std::string&>();
    if (shapeText == "box") {
        o.shape = Shape::Box;
        checkKeys(w, j, path,
                  {"id", "shape", "center", "half_extents", "rotation", "stiffness", "friction"},
                  "a box takes id, shape, center, half_extents, rotation, stiffness, friction");
        const Path he = path / "half_extents";
        o.halfExtents = vec3(w, required(w, j, path, "half_extents"), he);
        for (std::size_t i = 0; i < 3; ++i) {
            positive(w, o.halfExtents[static_cast<int>(i)], he[i], "a half extent");
        }
    } else if (shapeText == "sphere") {
        o.shape = Shape::Sphere;
        checkKeys(w, j, path,
                  {"id", "shape", "center", "radius", "rotation", "stiffness", "friction"},
                  "a sphere takes id, shape, center, radius, rotation, stiffness, friction");
        const double r = number(w, required(w, j, path, "radius"), path / "radius");
        positive(w, r, path / "radius", "the radius");
        o.halfExtents = Vec3(r);
    } else {
        w.fail(path / "shape",
               "unknown shape '" + shapeText + "' (expected \"box\" or \"sphere\")");
    }
    o.center = vec3(w, required(w, j, path, "center"), path / "center");

    if (const auto it = j.find("rotation"); it != j.end()) {
        const auto q = numbers<4>(w, *it, path / "rotation");
        const double len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (std::abs(len - 1.0) > 1e-3) {
            std::ostringstream s;
            s << "must be a unit quaternion (w, x, y, z); its length is " << len;
            w.fail(path / "rotation", s.str());
        }
        // A quaternion written from a normalised one reads back bit for bit.
        const double scale = std::abs(len - 1.0) < 1e-9 ? 1.0 : 1.0 / len;
        o.rotation = Quat(q[0] * scale, q[1] * scale, q[2] * scale, q[3] * scale);
    }
    if (const auto it = j.find("stiffness"); it != j.end()) {
        o.material.stiffness = number(w, *it, path / "stiffness");
        positive(w, o.material.stiffness, path / "stiffness", "stiffness (N/m)");
    }
    if (const auto it = j.find("friction"); it != j.end()) {
        const auto f = numbers<2>(w, *it, path / "friction");
        for (std::size_t i = 0; i < 2; ++i) {
            if (f[i] < 0.0) {
                w.fail((path / "friction")[i], "a friction coefficient must be >= 0");
            }
        }
        if (f[1] > f[0]) {
            w.fail(path / "friction",
                   "the dynamic coefficient (second) must not exceed the static one (first)");
        }
        o.material.staticFriction = f[0];
        o.material.dynamicFriction = f[1];
    }
    return o;
}

Aabb parseBounds(const Where& w, const Json& j) {
    const Path top;
    const Path path = top / "bounds";
    if (!j.is_object()) {
        w.fail(path, "expected an object {\"min\": [x,y,z], \"max\": [x,y,z]}, got " + typeName(j));
    }
    checkKeys(w, j, path, {"min", "max"});
    Aabb b{vec3(w, required(w, j, path, "min"), path / "min"),
           vec3(w, required(w, j, path, "max"), path / "max")};
    for (int i = 0; i < 3; ++i) {
        if (!(b.min[i] < b.max[i])) {
            w.fail(path, "min must be < max on every axis (axis " + std::to_string(i) + ")");
        }
    }
    return b;
}

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

void appendNumber(std::string& out, double v) {
    char buf[32];
    const auto res = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, res.ptr);
}

void appendVec(std::string& out, const double* v, int n) {
    out += '[';
    for (int i = 0; i < n; ++i) {
        if (i) {
            out += ", ";
        }
        appendNumber(out, v[i]);
    }
    out += ']';
}

} // namespace

Scene parseScene(std::string_view text, std::string_view sourceName) {
    const Where w(sourceName);
    const Path top;
    const Path objectsPath = top / "objects";
    std::vector<SceneObject> objects;
    std::string topKey;
    bool inObjects = false;

    // Depth 0 is the top-level object; its keys are reported at depth 1, and elements of the
    // "objects" array end at depth 2.
    auto callback = [&](int depth, Json::parse_event_t event, Json& parsed) -> bool {
        switch (event) {
        case Json::parse_event_t::key:
            if (depth == 1) {
                topKey = parsed.get<std::string>();
            }
            return true;
        case Json::parse_event_t::array_start:
            if (depth == 1 && topKey == "objects") {
                inObjects = true;
            }
            return true;
        case Json::parse_event_t::array_end:
            if (depth == 1) {
                inObjects = false;
            }
            return true;
        case Json::parse_event_t::object_end:
        case Json::parse_event_t::value:
            if (inObjects && depth == 2) {
                objects.push_back(parseObject(w, parsed, objectsPath[objects.size()]));
                return false; // converted; drop the JSON
            }
            return true;
        default:
            return true;
        }
    };

    Json root;
    try {
        root = Json::parse(text.begin(), text.end(), callback);
    } catch (const Json::parse_error& e) {
        const auto [line, col] = lineColumn(text, e.byte == 0 ? 0 : e.byte - 1);
        std::string what = e.what();
        // Drop nlohmann's "[json.exception.parse_error.101] parse error at line 1, column 2: ".
        if (const auto p = what.find(": "); p != std::string::npos && what.rfind("[json", 0) == 0) {
            what = what.substr(p + 2);
        }
        throw InputError(std::string(sourceName) + ":" + std::to_string(line) + ":" +
                         std::to_string(col) + ": not valid JSON: " + what);
    } catch (const Json::exception& e) {
        throw InputError(std::string(sourceName) + ": not valid JSON: " + e.what());
    }

    if (!root.is_object()) {
        w.fail(top,
               "expected a JSON object with \"format\": \"hapto-scene\", got " + typeName(root));
    }
    checkKeys(w, root, top, {"format", "version", "bounds", "objects"});
    const Json& format = required(w, root, top, "format");
    if (!format.is_string() || format.get<std::string>() != "hapto-scene") {
        w.fail(top / "format", "expected \"hapto-scene\", got " + format.dump());
    }
    const Json& version = required(w, root, top, "version");
    if (!version.is_number_integer() || version.get<std::int64_t>() != kSceneFormatVersion) {
        w.fail(top / "version", "this build reads version " + std::to_string(kSceneFormatVersion) +
                                    ", got " + version.dump());
    }
    const auto objectsIt = root.find("objects");
    if (objectsIt == root.end()) {
        w.fail(top, "missing required field 'objects' (an array, possibly empty)");
    }
    if (!objectsIt->is_array()) {
        w.fail(objectsPath, "expected an array, got " + typeName(*objectsIt));
    }

    // Duplicate ids, named by both places.
    {
        std::vector<std::pair<ObjectId, std::uint32_t>> ids;
        ids.reserve(objects.size());
        for (std::uint32_t i = 0; i < objects.size(); ++i) {
            ids.emplace_back(objects[i].id, i);
        }
        std::sort(ids.begin(), ids.end());
        for (std::size_t i = 1; i < ids.size(); ++i) {
            if (ids[i].first == ids[i - 1].first) {
                w.fail(objectsPath[ids[i].second] / "id",
                       "duplicate id " + std::to_string(ids[i].first) + " (also at objects[" +
                           std::to_string(ids[i - 1].second) + "])");
            }
        }
    }

    const auto boundsIt = root.find("bounds");
    const Aabb bounds =
        boundsIt != root.end() ? parseBounds(w, *boundsIt) : Scene::defaultBounds(objects);
    return Scene(bounds, std::move(objects));
}

Scene loadSceneFile(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        throw InputError(path.string() + ": cannot open the scene file (does it exist?)");
    }
    std::string text;
    in.seekg(0, std::ios::end);
    const auto size = in.tellg();
    if (size < 0) {
        throw InputError(path.string() + ": cannot read the scene file");
    }
    text.resize(static_cast<std::size_t>(size));
    in.seekg(0);
    in.read(text.data(), size);
    if (!in) {
        throw InputError(path.string() + ": cannot read the scene file");
    }
    return parseScene(text, path.string());
}

namespace {

// Streams the JSON in chunks of about a megabyte, so 10^7 objects never sit in one string.
void writeSceneJson(const Scene& scene, std::ostream& os) {
    std::string out;
    out.reserve(1 << 21);
    const auto flush = [&] {
        os.write(out.data(), static_cast<std::streamsize>(out.size()));
        out.clear();
    };
    out += "{\"format\": \"hapto-scene\", \"version\": ";
    out += std::to_string(kSceneFormatVersion);
    out += ",\n \"bounds\": {\"min\": ";
    appendVec(out, &scene.bounds().min.x, 3);
    out += ", \"max\": ";
    appendVec(out, &scene.bounds().max.x, 3);
    out += "},\n \"objects\": [";
    bool first = true;
    for (const SceneObject& o : scene.objects()) {
        out += first ? "\n  " : ",\n  ";
        first = false;
        out += "{\"id\": ";
        out += std::to_string(o.id);
        out += ", \"shape\": \"";
        out += shapeName(o.shape);
        out += "\", \"center\": ";
        appendVec(out, &o.center.x, 3);
        if (o.shape == Shape::Box) {
            out += ", \"half_extents\": ";
            appendVec(out, &o.halfExtents.x, 3);
            const double q[4] = {o.rotation.w, o.rotation.x, o.rotation.y, o.rotation.z};
            out += ", \"rotation\": ";
            appendVec(out, q, 4);
        } else {
            out += ", \"radius\": ";
            appendNumber(out, o.halfExtents.x);
        }
        out += ", \"stiffness\": ";
        appendNumber(out, o.material.stiffness);
        const double f[2] = {o.material.staticFriction, o.material.dynamicFriction};
        out += ", \"friction\": ";
        appendVec(out, f, 2);
        out += '}';
        if (out.size() > (1u << 20)) {
            flush();
        }
    }
    out += "]}\n";
    flush();
}

} // namespace

std::string sceneToJson(const Scene& scene) {
    std::ostringstream os;
    writeSceneJson(scene, os);
    return std::move(os).str();
}

void saveSceneFile(const Scene& scene, const std::filesystem::path& path) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) {
        throw InputError(path.string() + ": cannot open for writing");
    }
    writeSceneJson(scene, out);
    out.flush();
    if (!out) {
        throw InputError(path.string() + ": write failed (disk full?)");
    }
}

} // namespace hapto
