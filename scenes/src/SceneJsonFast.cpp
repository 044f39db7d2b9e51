// The fast path of the JSON scene loader, on simdjson's On-Demand API. Design note: it vouches
// only for what it fully understands. It reads every value of the document once, in the
// format's own shape (a top-level object of "format", "version", "bounds", "objects"; boxes and
// spheres with their known fields, each at most once), puts every value through the same checks
// as the checked loader (SceneFileChecks.h), and refuses, by returning nothing, on anything
// else: a syntax error, a field it does not know, a repeated field, a mesh, a big integer, a
// value a check refuses. The checked loader (nlohmann, SceneFile.cpp) then reads the text again
// and gives its exact answer: the scene (a mesh scene) or the message, with its line and JSON
// path. So a valid box-and-sphere scene is read once at simdjson's speed, and every refusal is
// the checked loader's, word for word; the cost of a bad file is a second parse.
//
// Version 3's fields (dynamic bodies, "gravity", "dynamics") are read here too and checked by the
// same applyBodyFields and checkPhysics; one in a file of an older version is not vouched for
// (the checked loader refuses it).
//
// Numbers are read as nlohmann reads them: an integer token (even "-0") as its integer value
// converted to double, any other as the nearest double (both correctly rounded).

#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"
#include "hapto/scenes/SceneFile.h"

#include "SceneFileChecks.h"

