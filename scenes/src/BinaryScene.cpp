// The binary scene file (layout: BinaryScene.h). Design note: the reader trusts nothing. The
// header's sizes must add up to the file's size exactly before anything is allocated, so a
// count cannot ask for more memory than the file holds; every value then goes through the
// JSON loader's own checks (SceneFileChecks.h), with the JSON path of the value, and a refusal
// is rethrown with the byte offset of the field, record or mesh entry it came from. Cost: one
// pass over the records, no parsing; 10^6 objects are 112 MB.

#include "hapto/scenes/BinaryScene.h"

#include "hapto/io/InputError.h"
#include "hapto/io/JsonInput.h"
#include "hapto/scenes/SceneFile.h"

#include "SceneFileChecks.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <optional>
#include <sstream>
#include <vector>

namespace hapto {
namespace {

using json::Path;
using json::Source;

static_assert(std::endian::native == std::endian::little,
              "the binary scene format is little-endian; this build reads it by memcpy");

constexpr std::uint32_t kMeshKindFile = 0;
constexpr std::uint32_t kMeshKindInline = 1;
constexpr std::uint64_t kMaxModelPathBytes = 4096;
constexpr std::uint64_t kMeshEntryHeadBytes = 16; // kind, zero, scale

template <class T> T load(const char* p) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return v;
}

/// "NAME: byte OFFSET: what". [control]
[[noreturn]] void failAt(std::string_view name, std::uint64_t offset, const std::string& what) {
    throw InputError(std::string(name) + ": byte " + std::to_string(offset) + ": " + what);
}

/// Runs `check`, which fails through `source` ("NAME: path: what"); a refusal is rethrown
/// with the byte offset after the name. [control]
template <class F> auto atOffset(const Source& source, std::uint64_t offset, F&& check) {
    try {
        return check();
    } catch (const InputError& e) {
        const std::string_view what = e.what();
        const std::string prefix = std::string(source.name()) + ": ";
        failAt(source.name(), offset,
               std::string(what.starts_with(prefix) ? what.substr(prefix.size()) : what));
    }
}

Vec3 finiteVec3(const Source& s, const char* p, const Path& path) {
    Vec3 v;
    for (int i = 0; i < 3; ++i) {
        v[i] = json::finiteNumber(s, load<double>(p + 8 * i), path[static_cast<std::size_t>(i)]);
    }
    return v;
}

/// One object record (mesh objects get their mesh later, from the mesh section). [control]
SceneObject readRecord(const Source& s, const char* r, const Path& path) {
    SceneObject o;
    o.id = load<std::uint32_t>(r);
    if (o.id > kMaxObjectId) {
        s.fail(path / "id", "must be in 0.." + std::to_string(kMaxObjectId) + " (got " +
                                std::to_string(o.id) + ")");
    }
    const std::uint8_t shape = load<std::uint8_t>(r + 4);
    if (shape > 2) {
        s.fail(path / "shape",
               "unknown shape code " + std::to_string(shape) + " (0 box, 1 sphere, 2 mesh)");
    }
    if (r[5] != 0 || r[6] != 0 || r[7] != 0) {
        s.fail(path, "the three bytes after the shape must be zero");
    }
    o.shape = static_cast<Shape>(shape);
    o.center = finiteVec3(s, r + 8, path / "center");
    const Path hp = path / (o.shape == Shape::Sphere ? "radius" : "half_extents");
    const Vec3 half = finiteVec3(s, r + 32, hp);
    if (o.shape == Shape::Box) {
        for (std::size_t i = 0; i < 3; ++i) {
            detail::checkHalfExtent(s, half[static_cast<int>(i)], hp[i]);
        }
        o.halfExtents = half;
    } else if (o.shape == Shape::Sphere) {
        detail::checkRadius(s, half.x, hp);
        if (half.y != half.x || half.z != half.x) {
            s.fail(hp, "a sphere's record holds its radius three times, got " + json::show(half.x) +
                           ", " + json::show(half.y) + ", " + json::show(half.z));
        }
        o.halfExtents = half;
    } else if (half != Vec3(0.0)) {
        s.fail(path / "half_extents", "a mesh's record holds zero half extents (its bounds "
                                      "come from its mesh)");
    }
    std::array<double, 4> q{};
    const Path qp = path / "rotation";
    for (std::size_t i = 0; i < 4; ++i) {
        q[i] = json::finiteNumber(s, load<double>(r + 56 + 8 * i), qp[i]);
    }
    o.rotation = json::unitQuaternion(s, q, qp);
    const Path sp = path / "stiffness";
    o.material.stiffness =
        detail::checkStiffness(s, json::finiteNumber(s, load<double>(r + 88), sp), sp);
    const Path fp = path / "friction";
    const double mu0 = json::finiteNumber(s, load<double>(r + 96), fp[0]);
    const double mu1 = json::finiteNumber(s, load<double>(r + 104), fp[1]);
    detail::checkFriction(s, mu0, mu1, fp);
    o.material.staticFriction = mu0;
    o.material.dynamicFriction = mu1;
    if (o.shape != Shape::Mesh) {
        detail::checkReach(s, o, path);
    }
    return o;
}

/// Reads the mesh entries into the mesh objects, in slot order. [control]
void readMeshes(const Source& s, std::string_view section, std::uint64_t sectionOffset,
                std::vector<SceneObject>& objects, const Path& objectsPath,
                const std::filesystem::path& baseDir) {
    detail::ModelCache models;
    std::uint64_t at = 0; // within the section
    const auto left = [&] { return section.size() - at; };
    for (std::size_t slot = 0; slot < objects.size(); ++slot) {
        SceneObject& o = objects[slot];
        if (o.shape != Shape::Mesh) {
            continue;
        }
        const Path path = objectsPath[slot];
        const std::uint64_t entry = sectionOffset + at;
        if (left() < kMeshEntryHeadBytes + 8) {
            failAt(s.name(), entry,
                   path.str() + ": the mesh section ends before this mesh object's entry");
        }
        const char* p = section.data() + at;
        const auto kind = load<std::uint32_t>(p);
        if ((kind != kMeshKindFile && kind != kMeshKindInline) || load<std::uint32_t>(p + 4) != 0) {
            failAt(s.name(), entry,
                   path.str() + ": unknown mesh entry kind " + std::to_string(kind) +
                       " (0 a model file, 1 inline), or its next 4 bytes are not zero");
        }
        const double scale = atOffset(s, entry + 8, [&] {
            const Path scp = path / "scale";
            return detail::checkMeshScale(s, json::finiteNumber(s, load<double>(p + 8), scp), scp);
        });
        if (kind == kMeshKindFile) {
            const auto length = load<std::uint64_t>(p + 16);
            if (length == 0 || length > kMaxModelPathBytes || length > left() - 24) {
                failAt(s.name(), entry + 16,
                       path.str() + ".file: the path length " + std::to_string(length) +
                           " must be 1.." + std::to_string(kMaxModelPathBytes) +
                           " and within the mesh section (" + std::to_string(left() - 24) +
                           " bytes left)");
            }
            const std::string file(p + 24, length);
            if (file.find('\0') != std::string::npos) {
                failAt(s.name(), entry + 24, path.str() + ".file: the path holds a NUL byte");
            }
            o.mesh = atOffset(s, entry + 24, [&] {
                try {
                    return detail::loadModel(models, baseDir, file, scale);
                } catch (const InputError& e) {
                    s.fail(path / "file", e.what());
                }
            });
            at += 24 + length;
        } else {
            if (left() < 32) {
                failAt(s.name(), entry,
                       path.str() + ": the mesh section ends inside this mesh entry's counts");
            }
            const auto vertexCount = load<std::uint64_t>(p + 16);
            const auto triangleCount = load<std::uint64_t>(p + 24);
            if (vertexCount > TriangleMesh::kMaxVertices ||
                triangleCount > TriangleMesh::kMaxTriangles) {
                failAt(s.name(), entry + 16,
                       path.str() + ": " + std::to_string(vertexCount) + " vertices and " +
                           std::to_string(triangleCount) + " triangles; a mesh may have at most " +
                           std::to_string(TriangleMesh::kMaxVertices) + " and " +
                           std::to_string(TriangleMesh::kMaxTriangles));
            }
            const std::uint64_t bytes = 24 * vertexCount + 12 * triangleCount;
            if (bytes > left() - 32) {
                failAt(s.name(), entry + 16,
                       path.str() + ": " + std::to_string(vertexCount) + " vertices and " +
                           std::to_string(triangleCount) + " triangles need " +
                           std::to_string(bytes) + " bytes; the mesh section has " +
                           std::to_string(left() - 32) + " left");
            }
            const char* v = p + 32;
            std::vector<Vec3> vertices(vertexCount);
            for (std::size_t i = 0; i < vertexCount; ++i) {
                vertices[i] = atOffset(s, entry + 32 + 24 * i, [&] {
                    return finiteVec3(s, v + 24 * i, (path / "vertices")[i]);
                });
            }
            const char* t = v + 24 * vertexCount;
            std::vector<TriangleIndices> triangles(triangleCount);
            if (triangleCount > 0) { // memcpy from or to null is undefined, even for 0 bytes
                std::memcpy(triangles.data(), t, 12 * triangleCount);
            }
            static_assert(sizeof(TriangleIndices) == 12);
            o.mesh = atOffset(s, entry, [&] {
                return detail::makeInlineMesh(s, path, std::move(vertices), std::move(triangles),
                                              scale, 0, std::nullopt);
            });
            at += 32 + bytes;
        }
        o.halfExtents = o.mesh->localBounds().halfExtents();
        atOffset(s, entry, [&] { detail::checkReach(s, o, path); });
    }
    if (at != section.size()) {
        failAt(s.name(), sectionOffset + at,
               std::to_string(section.size() - at) +
                   " bytes after the last mesh entry; the mesh section must end with it");
    }
}

template <class T> void put(std::string& out, T v) {
    char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    out.append(b, sizeof v);
}

void putVec(std::string& out, const Vec3& v) {
    put(out, v.x);
    put(out, v.y);
    put(out, v.z);
}

} // namespace

