// libFuzzer target: the model file reader (OBJ, STL, PLY: hapto's own readers). The first
// byte picks the format (its value mod 3: .obj, .stl, .ply), the rest is the file. Any input
// either loads or is refused with an InputError; nothing else may escape, crash, hang or leak.
// A mesh that loaded is one the renderer can use: at least one and at most kMaxTriangles
// triangles, every vertex finite, every index in range, vertices welded (no two at the same
// position), every triangle's plane a unit normal or zero, and its local BVH finds every
// triangle exactly once over the mesh's bounds.

#include "hapto/io/InputError.h"
#include "hapto/scenes/MeshFile.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

namespace {

void check(bool ok) {
    if (!ok) {
        __builtin_trap();
    }
}

void checkMesh(const hapto::TriangleMesh& mesh) {
    const auto vertices = mesh.vertices();
    const auto triangles = mesh.triangles();
    check(mesh.triangleCount() >= 1 && mesh.triangleCount() <= hapto::TriangleMesh::kMaxTriangles);
    for (const hapto::Vec3& v : vertices) {
        check(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z));
    }
    for (const hapto::TriangleIndices& t : triangles) {
        for (const std::uint32_t i : t) {
            check(i < vertices.size());
        }
    }
    std::vector<std::tuple<double, double, double>> positions;
    positions.reserve(vertices.size());
    for (const hapto::Vec3& v : vertices) {
        positions.emplace_back(v.x, v.y, v.z);
    }
    std::sort(positions.begin(), positions.end());
    check(std::adjacent_find(positions.begin(), positions.end()) == positions.end());
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const hapto::Vec3 n = mesh.face(t).normal;
        const double length2 = n.x * n.x + n.y * n.y + n.z * n.z;
        check(length2 == 0.0 || std::abs(length2 - 1.0) < 1e-9);
    }
    std::vector<std::uint32_t> found(mesh.triangleCount(), 0);
    mesh.forEachTriangleNear(mesh.localBounds(), [&](std::uint32_t t) {
        check(t < found.size());
        ++found[t];
    });
    check(std::all_of(found.begin(), found.end(), [](std::uint32_t n) { return n == 1; }));
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) {
        return 0;
    }
    static const std::array<const char*, 3> kNames = {"fuzz.obj", "fuzz.stl", "fuzz.ply"};
    const char* name = kNames[data[0] % 3];
    try {
        const auto mesh = hapto::parseMeshFile(
            std::string(reinterpret_cast<const char*>(data) + 1, size - 1), name, {});
        checkMesh(*mesh);
    } catch (const hapto::InputError&) {
    }
    return 0;
}
