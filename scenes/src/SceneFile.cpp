// Scene files. Design note: the loader streams. nlohmann's callback parser hands us each
// element of the top-level "objects" array as soon as it is complete; we validate and convert
// it, then tell the parser to drop it. Peak memory is the file text plus the SceneObjects, not
// a DOM of 10^7 objects. Every message names the file and the JSON path of the bad value.

#include "hapto/scenes/SceneFile.h"

#include "hapto/core/Finite.h"
#include "hapto/io/InputError.h"
#include "hapto/io/InputFile.h"
#include "hapto/io/JsonInput.h"
#include "hapto/scenes/BinaryScene.h"
#include "hapto/scenes/MeshFile.h"

#include "SceneFileChecks.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <tuple>

namespace hapto {

namespace detail {

using namespace hapto::json;

double checkHalfExtent(const Source& s, double v, const Path& path) {
    checkRange(s, v, path, 0.0, kUnbounded, true, "a half extent");
    return v;
}

double checkRadius(const Source& s, double v, const Path& path) {
    checkRange(s, v, path, 0.0, kUnbounded, true, "the radius");
    return v;
}

double checkMeshScale(const Source& s, double v, const Path& path) {
    checkRange(s, v, path, 0.0, kUnbounded, true, "the scale");
    return v;
}

double checkStiffness(const Source& s, double v, const Path& path) {
    checkRange(s, v, path, 0.0, Material::kMaxStiffness, true, "stiffness (N/m)");
    return v;
}

void checkFriction(const Source& s, double staticMu, double dynamicMu, const Path& path) {
    checkRange(s, staticMu, path[0], 0.0, Material::kMaxFriction, false, "a friction coefficient");
    checkRange(s, dynamicMu, path[1], 0.0, Material::kMaxFriction, false, "a friction coefficient");
    if (dynamicMu > staticMu) {
        s.fail(path, "the dynamic coefficient (second) must not exceed the static one (first)");
    }
}

void checkReach(const Source& s, const SceneObject& o, const Path& path) {
    // A box reaches at most the sum of its half extents from its centre along any axis,
    // whatever its rotation, a mesh at most its bounding radius. (Its size, and its distance
    // from the bounds, are checked once the bounds are known: finishScene.)
    const double reach = o.shape == Shape::Sphere ? o.halfExtents.x
                         : o.shape == Shape::Mesh
                             ? o.mesh->boundingRadius()
                             : o.halfExtents.x + o.halfExtents.y + o.halfExtents.z;
    for (int i = 0; i < 3; ++i) {
        if (!std::isfinite(std::abs(o.center[i]) + reach)) {
            s.fail(path, "the object reaches past the largest finite coordinate (centre " +
                             show(o.center[i]) + " on axis " + std::to_string(i) + ", size " +
                             show(reach) + ")");
        }
    }
}

void checkBounds(const Source& s, const Aabb& b, const Path& path) {
    for (int i = 0; i < 3; ++i) {
        if (!(b.min[i] < b.max[i])) {
            s.fail(path, "min must be < max on every axis (axis " + std::to_string(i) + ")");
        }
        if (!std::isfinite(b.max[i] - b.min[i])) {
            s.fail(path, "the bounds are too large: max - min overflows on axis " +
                             std::to_string(i) + " (" + show(b.min[i]) + " .. " + show(b.max[i]) +
                             "); every size must be a finite number of metres");
        }
    }
}

namespace {

// Every distance an index computes between an object and the bounds must be finite: refuses
// the first object whose AABB, together with the bounds, spans an overflowing size.
void checkSpan(const Source& w, const Aabb& bounds, std::span<const SceneObject> objects,
               const Path& objectsPath) {
    for (std::size_t k = 0; k < objects.size(); ++k) {
        const Aabb box = objects[k].aabb();
        for (int i = 0; i < 3; ++i) {
            const double lo = std::min(box.min[i], bounds.min[i]);
            const double hi = std::max(box.max[i], bounds.max[i]);
            if (!std::isfinite(hi - lo)) {
                w.fail(objectsPath[k], "the object lies too far from the bounds: the space "
                                       "spanning both overflows on axis " +
                                           std::to_string(i) + " (" + show(lo) + " .. " + show(hi) +
                                           ")");
            }
        }
    }
}

} // namespace

void checkUniqueIds(const Source& w, std::span<const SceneObject> objects,
                    const Path& objectsPath) {
    // Ids written in ascending order (as every generator does) are unique without a sort.
    bool ascending = true;
    for (std::size_t i = 1; i < objects.size() && ascending; ++i) {
        ascending = objects[i - 1].id < objects[i].id;
    }
    if (ascending) {
        return;
    }
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

Scene finishScene(const Source& w, std::vector<SceneObject> objects,
                  const std::optional<Aabb>& explicitBounds, const Path& objectsPath) {
    if (explicitBounds) {
        checkSpan(w, *explicitBounds, objects, objectsPath);
        return Scene(*explicitBounds, std::move(objects));
    }
    // Default bounds pad the objects' union by 5 % (at least 1 mm). Far enough from the origin
    // that margin is lost to rounding or overflows; refuse here, with the file and the reason,
    // rather than let the Scene refuse the bounds.
    const Aabb bounds = Scene::defaultBounds(objects);
    for (int i = 0; i < 3; ++i) {
        if (!(std::isfinite(bounds.min[i]) && std::isfinite(bounds.max[i]) &&
              std::isfinite(bounds.max[i] - bounds.min[i]) && bounds.min[i] < bounds.max[i])) {
            w.fail(objectsPath, "the objects lie too far out on axis " + std::to_string(i) +
                                    " to pad default bounds around them (the margin is lost to "
                                    "rounding or overflows); give \"bounds\" explicitly");
        }
    }
    return Scene(bounds, std::move(objects));
}

std::shared_ptr<const TriangleMesh> makeInlineMesh(const Source& w, const Path& path,
                                                   std::vector<Vec3> vertices,
                                                   std::vector<TriangleIndices> triangles,
                                                   double scale, std::uint32_t farMark,
                                                   std::optional<std::int64_t> farValue) {
    const Path vp = path / "vertices";
    const Path tp = path / "triangles";
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        const Vec3 scaled = vertices[i] * scale;
        if (!finite(scaled)) {
            w.fail(vp[i], "the vertex times the scale " + show(scale) + " is not finite");
        }
        const double out = std::max({std::abs(scaled.x), std::abs(scaled.y), std::abs(scaled.z)});
        if (out > TriangleMesh::kMaxCoordinate) {
            w.fail(vp[i], std::string("the vertex") +
                              (scale == 1.0 ? "" : " times the scale " + show(scale)) + " lies " +
                              show(out) + " m out, beyond the " +
                              show(TriangleMesh::kMaxCoordinate) +
                              " m a mesh vertex may lie from its origin");
        }
        vertices[i] = scaled;
    }
    const std::size_t count = vertices.size();
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        for (std::size_t k = 0; k < 3; ++k) {
            if (triangles[i][k] >= count) {
                const bool far = farValue && triangles[i][k] == farMark;
                const std::int64_t value = far ? *farValue : triangles[i][k];
                w.fail(tp[i][k], "vertex index " + std::to_string(value) +
                                     " is out of range (the mesh has " + std::to_string(count) +
                                     " vertices)");
            }
        }
    }
    // make() names the element of what it refuses ("no triangles left" when all are
    // degenerate) after the file and the object.
    return TriangleMesh::make(std::move(vertices), std::move(triangles), MeshSource{"", scale},
                              std::string(w.name()) + ": " + path.str());
}

std::shared_ptr<const TriangleMesh> loadModel(ModelCache& models,
                                              const std::filesystem::path& baseDir,
                                              const std::string& file, double scale) {
    auto& cached = models[{file, scale}];
    if (!cached) {
        const std::filesystem::path where = std::filesystem::path(file).is_absolute()
                                                ? std::filesystem::path(file)
                                                : baseDir / file;
        cached = loadMeshFile(where, MeshSource{file, scale});
    }
    return cached;
}

} // namespace detail