bool isBinaryScene(std::string_view bytes) {
    return bytes.starts_with(kBinarySceneMagic);
}

Scene parseBinaryScene(std::string_view bytes, std::string_view sourceName,
                       const std::filesystem::path& baseDir) {
    const Source s(sourceName);
    if (bytes.size() < kBinarySceneHeaderBytes) {
        failAt(sourceName, 0,
               "the file has " + std::to_string(bytes.size()) +
                   " bytes, fewer than the binary scene header's " +
                   std::to_string(kBinarySceneHeaderBytes));
    }
    if (!isBinaryScene(bytes)) {
        failAt(sourceName, 0, "not a binary hapto scene (the magic \"HAPTOSCN\" is missing)");
    }
    const char* h = bytes.data();
    if (const auto v = load<std::uint32_t>(h + 8); v != kBinarySceneVersion) {
        failAt(sourceName, 8,
               "this build reads binary scene version " + std::to_string(kBinarySceneVersion) +
                   ", got " + std::to_string(v));
    }
    if (const auto v = load<std::uint32_t>(h + 12); v != kBinarySceneHeaderBytes) {
        failAt(sourceName, 12,
               "the header size must be " + std::to_string(kBinarySceneHeaderBytes) + ", got " +
                   std::to_string(v));
    }
    if (const auto v = load<std::uint32_t>(h + 16); v != kBinarySceneRecordBytes) {
        failAt(sourceName, 16,
               "the object record size must be " + std::to_string(kBinarySceneRecordBytes) +
                   ", got " + std::to_string(v));
    }
    if (const auto v = load<std::uint32_t>(h + 20); v != 0) {
        failAt(sourceName, 20, "the flags must be 0 (reserved), got " + std::to_string(v));
    }
    const auto count = load<std::uint64_t>(h + 24);
    const auto meshBytes = load<std::uint64_t>(h + 32);
    const std::uint64_t recordsSpace = bytes.size() - kBinarySceneHeaderBytes;
    if (count > std::numeric_limits<std::uint32_t>::max() ||
        count > recordsSpace / kBinarySceneRecordBytes ||
        meshBytes != recordsSpace - count * kBinarySceneRecordBytes) {
        failAt(sourceName, 24,
               "the header's " + std::to_string(count) + " objects and " +
                   std::to_string(meshBytes) + " mesh section bytes do not add up to the file's " +
                   std::to_string(bytes.size()) + " bytes (header " +
                   std::to_string(kBinarySceneHeaderBytes) + " + " +
                   std::to_string(kBinarySceneRecordBytes) +
                   " per object + mesh section); the file is truncated or damaged");
    }
    const Path top;
    const Aabb bounds = atOffset(s, 40, [&] {
        const Aabb b{finiteVec3(s, h + 40, top / "bounds" / "min"),
                     finiteVec3(s, h + 64, top / "bounds" / "max")};
        detail::checkBounds(s, b, top / "bounds");
        return b;
    });
    if (load<std::uint64_t>(h + 88) != 0) {
        failAt(sourceName, 88, "the reserved header bytes must be zero");
    }

    const Path objectsPath = top / "objects";
    std::vector<SceneObject> objects;
    objects.reserve(count);
    bool hasMesh = false;
    for (std::uint64_t i = 0; i < count; ++i) {
        const std::uint64_t offset = kBinarySceneHeaderBytes + i * kBinarySceneRecordBytes;
        objects.push_back(atOffset(
            s, offset, [&] { return readRecord(s, bytes.data() + offset, objectsPath[i]); }));
        hasMesh = hasMesh || objects.back().shape == Shape::Mesh;
    }
    const std::uint64_t sectionOffset = kBinarySceneHeaderBytes + count * kBinarySceneRecordBytes;
    if (hasMesh || meshBytes != 0) {
        readMeshes(s, bytes.substr(sectionOffset), sectionOffset, objects, objectsPath, baseDir);
    }
    return atOffset(s, kBinarySceneHeaderBytes, [&] {
        detail::checkUniqueIds(s, objects, objectsPath);
        return detail::finishScene(s, std::move(objects), bounds, objectsPath);
    });
}

