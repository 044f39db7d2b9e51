// Model files through assimp. Design note: the file is opened once through InputFile (a
// regular file of bounded size, never a FIFO or a folder) and read whole; its bytes are checked
// for what assimp misses (MeshFileChecks.cpp) and then handed to assimp from memory, so the
// bytes checked are the bytes read. assimp runs with the least post-processing that gives
// triangles: Triangulate (polygons to triangles) and ValidateDataStructure (a last net for
// indices out of range). Its meshes are then gathered through the node tree (with the node
// transforms) into one mesh, and vertices at exactly the same position are merged (weld(): one
// sort), so triangles that share an edge share its vertex indices, as the renderer needs.
// assimp's own JoinIdenticalVertices is not used: it merges only within one of its meshes and
// only corners whose normals and texture coordinates agree too (so weld() is needed anyway),
// and on a 10^6-triangle binary STL it took 2.2 s of a 3 s load and 450 MB of its 720 MB peak
// (assimp 5.2.5, this machine; see docs/DESIGN.md).

#include "hapto/scenes/MeshFile.h"

#include "MeshFileChecks.h"

#include "hapto/core/Finite.h"
#include "hapto/io/InputError.h"
#include "hapto/io/InputFile.h"

#include <assimp/IOStream.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

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

const char* hintOf(detail::MeshFormat f) {
    switch (f) {
    case detail::MeshFormat::Obj:
        return "obj";
    case detail::MeshFormat::Stl:
        return "stl";
    case detail::MeshFormat::Ply:
        return "ply";
    }
    return "";
}

/// The files assimp may open while it reads a model from memory: none. An OBJ may name material
/// libraries (`mtllib`), which assimp's default IOSystem opens from disk by those names: a FIFO
/// blocks the load forever, a device or any other file is read as a material and can get the
/// model refused. hapto reads geometry only, so to assimp every other file is missing (it notes
/// that and goes on without materials).
class NoOtherFiles final : public Assimp::IOSystem {
public:
    bool Exists(const char*) const override { return false; }
    char getOsSeparator() const override { return '/'; }
    Assimp::IOStream* Open(const char*, const char*) override { return nullptr; }
    void Close(Assimp::IOStream* stream) override { delete stream; }
};

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

struct Gathered {
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
};

/// Appends every triangle of the node's meshes and its children's, placed by the accumulated
/// node transform; points and lines (faces of 1 or 2 indices) are skipped.
void gather(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent, Gathered& out) {
    const aiMatrix4x4 transform = parent * node.mTransformation;
    for (unsigned m = 0; m < node.mNumMeshes; ++m) {
        const aiMesh& mesh = *scene.mMeshes[node.mMeshes[m]];
        const auto base = static_cast<std::uint32_t>(out.vertices.size());
        for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
            const aiVector3D p = transform * mesh.mVertices[v];
            out.vertices.emplace_back(p.x, p.y, p.z);
        }
        for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
            const aiFace& face = mesh.mFaces[f];
            if (face.mNumIndices == 3) {
                out.triangles.push_back(
                    {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
            }
        }
    }
    for (unsigned c = 0; c < node.mNumChildren; ++c) {
        gather(scene, *node.mChildren[c], transform, out);
    }
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
    detail::checkHead(knownFormat(path), file.readHead(kHeadBytes), file.size(), name);
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
    switch (format) {
    case detail::MeshFormat::Obj:
        if (bytes.starts_with("\xEF\xBB\xBF")) {
            bytes.erase(0, 3); // a UTF-8 byte order mark: assimp 5.2.5 would lose the first line
        }
        detail::blankObjComments(bytes);
        detail::checkObj(bytes, name, source.scale);
        break;
    case detail::MeshFormat::Stl:
        detail::checkStl(bytes, name, source.scale);
        break;
    case detail::MeshFormat::Ply:
        detail::checkPly(bytes, name, source.scale);
        break;
    }

    Assimp::Importer importer;
    importer.SetIOHandler(new NoOtherFiles); // owned by the importer
    const aiScene* scene = importer.ReadFileFromMemory(
        bytes.data(), bytes.size(), aiProcess_Triangulate | aiProcess_ValidateDataStructure,
        hintOf(format));
    if (!scene || !scene->mRootNode) {
        throw InputError(name + ": the " + hintOf(format) +
                         " reader (assimp) refuses it: " + importer.GetErrorString());
    }
    std::string().swap(bytes); // assimp has its own copy now

    Gathered g;
    gather(*scene, *scene->mRootNode, aiMatrix4x4(), g);
    importer.FreeScene();
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