namespace {

using namespace hapto::json;
using namespace hapto::detail;

/// What the loader keeps while it streams objects: where model files are found, the models
/// read so far (a file placed twice at one scale is read once and shared), and the file's
/// version once its "version" field has been read (0 before).
struct LoadContext {
    std::filesystem::path baseDir;
    ModelCache models;
    std::int64_t version = 0;
    /// The inline "vertices" (unscaled) and "triangles" of the object being read, converted
    /// element by element as the parser completes them, so a large inline mesh never sits in
    /// the parser's DOM. A triangle's index too large for 32 bits is kept as kFarIndex, and
    /// the first such is remembered (triangle, corner, value) for its message.
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
    std::optional<std::tuple<std::size_t, std::size_t, std::int64_t>> farIndex;
    /// The place of the object being read in "objects", and the first object that gave a
    /// version-3 field (its place and the field's key), for the version check when "version"
    /// follows "objects".
    std::size_t objectIndex = 0;
    std::optional<std::pair<std::size_t, const char*>> firstBodyField;
    static constexpr std::uint32_t kFarIndex = 0xFFFFFFFFu; // > TriangleMesh::kMaxVertices

    void startObject() {
        vertices.clear();
        triangles.clear();
        farIndex.reset();
    }
};

/// One element of an inline "vertices" array. [control]
void streamVertex(const Source& w, const Json& j, const Path& vp, LoadContext& c) {
    if (c.vertices.size() >= TriangleMesh::kMaxVertices) {
        w.fail(vp, "more than " + std::to_string(TriangleMesh::kMaxVertices) +
                       " vertices; a mesh may have at most that many");
    }
    c.vertices.push_back(vec3(w, j, vp[c.vertices.size()]));
}

/// One element of an inline "triangles" array; the index range is checked once the vertices
/// are known (parseInlineMesh). [control]
void streamTriangle(const Source& w, const Json& t, const Path& tp, LoadContext& c) {
    const std::size_t i = c.triangles.size();
    if (i >= TriangleMesh::kMaxTriangles) {
        w.fail(tp, "more than " + std::to_string(TriangleMesh::kMaxTriangles) +
                       " triangles; a mesh may have at most that many");
    }
    if (!t.is_array() || t.size() != 3) {
        w.fail(tp[i], "expected [i, j, k], three vertex indices, got " +
                          (t.is_array() ? "an array of " + std::to_string(t.size()) : typeName(t)));
    }
    TriangleIndices tri{};
    for (std::size_t k = 0; k < 3; ++k) {
        if (!t[k].is_number_integer()) {
            w.fail(tp[i][k], "expected a vertex index (a whole number), got " + describe(t[k]));
        }
        const std::int64_t index = t[k].is_number_unsigned()
                                       ? static_cast<std::int64_t>(std::min<std::uint64_t>(
                                             t[k].get<std::uint64_t>(), std::uint64_t(1) << 62))
                                       : t[k].get<std::int64_t>();
        if (index < 0 || index >= static_cast<std::int64_t>(LoadContext::kFarIndex)) {
            if (!c.farIndex) {
                c.farIndex.emplace(i, k, index);
            }
            tri[k] = LoadContext::kFarIndex;
        } else {
            tri[k] = static_cast<std::uint32_t>(index);
        }
    }
    c.triangles.push_back(tri);
}

/// An inline mesh: "vertices" [[x,y,z],...] (times `scale`) and "triangles" [[i,j,k],...],
/// their elements already converted into `c` by parseScene's callback. [control]
std::shared_ptr<const TriangleMesh>
parseInlineMesh(const Source& w, const Json& j, const Path& path, double scale, LoadContext& c) {
    const Path vp = path / "vertices";
    const Path tp = path / "triangles";
    const Json& vj = required(w, j, path, "vertices");
    const Json& tj = required(w, j, path, "triangles");
    if (!vj.is_array()) {
        w.fail(vp, "expected an array of [x, y, z], got " + typeName(vj));
    }
    if (!tj.is_array()) {
        w.fail(tp, "expected an array of [i, j, k], got " + typeName(tj));
    }
    std::vector<Vec3> vertices = std::move(c.vertices);
    std::vector<TriangleIndices> triangles = std::move(c.triangles);
    std::optional<std::int64_t> far;
    if (c.farIndex) {
        far = std::get<2>(*c.farIndex);
    }
    c.startObject();
    return makeInlineMesh(w, path, std::move(vertices), std::move(triangles), scale,
                          LoadContext::kFarIndex, far);
}

/// A mesh read from a model file, named relative to the scene file's folder.
std::shared_ptr<const TriangleMesh> parseFileMesh(const Source& w, const Json& j, const Path& path,
                                                  double scale, LoadContext& context) {
    const Path fp = path / "file";
    const std::string file = string(w, required(w, j, path, "file"), fp);
    if (file.empty()) {
        w.fail(fp, "expected the model file's path (relative to the scene file), got \"\"");
    }
    if (const std::size_t nul = file.find('\0'); nul != std::string::npos) {
        w.fail(fp, "a NUL character (\\u0000) in the model file's path, at character " +
                       std::to_string(nul) + " (the system would read the path only up to it)");
    }
    try {
        return loadModel(context.models, context.baseDir, file, scale);
    } catch (const InputError& e) {
        w.fail(fp, e.what());
    }
}

/// "inertia": 3 principal moments [Ixx, Iyy, Izz] or a 3x3 tensor [[...], [...], [...]] (kg m^2).
void readInertia(const Source& w, const Json& j, const Path& path, BodyFields& f) {
    const char* expected = "expected 3 principal moments [Ixx, Iyy, Izz] or a 3x3 tensor "
                           "[[Ixx, Ixy, Ixz], [Iyx, Iyy, Iyz], [Izx, Izy, Izz]] (kg m^2), got ";
    if (!j.is_array() || j.size() != 3) {
        w.fail(path,
               expected + (j.is_array() ? "an array of " + std::to_string(j.size()) : typeName(j)));
    }
    std::array<double, 9> m{};
    f.inertiaPrincipal = !j[0].is_array();
    for (std::size_t r = 0; r < 3; ++r) {
        if (j[r].is_array() == f.inertiaPrincipal) {
            w.fail(path[r], std::string(expected) + "a mix of numbers and arrays");
        }
        if (f.inertiaPrincipal) {
            m[r * 3 + r] = number(w, j[r], path[r]);
        } else {
            const auto row = numbers<3>(w, j[r], path[r]);
            std::copy(row.begin(), row.end(), m.begin() + static_cast<std::ptrdiff_t>(r * 3));
        }
    }
    f.inertia = m;
}

/// An object's version-3 fields, read but not checked (applyBodyFields checks them).
BodyFields readBodyFields(const Source& w, const Json& j, const Path& path) {
    BodyFields f;
    if (const Json* v = optional(j, "dynamic")) {
        f.dynamic = boolean(w, *v, path / "dynamic");
    }
    if (const Json* v = optional(j, "mass_kg")) {
        f.massKg = number(w, *v, path / "mass_kg");
    }
    if (const Json* v = optional(j, "density_kg_per_m3")) {
        f.densityKgPerM3 = number(w, *v, path / "density_kg_per_m3");
    }
    if (const Json* v = optional(j, "inertia")) {
        readInertia(w, *v, path / "inertia", f);
    }
    if (const Json* v = optional(j, "restitution")) {
        f.restitution = number(w, *v, path / "restitution");
    }
    if (const Json* v = optional(j, "velocity")) {
        f.velocity = vec3(w, *v, path / "velocity");
    }
    if (const Json* v = optional(j, "angular_velocity")) {
        f.angularVelocity = vec3(w, *v, path / "angular_velocity");
    }
    return f;
}

/// Refuses version-3 fields in a file known to be older, before their values are read;
/// remembers the first when the version is not known yet (checkTopLevel refuses it then).
void gateBodyFields(const Source& w, const Json& j, const Path& path, LoadContext& c) {
    const auto given = std::find_if(kBodyKeys.begin(), kBodyKeys.end(),
                                    [&j](const char* key) { return optional(j, key) != nullptr; });
    if (given == kBodyKeys.end()) {
        return;
    }
    if (c.version == 1 || c.version == 2) {
        refuseBeforeVersion3(w, path / *given, *given);
    }
    if (!c.firstBodyField) {
        c.firstBodyField.emplace(c.objectIndex, *given);
    }
}

void refuseMeshInVersion1(const Source& w, const Path& shapePath) {
    w.fail(shapePath, "\"mesh\" needs \"version\": 2 (version 1 has boxes and spheres only)");
}

SceneObject parseObject(const Source& w, const Json& j, const Path& path, LoadContext& context) {
    object(w, j, path);
    SceneObject o;
    const Json& id = required(w, j, path, "id");
    if (!id.is_number_integer()) {
        w.fail(path / "id", "expected a non-negative integer, got " + typeName(id));
    }
    o.id = static_cast<ObjectId>(integer(w, id, path / "id", 0, kMaxObjectId));

    const Json& shape = required(w, j, path, "shape");
    if (!shape.is_string()) {
        w.fail(path / "shape",
               "expected a string (\"box\", \"sphere\" or \"mesh\"), got " + typeName(shape));
    }
    const auto& shapeText = shape.get_ref<const std::string&>();
    if (shapeText == "box") {
        o.shape = Shape::Box;
        checkKeys(w, j, path,
                  {"id", "shape", "center", "half_extents", "rotation", "stiffness", "friction",
                   "dynamic", "mass_kg", "density_kg_per_m3", "inertia", "restitution", "velocity",
                   "angular_velocity"});
        const Path he = path / "half_extents";
        o.halfExtents = vec3(w, required(w, j, path, "half_extents"), he);
        for (std::size_t i = 0; i < 3; ++i) {
            checkHalfExtent(w, o.halfExtents[static_cast<int>(i)], he[i]);
        }
    } else if (shapeText == "sphere") {
        o.shape = Shape::Sphere;
        checkKeys(w, j, path,
                  {"id", "shape", "center", "radius", "rotation", "stiffness", "friction",
                   "dynamic", "mass_kg", "density_kg_per_m3", "inertia", "restitution", "velocity",
                   "angular_velocity"});
        const Path rp = path / "radius";
        o.halfExtents = Vec3(checkRadius(w, number(w, required(w, j, path, "radius"), rp), rp));
    } else if (shapeText == "mesh") {
        if (context.version == 1) {
            refuseMeshInVersion1(w, path / "shape");
        }
        o.shape = Shape::Mesh;
        checkKeys(w, j, path,
                  {"id", "shape", "center", "rotation", "scale", "file", "vertices", "triangles",
                   "stiffness", "friction", "dynamic", "mass_kg", "density_kg_per_m3", "inertia",
                   "restitution", "velocity", "angular_velocity"});
        double scale = 1.0;
        if (const Json* v = optional(j, "scale")) {
            scale = checkMeshScale(w, number(w, *v, path / "scale"), path / "scale");
        }
        const bool hasFile = optional(j, "file") != nullptr;
        const bool hasInline = optional(j, "vertices") || optional(j, "triangles");
        if (hasFile == hasInline) {
            w.fail(path, hasFile ? "give either \"file\" or \"vertices\" and \"triangles\", "
                                   "not both"
                                 : "a mesh needs \"file\" (a model file) or \"vertices\" and "
                                   "\"triangles\"");
        }
        o.mesh = hasFile ? parseFileMesh(w, j, path, scale, context)
                         : parseInlineMesh(w, j, path, scale, context);
        o.halfExtents = o.mesh->localBounds().halfExtents();
    } else {
        w.fail(path / "shape",
               "unknown shape '" + shapeText + "' (expected \"box\", \"sphere\" or \"mesh\")");
    }
    o.center = vec3(w, required(w, j, path, "center"), path / "center");
    checkReach(w, o, path); // the bounding box must be finite too
    if (const Json* v = optional(j, "rotation")) {
        o.rotation = quaternion(w, *v, path / "rotation");
    }
    if (const Json* v = optional(j, "stiffness")) {
        const Path sp = path / "stiffness";
        o.material.stiffness = checkStiffness(w, number(w, *v, sp), sp);
    }
    if (const Json* v = optional(j, "friction")) {
        const Path fp = path / "friction";
        const auto f = numbers<2>(w, *v, fp);
        checkFriction(w, f[0], f[1], fp);
        o.material.staticFriction = f[0];
        o.material.dynamicFriction = f[1];
    }
    gateBodyFields(w, j, path, context);
    applyBodyFields(w, o, readBodyFields(w, j, path), path);
    return o;
}

Aabb parseBounds(const Source& w, const Json& j, const Path& path) {
    if (!j.is_object()) {
        w.fail(path, "expected an object {\"min\": [x,y,z], \"max\": [x,y,z]}, got " + typeName(j));
    }
    checkKeys(w, j, path, {"min", "max"});
    const Aabb b{vec3(w, required(w, j, path, "min"), path / "min"),
                 vec3(w, required(w, j, path, "max"), path / "max")};
    checkBounds(w, b, path);
    return b;
}

void appendNumber(std::string& out, double v) {
    // Negative zero as "-0.0": a JSON reader takes "-0" for the integer 0, so the sign would
    // not survive a round trip (friction -0 is valid: it is >= 0).
    if (v == 0.0 && std::signbit(v)) {
        out += "-0.0";
        return;
    }
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

/// A mesh's own fields: a file mesh by its file and scale; any other inline, its vertices as
/// held (scale applied) with scale 1. Flushes through `flush` as it goes, so a large inline
/// mesh never sits in one string either.
template <class Flush> void appendMesh(std::string& out, const TriangleMesh& mesh, Flush& flush) {
    if (!mesh.source().file.empty()) {
        out += ", \"scale\": ";
        appendNumber(out, mesh.source().scale);
        out += ", \"file\": ";
        out += Json(mesh.source().file).dump();
        return;
    }
    out += ", \"scale\": 1, \"vertices\": [";
    const auto vertices = mesh.vertices();
    for (std::size_t i = 0; i < vertices.size(); ++i) {
        out += i ? ", " : "";
        appendVec(out, &vertices[i].x, 3);
        if (out.size() > (1u << 20)) {
            flush();
        }
    }
    out += "], \"triangles\": [";
    const auto triangles = mesh.triangles();
    for (std::size_t i = 0; i < triangles.size(); ++i) {
        out += i ? ", [" : "[";
        for (int k = 0; k < 3; ++k) {
            out += k ? ", " : "";
            out += std::to_string(triangles[i][k]);
        }
        out += ']';
        if (out.size() > (1u << 20)) {
            flush();
        }
    }
    out += ']';
}

/// Refuses a NUL byte in a JSON scene's text (JSON has none: a control character must be
/// escaped even in a string), naming its line, column and byte; the parser would stop there
/// with "unexpected end of input". [control]
void refuseNulInJson(std::string_view text, std::string_view sourceName) {
    const void* p = std::memchr(text.data(), '\0', text.size());
    if (!p) {
        return;
    }
    const auto at = static_cast<std::size_t>(static_cast<const char*>(p) - text.data());
    const std::string_view before = text.substr(0, at);
    const auto line = 1 + std::count(before.begin(), before.end(), '\n');
    const std::size_t column = at - (before.rfind('\n') + 1) + 1; // npos + 1 is 0
    throw InputError(std::string(sourceName) + ":" + std::to_string(line) + ":" +
                     std::to_string(column) + ": not valid JSON: a NUL byte (byte " +
                     std::to_string(at) +
                     "); a scene file is JSON text or a binary hapto scene (HAPTOSCN)");
}

/// Converts a scene file's objects while the parser reads it, so a large file is never held as
/// one JSON tree. Depth 0 is the top-level object; its keys are reported at depth 1, and
/// elements of the "objects" array end at depth 2: each is converted as soon as it is complete,
/// then dropped. Inside an element of "objects", its keys are reported at depth 3, and the
/// elements of its "vertices" or "triangles" array end at depth 4: each is converted into the
/// context and dropped too (`mObjectKey` names the element's array being read, "" outside one).
class ObjectStream {
public:
    ObjectStream(const Source& w, const Path& objectsPath, LoadContext& context,
                 std::vector<SceneObject>& objects)
        : mW(w), mObjectsPath(objectsPath), mContext(context), mObjects(objects) {}

    /// The parser's callback: false drops what was just read (it has been converted).
    bool event(int depth, Json::parse_event_t event, Json& parsed) {
        switch (event) {
        case Json::parse_event_t::key:
            onKey(depth, parsed);
            return true;
        case Json::parse_event_t::object_start:
            if (mInObjects && depth == 2) {
                startObject();
            }
            return true;
        case Json::parse_event_t::array_start:
            onArrayStart(depth);
            return true;
        case Json::parse_event_t::array_end:
            if (depth == 1 || depth == 3) {
                (depth == 1 ? mInObjects : mInMeshArray) = false;
                return true;
            }
            [[fallthrough]]; // an array as an element of "objects": refused by parseObject
        case Json::parse_event_t::object_end:
        case Json::parse_event_t::value:
            return onComplete(depth, parsed);
        default:
            return true;
        }
    }

private:
    void onKey(int depth, const Json& parsed) {
        if (depth == 1) {
            mTopKey = parsed.get<std::string>();
        } else if (depth == 3 && mInObjects) {
            mObjectKey = parsed.get<std::string>();
        }
    }

    void startObject() {
        mContext.startObject();
        mObjectKey.clear();
    }

    void onArrayStart(int depth) {
        if (depth == 1 && mTopKey == "objects") {
            mInObjects = true;
        } else if (mInObjects && depth == 2) {
            startObject();
        } else if (mInObjects && depth == 3) {
            mInMeshArray = mObjectKey == "vertices" || mObjectKey == "triangles";
        }
    }

    /// A value, object or array is complete: a mesh element or an object is converted.
    bool onComplete(int depth, const Json& parsed) {
        if (mInObjects && depth == 4 && mInMeshArray) {
            const Path element = mObjectsPath[mObjects.size()];
            if (mObjectKey == "vertices") {
                streamVertex(mW, parsed, element / "vertices", mContext);
            } else {
                streamTriangle(mW, parsed, element / "triangles", mContext);
            }
            return false;
        }
        if (mInObjects && depth == 2) {
            mContext.objectIndex = mObjects.size();
            mObjects.push_back(parseObject(mW, parsed, mObjectsPath[mObjects.size()], mContext));
            return false;
        }
        if (depth == 1 && mTopKey == "version" && parsed.is_number_integer()) {
            mContext.version = parsed.get<std::int64_t>(); // checked later, used by meshes
        }
        return true;
    }

    const Source& mW;
    const Path& mObjectsPath;
    LoadContext& mContext;
    std::vector<SceneObject>& mObjects;
    std::string mTopKey;
    std::string mObjectKey;
    bool mInObjects = false;
    bool mInMeshArray = false;
};

/// The top level of a parsed scene file: its keys, "format", "version" (and no mesh in a
/// version 1 file: "version" may follow "objects", so meshes read before it are refused here)
/// and "objects" as an array.
void checkTopLevel(const Source& w, const Json& root, const std::vector<SceneObject>& objects,
                   const Path& objectsPath, const LoadContext& context) {
    const Path top;
    if (!root.is_object()) {
        w.fail(top,
               "expected a JSON object with \"format\": \"hapto-scene\", got " + typeName(root));
    }
    checkKeys(w, root, top, {"format", "version", "bounds", "objects", "gravity", "dynamics"});
    const Json& format = required(w, root, top, "format");
    if (!format.is_string() || format.get<std::string>() != "hapto-scene") {
        w.fail(top / "format", "expected \"hapto-scene\", got " + describe(format));
    }
    const Json& version = required(w, root, top, "version");
    if (!version.is_number_integer() || version.get<std::int64_t>() < 1 ||
        version.get<std::int64_t>() > kSceneFormatVersion) {
        w.fail(top / "version", "this build reads versions 1 to " +
                                    std::to_string(kSceneFormatVersion) + ", got " +
                                    describe(version));
    }
    if (version.get<std::int64_t>() == 1) {
        for (std::size_t i = 0; i < objects.size(); ++i) {
            if (objects[i].shape == Shape::Mesh) {
                refuseMeshInVersion1(w, objectsPath[i] / "shape");
            }
        }
    }
    if (version.get<std::int64_t>() < 3) {
        if (context.firstBodyField) {
            const auto [i, key] = *context.firstBodyField;
            refuseBeforeVersion3(w, objectsPath[i] / key, key);
        }
        for (const char* key : kPhysicsKeys) {
            if (optional(root, key)) {
                refuseBeforeVersion3(w, top / key, key);
            }
        }
    }
    const Json* objectsJson = optional(root, "objects");
    if (!objectsJson) {
        w.fail(top, "missing required field 'objects' (an array, possibly empty)");
    }
    if (!objectsJson->is_array()) {
        w.fail(objectsPath, "expected an array, got " + typeName(*objectsJson));
    }
}

/// The top level's "gravity" and "dynamics" (version 3), checked.
ScenePhysics parsePhysics(const Source& w, const Json& root) {
    const Path top;
    std::optional<Vec3> gravity;
    std::optional<double> rateHz;
    if (const Json* g = optional(root, "gravity")) {
        gravity = vec3(w, *g, top / "gravity");
    }
    if (const Json* d = optional(root, "dynamics")) {
        const Path dp = top / "dynamics";
        object(w, *d, dp);
        checkKeys(w, *d, dp, {"rate_hz"});
        if (const Json* r = optional(*d, "rate_hz")) {
            rateHz = number(w, *r, dp / "rate_hz");
        }
    }
    return checkPhysics(w, gravity, rateHz, top);
}

} // namespace

Scene parseSceneChecked(std::string_view text, std::string_view sourceName,
                        const std::filesystem::path& baseDir) {
    refuseNulInJson(text, sourceName);
    const Source w(sourceName);
    const Path top;
    const Path objectsPath = top / "objects";
    std::vector<SceneObject> objects;
    LoadContext context;
    context.baseDir = baseDir;
    ObjectStream stream(w, objectsPath, context, objects);
    const Json root =
        parseText(text, w, [&stream](int depth, Json::parse_event_t event, Json& parsed) {
            return stream.event(depth, event, parsed);
        });
    checkTopLevel(w, root, objects, objectsPath, context);
    checkUniqueIds(w, objects, objectsPath);
    const Json* boundsJson = optional(root, "bounds");
    std::optional<Aabb> bounds;
    if (boundsJson) {
        bounds = parseBounds(w, *boundsJson, top / "bounds");
    }
    const ScenePhysics physics = parsePhysics(w, root);
    Scene scene = finishScene(w, std::move(objects), bounds, objectsPath);
    scene.setPhysics(physics);
    return scene;
}

namespace {

/// Spare bytes kept after a scene file's text: simdjson reads up to SIMDJSON_PADDING (64) past
/// the end, and finds them in the string's capacity instead of copying the text.
constexpr std::size_t kReadPadding = 64;

/// How much of a scene file is looked at for a NUL byte before it is read whole (bytes).
constexpr std::size_t kHeadBytes = 4096;

/// The scene file's bytes, read once into a string of exactly their size (a file that reports
/// no size, as in /proc, is read as it comes). A JSON scene with a NUL byte in its first
/// kHeadBytes (a file of zeros) is refused before it is read whole. [control]
std::string readSceneFile(const std::filesystem::path& path) {
    InputFile file(path, "scene file");
    if (file.size() == 0) {
        return file.readAll();
    }
    if (const std::string head = file.readHead(kHeadBytes); !isBinaryScene(head)) {
        refuseNulInJson(head, path.string());
    }
    std::string text;
    text.reserve(file.size() + kReadPadding);
    text.resize(file.size());
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(file.releaseToStdio(), &std::fclose);
    const std::size_t got = std::fread(text.data(), 1, text.size(), f.get());
    if (std::ferror(f.get())) {
        throw InputError(path.string() + ": cannot read the scene file");
    }
    if (got != text.size() || std::fgetc(f.get()) != EOF) {
        throw InputError(path.string() + ": the scene file changed size while it was read");
    }
    return text;
}

} // namespace

Scene loadSceneFile(const std::filesystem::path& path) {
    const std::string text = readSceneFile(path);
    if (isBinaryScene(text)) {
        return parseBinaryScene(text, path.string(), path.parent_path());
    }
    // The string's spare capacity is simdjson's padding when there is enough of it.
    if (auto scene = detail::parseSceneFast(text, text.capacity(), path.string())) {
        return std::move(*scene);
    }
    return parseSceneChecked(text, path.string(), path.parent_path());
}

Scene parseScene(std::string_view text, std::string_view sourceName,
                 const std::filesystem::path& baseDir) {
    if (auto scene = detail::parseSceneFast(text, text.size(), sourceName)) {
        return std::move(*scene);
    }
    return parseSceneChecked(text, sourceName, baseDir);
}

namespace {

/// The scene's "gravity" and "dynamics" (version 3: always both, explicit).
void appendPhysics(std::string& out, const ScenePhysics& physics) {
    out += ",\n \"gravity\": ";
    appendVec(out, &physics.gravity.x, 3);
    out += ", \"dynamics\": {\"rate_hz\": ";
    appendNumber(out, physics.rateHz);
    out += '}';
}

/// An object's version-3 fields: a restitution other than 0; a dynamic body's mass, full
/// inertia tensor (rows) and velocities. Nothing for a static object without restitution.
void appendBody(std::string& out, const BodyProperties& b) {
    if (b.dynamic) {
        out += ", \"dynamic\": true, \"mass_kg\": ";
        appendNumber(out, b.massKg);
        out += ", \"inertia\": [";
        for (int r = 0; r < 3; ++r) {
            const double row[3] = {b.inertia[0][r], b.inertia[1][r], b.inertia[2][r]};
            out += r ? ", " : "";
            appendVec(out, row, 3);
        }
        out += ']';
    }
    if (b.restitution != 0.0 || b.dynamic) {
        out += ", \"restitution\": ";
        appendNumber(out, b.restitution);
    }
    if (b.dynamic) {
        out += ", \"velocity\": ";
        appendVec(out, &b.velocity.x, 3);
        out += ", \"angular_velocity\": ";
        appendVec(out, &b.angularVelocity.x, 3);
    }
}

// Streams the JSON in chunks of about a megabyte, so 10^7 objects never sit in one string.
void writeSceneJson(const Scene& scene, std::ostream& os) {
    std::string out;
    out.reserve(1 << 21);
    const auto flush = [&] {
        os.write(out.data(), static_cast<std::streamsize>(out.size()));
        out.clear();
    };
    // A scene without meshes is written as version 1, byte for byte as before version 2.
    const int version = sceneFormatVersionOf(scene);
    out += "{\"format\": \"hapto-scene\", \"version\": ";
    out += std::to_string(version);
    if (version >= 3) {
        appendPhysics(out, scene.physics());
    }
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
        } else if (o.shape == Shape::Mesh) {
            const double q[4] = {o.rotation.w, o.rotation.x, o.rotation.y, o.rotation.z};
            out += ", \"rotation\": ";
            appendVec(out, q, 4);
            appendMesh(out, *o.mesh, flush);
        } else {
            out += ", \"radius\": ";
            appendNumber(out, o.halfExtents.x);
            // A sphere's orientation does not change its shape, but it is part of the object
            // (a grasp turns it): written when it is not the identity, so the file reads back
            // to the same scene.
            if (o.rotation != Quat(1, 0, 0, 0)) {
                const double q[4] = {o.rotation.w, o.rotation.x, o.rotation.y, o.rotation.z};
                out += ", \"rotation\": ";
                appendVec(out, q, 4);
            }
        }
        out += ", \"stiffness\": ";
        appendNumber(out, o.material.stiffness);
        const double f[2] = {o.material.staticFriction, o.material.dynamicFriction};
        out += ", \"friction\": ";
        appendVec(out, f, 2);
        appendBody(out, o.body);
        out += '}';
        if (out.size() > (1u << 20)) {
            flush();
        }
    }
    out += "]}\n";
    flush();
}

} // namespace

int sceneFormatVersionOf(const Scene& scene) {
    const auto objects = scene.objects();
    const bool bodies = std::any_of(objects.begin(), objects.end(), [](const SceneObject& o) {
        return o.body.dynamic || o.body.restitution != 0.0;
    });
    if (bodies || scene.physics() != ScenePhysics{}) {
        return kSceneFormatVersion;
    }
    // A mesh has at least one triangle, so triangleCount() tells.
    return scene.triangleCount() > 0 ? kSceneFormatVersionWithMeshes
                                     : kSceneFormatVersionWithoutMeshes;
}

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
