// Model files read by hapto's own readers. Design note: the file is opened once through
// InputFile (a regular file of bounded size, never a FIFO or a folder), its first bytes and size
// checked (checkHead) before it is read whole, then read by the reader of its format
// (ObjReader.cpp, StlReader.cpp, PlyReader.cpp: one pass each, the first bad thing refused with
// its place) into positions and faces; the faces are cut into triangles
// (PolygonTriangulation.cpp), the positions scaled, and vertices at exactly the same position
// merged (weld(): one sort), so triangles that share an edge share its vertex indices, as the
// renderer needs. hapto once handed the checked bytes to assimp 5.2.5; the readers give the
// same meshes (MeshFileTests compares them with figures assimp gave) from one parse.

#include "hapto/scenes/MeshFile.h"

#include "MeshReading.h"

#include "hapto/core/Finite.h"
#include "hapto/io/InputError.h"
#include "hapto/io/InputFile.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numeric>
#include <optional>
#include <vector>

namespace hapto {
namespace {

std::optional<detail::MeshFormat> formatOf(const std::filesystem::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (ext == ".obj") {
        return detail::MeshFormat::Obj;
    }
    if (ext == ".stl") {
        return detail::MeshFormat::Stl;
    }
    if (ext == ".ply") {
        return detail::MeshFormat::Ply;
    }
    return std::nullopt;
}

/// How much of a model file checkHead looks at before the file is read whole (bytes).
constexpr std::size_t kHeadBytes = 4096;

void checkScale(const std::string& name, double scale) {
    if (!(std::isfinite(scale) && scale > 0.0)) {
        throw InputError(name + ": the scale must be a finite number > 0");
    }
}

/// The format the path's extension names; throws InputError for any other.
detail::MeshFormat knownFormat(const std::filesystem::path& path) {
    const auto format = formatOf(path);
    if (!format) {
        throw InputError(path.string() + ": unknown model format '" + path.extension().string() +
                         "' (hapto reads .obj, .stl and .ply)");
    }
    return *format;
}

/// Refuses a model file from its first bytes and its size, before it is read whole: an STL
/// that is neither ASCII nor binary of its header's size (checkStlHead); an OBJ with a NUL byte
/// in `head`; a PLY with a NUL byte before its header ends.
void checkHead(detail::MeshFormat format, std::string_view head, std::uint64_t size,
               const std::string& name) {
    if (size == 0) {
        return; // empty, or a file that reports no size (/proc): the whole file's check decides
    }
    switch (format) {
    case detail::MeshFormat::Obj:
        detail::refuseNul(head, name, "an OBJ text file");
        break;
    case detail::MeshFormat::Stl:
        detail::checkStlHead(head, size, name);
        break;
    case detail::MeshFormat::Ply:
        detail::refuseNul(head.substr(0, head.find("end_header")), name,
                          "a PLY file (its header is text)");
        break;
    }
}

/// The model's vertices and triangles, as hapto keeps them before scaling.
struct Gathered {
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
};

/// Reads `bytes` with the reader of `format`, and cuts the faces into triangles.
Gathered read(detail::MeshFormat format, std::string& bytes, const std::string& name,
              double scale) {
    detail::ModelFaces model;
    detail::NgonRotation rotation = detail::NgonRotation::None;
    switch (format) {
    case detail::MeshFormat::Obj:
        if (bytes.starts_with("\xEF\xBB\xBF")) {
            bytes.erase(0, 3); // a UTF-8 byte order mark
        }
        detail::blankObjComments(bytes);
        model = detail::readObj(bytes, name, scale);
        rotation = detail::NgonRotation::WithinFace;
        break;
    case detail::MeshFormat::Stl:
        model = detail::readStl(bytes, name, scale);
        break;
    case detail::MeshFormat::Ply:
        model = detail::readPly(bytes, name, scale);
        rotation = detail::NgonRotation::AcrossFaces;
        break;
    }
    std::string().swap(bytes); // read: the model holds what is needed
    std::vector<TriangleIndices> triangles = detail::triangulate(model, rotation);
    return {std::move(model.vertices), std::move(triangles)};
}

/// Merges vertices at exactly the same position; rewrites the triangles' indices.
void weld(Gathered& g) {
    std::vector<std::uint32_t> order(g.vertices.size());
    std::iota(order.begin(), order.end(), 0u);
    const auto less = [&](std::uint32_t a, std::uint32_t b) {
        const Vec3& p = g.vertices[a];
        const Vec3& q = g.vertices[b];
        return p.x != q.x ? p.x < q.x : p.y != q.y ? p.y < q.y : p.z < q.z;
    };
    std::sort(order.begin(), order.end(), less);
    std::vector<std::uint32_t> remap(g.vertices.size());
    std::vector<Vec3> kept;
    kept.reserve(g.vertices.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
        if (i == 0 || g.vertices[order[i]] != kept.back()) {
            kept.push_back(g.vertices[order[i]]);
        }
        remap[order[i]] = static_cast<std::uint32_t>(kept.size() - 1);
    }
    for (TriangleIndices& t : g.triangles) {
        for (std::uint32_t& i : t) {
            i = remap[i];
        }
    }
    g.vertices = std::move(kept);
}

} // namespace

bool isMeshFile(const std::filesystem::path& path) {
    return formatOf(path).has_value();
}

std::shared_ptr<const TriangleMesh> loadMeshFile(const std::filesystem::path& path,
                                                 MeshSource source) {
    const std::string name = path.string();
    checkScale(name, source.scale);
    // Opened first, so a folder or a FIFO is named as such whatever its name.
    InputFile file(path, "model file");
    // A file its first bytes and size refuse (a 2 GB STL of zeros) is never read whole.
    checkHead(knownFormat(path), file.readHead(kHeadBytes), file.size(), name);
    return parseMeshFile(file.readAll(), path, std::move(source));
}

std::shared_ptr<const TriangleMesh>
parseMeshFile(std::string bytes, const std::filesystem::path& path, MeshSource source) {
    const std::string name = path.string();
    checkScale(name, source.scale);
    const detail::MeshFormat format = knownFormat(path);
    if (bytes.empty()) {
        throw InputError(name + ": the model file is empty");
    }

    Gathered g = read(format, bytes, name, source.scale);
    for (Vec3& v : g.vertices) {
        const Vec3 scaled = v * source.scale;
        if (!finite(scaled)) {
            throw InputError(name + ": the vertex (" + std::to_string(v.x) + ", " +
                             std::to_string(v.y) + ", " + std::to_string(v.z) +
                             ") times the scale " + std::to_string(source.scale) +
                             " is not finite");
        }
        v = scaled;
    }
    weld(g);
    return TriangleMesh::make(std::move(g.vertices), std::move(g.triangles), std::move(source),
                              name);
}

} // namespace hapto