#include <simdjson.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace hapto::detail {
namespace {

namespace od = simdjson::ondemand;
using json::Path;
using json::Source;

/// The fast path does not vouch for this input: the checked loader reads it.
struct NotVouched {};

template <class T> T ok(simdjson::simdjson_result<T>&& r) {
    T v;
    if (std::move(r).get(v) != simdjson::SUCCESS) {
        throw NotVouched{};
    }
    return v;
}

double number(od::value v) {
    od::number n = ok(v.get_number());
    switch (n.get_number_type()) {
    case od::number_type::signed_integer:
        return static_cast<double>(n.get_int64());
    case od::number_type::unsigned_integer:
        return static_cast<double>(n.get_uint64());
    case od::number_type::floating_point_number:
        return n.get_double();
    }
    throw NotVouched{};
}

template <std::size_t N> std::array<double, N> numbers(od::value v) {
    std::array<double, N> out{};
    std::size_t i = 0;
    for (auto element : ok(v.get_array())) {
        if (i == N) {
            throw NotVouched{};
        }
        out[i++] = number(ok(std::move(element)));
    }
    if (i != N) {
        throw NotVouched{};
    }
    return out;
}

Vec3 vec3(od::value v) {
    const auto a = numbers<3>(v);
    return {a[0], a[1], a[2]};
}

/// Marks a field seen; a repeated one is not vouched for.
void once(unsigned& seen, unsigned bit) {
    if (seen & bit) {
        throw NotVouched{};
    }
    seen |= bit;
}

/// "inertia": 3 principal moments or 3 rows of 3, as readInertia reads them.
void inertia(od::value v, BodyFields& f) {
    std::array<double, 9> m{};
    std::size_t r = 0;
    for (auto element : ok(v.get_array())) {
        od::value row = ok(std::move(element));
        const bool isRow = ok(row.type()) == od::json_type::array;
        if (r == 3 || (r > 0 && isRow == f.inertiaPrincipal)) {
            throw NotVouched{};
        }
        f.inertiaPrincipal = !isRow;
        if (isRow) {
            const auto values = numbers<3>(row);
            std::copy(values.begin(), values.end(), m.begin() + static_cast<std::ptrdiff_t>(r * 3));
        } else {
            m[r * 3 + r] = number(row);
        }
        ++r;
    }
    if (r != 3) {
        throw NotVouched{};
    }
    f.inertia = m;
}

/// One version-3 field of an object into `f`; false when `key` is none of them.
bool bodyField(std::string_view key, od::value value, BodyFields& f) {
    const auto set = [](auto& field, auto v) {
        if (field) {
            throw NotVouched{}; // repeated
        }
        field = v;
    };
    if (key == "dynamic") {
        set(f.dynamic, ok(value.get_bool()));
    } else if (key == "mass_kg") {
        set(f.massKg, number(value));
    } else if (key == "density_kg_per_m3") {
        set(f.densityKgPerM3, number(value));
    } else if (key == "inertia") {
        if (f.inertia) {
            throw NotVouched{};
        }
        inertia(value, f);
    } else if (key == "restitution") {
        set(f.restitution, number(value));
    } else if (key == "velocity") {
        set(f.velocity, vec3(value));
    } else if (key == "angular_velocity") {
        set(f.angularVelocity, vec3(value));
    } else {
        return false;
    }
    return true;
}

/// The fields of an object seen so far, one bit each.
enum ObjectField : unsigned {
    kId = 1,
    kShape = 2,
    kCenter = 4,
    kHalf = 8,
    kRadius = 16,
    kRotation = 32,
    kStiffness = 64,
    kFriction = 128,
    kBody = 256 // any version-3 field
};

/// An object's material (its stiffness already in `o`) and version-3 fields, checked as
/// parseObject checks them.
void checkMaterialAndBody(const Source& w, SceneObject& o, unsigned seen,
                          const std::array<double, 2>& friction, const BodyFields& body,
                          const Path& path) {
    if (seen & kStiffness) {
        const Path sp = path / "stiffness";
        checkStiffness(w, json::finiteNumber(w, o.material.stiffness, sp), sp);
    }
    if (seen & kFriction) {
        const Path fp = path / "friction";
        checkFriction(w, json::finiteNumber(w, friction[0], fp[0]),
                      json::finiteNumber(w, friction[1], fp[1]), fp);
        o.material.staticFriction = friction[0];
        o.material.dynamicFriction = friction[1];
    }
    if (seen & kBody) {
        applyBodyFields(w, o, body, path);
    }
}

/// One element of "objects": a box or a sphere, checked as parseObject checks it. Sets
/// `version3` when it has a version-3 field.
SceneObject object(const Source& w, od::value v, const Path& path, bool& version3) {
    unsigned seen = 0;
    SceneObject o;
    std::uint64_t id = 0;
    std::string_view shape;
    double radius = 0.0;
    std::array<double, 4> rotation{};
    std::array<double, 2> friction{};
    BodyFields body;
    for (auto f : ok(v.get_object())) {
        od::field field = ok(std::move(f));
        const std::string_view key = ok(field.unescaped_key());
        od::value value = field.value();
        if (key == "id") {
            once(seen, kId);
            id = ok(value.get_uint64());
        } else if (key == "shape") {
            once(seen, kShape);
            shape = ok(value.get_string());
            if (shape == "box") {
                o.shape = Shape::Box;
            } else if (shape == "sphere") {
                o.shape = Shape::Sphere;
            } else {
                throw NotVouched{}; // a mesh, or an unknown shape
            }
        } else if (key == "center") {
            once(seen, kCenter);
            o.center = vec3(value);
        } else if (key == "half_extents") {
            once(seen, kHalf);
            o.halfExtents = vec3(value);
        } else if (key == "radius") {
            once(seen, kRadius);
            radius = number(value);
        } else if (key == "rotation") {
            once(seen, kRotation);
            rotation = numbers<4>(value);
        } else if (key == "stiffness") {
            once(seen, kStiffness);
            o.material.stiffness = number(value);
        } else if (key == "friction") {
            once(seen, kFriction);
            friction = numbers<2>(value);
        } else if (bodyField(key, value, body)) {
            seen |= kBody;
        } else {
            throw NotVouched{};
        }
    }
    const unsigned sized = o.shape == Shape::Box ? kHalf : kRadius;
    if ((seen & (kId | kShape | kCenter | sized)) != (kId | kShape | kCenter | sized) ||
        (seen & (kHalf | kRadius)) != sized || id > kMaxObjectId) {
        throw NotVouched{};
    }
    o.id = static_cast<ObjectId>(id);
    if (o.shape == Shape::Box) {
        const Path he = path / "half_extents";
        for (std::size_t i = 0; i < 3; ++i) {
            checkHalfExtent(w, json::finiteNumber(w, o.halfExtents[static_cast<int>(i)], he[i]),
                            he[i]);
        }
    } else {
        const Path rp = path / "radius";
        o.halfExtents = Vec3(checkRadius(w, json::finiteNumber(w, radius, rp), rp));
    }
    for (int i = 0; i < 3; ++i) {
        json::finiteNumber(w, o.center[i], path / "center");
    }
    checkReach(w, o, path);
    if (seen & kRotation) {
        const Path qp = path / "rotation";
        for (std::size_t i = 0; i < 4; ++i) {
            json::finiteNumber(w, rotation[i], qp[i]);
        }
        o.rotation = json::unitQuaternion(w, rotation, qp);
    }
    checkMaterialAndBody(w, o, seen, friction, body, path);
    version3 = version3 || (seen & kBody) != 0;
    return o;
}

Aabb bounds(const Source& w, od::value v, const Path& path) {
    unsigned seen = 0;
    Aabb b;
    for (auto f : ok(v.get_object())) {
        od::field field = ok(std::move(f));
        const std::string_view key = ok(field.unescaped_key());
        if (key == "min") {
            once(seen, 1);
            b.min = vec3(field.value());
        } else if (key == "max") {
            once(seen, 2);
            b.max = vec3(field.value());
        } else {
            throw NotVouched{};
        }
    }
    if (seen != 3) {
        throw NotVouched{};
    }
    for (int i = 0; i < 3; ++i) {
        json::finiteNumber(w, b.min[i], path / "min");
        json::finiteNumber(w, b.max[i], path / "max");
    }
    checkBounds(w, b, path);
    return b;
}

/// "dynamics": {"rate_hz": r}, the rate when given.
std::optional<double> dynamics(od::value v) {
    std::optional<double> rate;
    for (auto f : ok(v.get_object())) {
        od::field field = ok(std::move(f));
        if (ok(field.unescaped_key()) != "rate_hz" || rate) {
            throw NotVouched{};
        }
        rate = number(field.value());
    }
    return rate;
}

} // namespace