void writeBinaryScene(const Scene& scene, std::ostream& os) {
    if (sceneFormatVersionOf(scene) >= 3) {
        throw InputError("the scene has dynamic bodies, restitution or non-default physics (scene "
                         "format version 3), which the binary format does not carry: write it "
                         "as JSON (-o F.json)");
    }
    std::string out; // flushed past 1 MB: room for that, or for the whole of a small scene
    out.reserve(
        std::min<std::size_t>(std::size_t{1} << 21, 4096 + 512 * std::size_t{scene.size()}));
    const auto flush = [&] {
        os.write(out.data(), static_cast<std::streamsize>(out.size()));
        out.clear();
    };
    // The mesh section first, into its own buffer, for its size in the header (meshes are few
    // and their triangles dominate; a scene of boxes has an empty section).
    std::string meshes;
    for (const SceneObject& o : scene.objects()) {
        if (o.shape != Shape::Mesh) {
            continue;
        }
        const TriangleMesh& m = *o.mesh;
        const bool file = !m.source().file.empty();
        put(meshes, file ? kMeshKindFile : kMeshKindInline);
        put(meshes, std::uint32_t{0});
        put(meshes, file ? m.source().scale : 1.0);
        if (file) {
            put(meshes, std::uint64_t{m.source().file.size()});
            meshes += m.source().file;
            continue;
        }
        put(meshes, std::uint64_t{m.vertices().size()});
        put(meshes, std::uint64_t{m.triangles().size()});
        for (const Vec3& v : m.vertices()) {
            putVec(meshes, v);
        }
        for (const TriangleIndices& t : m.triangles()) {
            put(meshes, t[0]);
            put(meshes, t[1]);
            put(meshes, t[2]);
        }
    }
    out.append(kBinarySceneMagic);
    put(out, kBinarySceneVersion);
    put(out, kBinarySceneHeaderBytes);
    put(out, kBinarySceneRecordBytes);
    put(out, std::uint32_t{0});
    put(out, std::uint64_t{scene.size()});
    put(out, std::uint64_t{meshes.size()});
    putVec(out, scene.bounds().min);
    putVec(out, scene.bounds().max);
    put(out, std::uint64_t{0});
    for (const SceneObject& o : scene.objects()) {
        put(out, o.id);
        put(out, static_cast<std::uint8_t>(o.shape));
        out.append(3, '\0');
        putVec(out, o.center);
        putVec(out, o.shape == Shape::Mesh ? Vec3(0.0) : o.halfExtents);
        put(out, o.rotation.w);
        put(out, o.rotation.x);
        put(out, o.rotation.y);
        put(out, o.rotation.z);
        put(out, o.material.stiffness);
        put(out, o.material.staticFriction);
        put(out, o.material.dynamicFriction);
        if (out.size() > (1u << 20)) {
            flush();
        }
    }
    flush();
    os.write(meshes.data(), static_cast<std::streamsize>(meshes.size()));
}

std::string sceneToBinary(const Scene& scene) {
    std::ostringstream os;
    writeBinaryScene(scene, os);
    return std::move(os).str();
}

} // namespace hapto