std::optional<Scene> parseSceneFast(std::string_view text, std::size_t capacity,
                                    std::string_view sourceName) {
    const Source w(sourceName);
    const Path top;
    const Path objectsPath = top / "objects";
    simdjson::padded_string copy;
    simdjson::padded_string_view input;
    if (capacity >= text.size() + simdjson::SIMDJSON_PADDING) {
        input = simdjson::padded_string_view(text.data(), text.size(), capacity);
    } else {
        copy = simdjson::padded_string(text);
        input = copy;
    }
    try {
        od::parser parser;
        od::document doc = ok(parser.iterate(input));
        unsigned seen = 0;
        std::int64_t version = 0;
        std::optional<Aabb> box;
        std::vector<SceneObject> objects;
        bool version3 = false;
        std::optional<Vec3> gravity;
        std::optional<double> rateHz;
        for (auto f : ok(doc.get_object())) {
            od::field field = ok(std::move(f));
            const std::string_view key = ok(field.unescaped_key());
            od::value value = field.value();
            if (key == "format") {
                once(seen, 1);
                if (ok(value.get_string()) != "hapto-scene") {
                    throw NotVouched{};
                }
            } else if (key == "version") {
                once(seen, 2);
                version = ok(value.get_int64());
            } else if (key == "bounds") {
                once(seen, 4);
                box = bounds(w, value, top / "bounds");
            } else if (key == "objects") {
                once(seen, 8);
                for (auto element : ok(value.get_array())) {
                    objects.push_back(
                        object(w, ok(std::move(element)), objectsPath[objects.size()], version3));
                }
            } else if (key == "gravity") {
                once(seen, 16);
                gravity = vec3(value);
            } else if (key == "dynamics") {
                once(seen, 32);
                rateHz = dynamics(value);
            } else {
                throw NotVouched{};
            }
        }
        // Nothing may follow the top-level object: at the end, the location is out of bounds.
        const char* rest = nullptr;
        if (doc.current_location().get(rest) != simdjson::OUT_OF_BOUNDS || (seen & 11) != 11 ||
            version < 1 || version > kSceneFormatVersion ||
            (version < 3 && (version3 || (seen & 48) != 0))) {
            throw NotVouched{};
        }
        const ScenePhysics physics = checkPhysics(w, gravity, rateHz, top);
        checkUniqueIds(w, objects, objectsPath);
        Scene scene = finishScene(w, std::move(objects), box, objectsPath);
        scene.setPhysics(physics);
        return scene;
    } catch (const NotVouched&) {
        return std::nullopt;
    } catch (const InputError&) {
        return std::nullopt;
    }
}

} // namespace hapto::detail
