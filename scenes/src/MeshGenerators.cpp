#include "hapto/scenes/MeshGenerators.h"

#include "hapto/core/Random.h"
#include "hapto/io/InputError.h"
#include "hapto/scenes/Generators.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <map>
#include <numbers>
#include <utility>
#include <vector>

namespace hapto {
namespace {

// Rounded to float, so the PLY file (float coordinates) reads back to exactly this mesh.
Vec3 toFloat(const Vec3& v) {
    return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}

// The resolution k >= lo whose count c k^power is nearest n in ratio.
std::size_t nearestResolution(double n, double c, int power, std::size_t lo) {
    const double x = std::pow(n / c, 1.0 / power);
    const auto below = std::max<std::size_t>(lo, static_cast<std::size_t>(std::floor(x)));
    const std::size_t above = below + 1;
    const double countBelow = c * std::pow(static_cast<double>(below), power);
    const double countAbove = c * std::pow(static_cast<double>(above), power);
    return n / countBelow <= countAbove / n ? below : above;
}

// The torus's grid: V around the tube (>= 3), U around the ring (>= 3), U about 3 V.
std::pair<std::size_t, std::size_t> torusGrid(std::size_t n) {
    const std::size_t v = nearestResolution(static_cast<double>(n), 6.0, 2, 3);
    const std::size_t u = nearestResolution(static_cast<double>(n), 2.0 * v, 1, 3);
    return {u, v};
}

void checkOptions(const MeshOptions& o) {
    const std::string what = "mesh scene (" + std::string(meshShapeName(o.shape)) + "): ";
    if (o.triangles < kMinGeneratedTriangles || o.triangles > kMaxGeneratedTriangles) {
        throw InputError(
            what + "--triangles must be in [" + std::to_string(kMinGeneratedTriangles) + ", " +
            std::to_string(kMaxGeneratedTriangles) + "], got " + std::to_string(o.triangles));
    }
    if (!std::isfinite(o.size) || o.size <= 0.0 || o.size > kMaxGeneratedLength) {
        throw InputError(what + "--size must be a finite length in (0, " +
                         std::to_string(kMaxGeneratedLength) + "] m, got " +
                         std::to_string(o.size));
    }
}

// ---- sphere ----------------------------------------------------------------------------------

// A class-I geodesic sphere of frequency f: vertices once per icosahedron corner, edge and face.
void geodesicSphere(std::size_t f, double radius, std::vector<Vec3>& vertices,
                    std::vector<TriangleIndices>& triangles) {
    const double phi = std::numbers::phi;
    const std::array<Vec3, 12> corner = {Vec3(-1, phi, 0),  Vec3(1, phi, 0),   Vec3(-1, -phi, 0),
                                         Vec3(1, -phi, 0),  Vec3(0, -1, phi),  Vec3(0, 1, phi),
                                         Vec3(0, -1, -phi), Vec3(0, 1, -phi),  Vec3(phi, 0, -1),
                                         Vec3(phi, 0, 1),   Vec3(-phi, 0, -1), Vec3(-phi, 0, 1)};
    std::array<std::array<std::uint32_t, 3>, 20> faces = {
        {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
         {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
         {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}}};
    const auto onSphere = [radius](const Vec3& p) { return toFloat(glm::normalize(p) * radius); };

    vertices.clear();
    vertices.reserve(10 * f * f + 2);
    for (const Vec3& c : corner) {
        vertices.push_back(onSphere(c));
    }
    // Each of the 30 edges: its f - 1 inner vertices, from the lower corner to the higher.
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> edgeStart;
    for (auto& face : faces) {
        // Outward: the icosahedron is convex and centred, so the normal points away from 0.
        const Vec3 n =
            glm::cross(corner[face[1]] - corner[face[0]], corner[face[2]] - corner[face[0]]);
        if (glm::dot(n, corner[face[0]]) < 0.0) {
            std::swap(face[1], face[2]);
        }
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = std::min(face[e], face[(e + 1) % 3]);
            const std::uint32_t b = std::max(face[e], face[(e + 1) % 3]);
            if (edgeStart.emplace(std::pair(a, b), static_cast<std::uint32_t>(vertices.size()))
                    .second) {
                for (std::size_t t = 1; t < f; ++t) {
                    const double s = static_cast<double>(t) / static_cast<double>(f);
                    vertices.push_back(onSphere(corner[a] + s * (corner[b] - corner[a])));
                }
            }
        }
    }
    // The vertex t / f of the way from corner u to corner v.
    const auto edgeVertex = [&](std::uint32_t u, std::uint32_t v, std::size_t t) -> std::uint32_t {
        if (t == 0) {
            return u;
        }
        if (t == f) {
            return v;
        }
        const std::uint32_t start = edgeStart.at({std::min(u, v), std::max(u, v)});
        return static_cast<std::uint32_t>(u < v ? start + t - 1 : start + (f - t) - 1);
    };

    triangles.clear();
    triangles.reserve(20 * f * f);
    std::vector<std::uint32_t> grid; // the face's (f + 1)(f + 2) / 2 vertex numbers
    for (const auto& face : faces) {
        const Vec3 &a = corner[face[0]], &b = corner[face[1]], &c = corner[face[2]];
        // P(i, j) = a + i/f (b - a) + j/f (c - a), i + j <= f; row i holds f + 1 - i points.
        grid.clear();
        for (std::size_t i = 0; i <= f; ++i) {
            for (std::size_t j = 0; i + j <= f; ++j) {
                std::uint32_t index;
                if (j == 0) {
                    index = edgeVertex(face[0], face[1], i);
                } else if (i == 0) {
                    index = edgeVertex(face[0], face[2], j);
                } else if (i + j == f) {
                    index = edgeVertex(face[1], face[2], j);
                } else {
                    const double fi = static_cast<double>(i) / static_cast<double>(f);
                    const double fj = static_cast<double>(j) / static_cast<double>(f);
                    index = static_cast<std::uint32_t>(vertices.size());
                    vertices.push_back(onSphere(a + fi * (b - a) + fj * (c - a)));
                }
                grid.push_back(index);
            }
        }
        const auto at = [&](std::size_t i, std::size_t j) {
            // Rows before i hold sum_{r < i} (f + 1 - r) points.
            return grid[i * (f + 1) - i * (i - 1) / 2 + j];
        };
        for (std::size_t i = 0; i < f; ++i) {
            for (std::size_t j = 0; i + j < f; ++j) {
                triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
                if (i + j + 1 < f) {
                    triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
                }
            }
        }
    }
}

// ---- torus -----------------------------------------------------------------------------------

// Axis y; major radius R = 3 size / 8, tube radius r = size / 8 (outer diameter = size).
void torus(std::size_t u, std::size_t v, double size, std::vector<Vec3>& vertices,
           std::vector<TriangleIndices>& triangles) {
    const double major = 0.375 * size, minor = 0.125 * size;
    vertices.clear();
    vertices.reserve(u * v);
    for (std::size_t i = 0; i < u; ++i) {
        const double a = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(u);
        for (std::size_t j = 0; j < v; ++j) {
            const double b =
                2.0 * std::numbers::pi * static_cast<double>(j) / static_cast<double>(v);
            const double ring = major + minor * std::cos(b);
            vertices.push_back(
                toFloat(Vec3(ring * std::cos(a), minor * std::sin(b), ring * std::sin(a))));
        }
    }
    const auto at = [u, v](std::size_t i, std::size_t j) {
        return static_cast<std::uint32_t>((i % u) * v + (j % v));
    };
    triangles.clear();
    triangles.reserve(2 * u * v);
    for (std::size_t i = 0; i < u; ++i) {
        for (std::size_t j = 0; j < v; ++j) {
            // d/dv x d/du points out of the tube: (a, d, c) and (a, c, b) are CCW from outside.
            const std::uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1),
                                d = at(i, j + 1);
            triangles.push_back({a, d, c});
            triangles.push_back({a, c, b});
        }
    }
}

// ---- terrain ---------------------------------------------------------------------------------

// Value noise on a 256-periodic lattice: a random value per lattice point, smoothstep between.
class ValueNoise {
public:
    explicit ValueNoise(std::uint64_t seed) {
        Random rng(seed);
        for (std::size_t i = 0; i < 256; ++i) {
            mPermutation[i] = static_cast<std::uint8_t>(i);
            mValue[i] = rng.uniform(-1.0, 1.0);
        }
        for (std::size_t i = 255; i > 0; --i) { // Fisher-Yates
            std::swap(mPermutation[i], mPermutation[rng.below(i + 1)]);
        }
    }

    // In [-1, 1].
    double operator()(double x, double z) const {
        const double fx = std::floor(x), fz = std::floor(z);
        const double tx = smooth(x - fx), tz = smooth(z - fz);
        const auto ix = static_cast<std::int64_t>(fx), iz = static_cast<std::int64_t>(fz);
        const double v00 = lattice(ix, iz), v10 = lattice(ix + 1, iz);
        const double v01 = lattice(ix, iz + 1), v11 = lattice(ix + 1, iz + 1);
        const double v0 = v00 + tx * (v10 - v00), v1 = v01 + tx * (v11 - v01);
        return v0 + tz * (v1 - v0);
    }

private:
    static double smooth(double t) { return t * t * (3.0 - 2.0 * t); }
    double lattice(std::int64_t x, std::int64_t z) const {
        const std::uint8_t h = mPermutation[static_cast<std::uint8_t>(x)];
        return mValue[mPermutation[static_cast<std::uint8_t>(h + static_cast<std::uint8_t>(z))]];
    }
    std::array<std::uint8_t, 256> mPermutation{};
    std::array<double, 256> mValue{};
};

// C x C cells over [-size/2, size/2]^2 in x and z; heights within +-size/10.
void terrain(std::size_t cells, double size, std::uint64_t seed, std::vector<Vec3>& vertices,
             std::vector<TriangleIndices>& triangles) {
    const ValueNoise noise(seed);
    constexpr int kOctaves = 4;
    constexpr double kBaseCells = 4.0; // lattice cells across the terrain at the first octave
    const std::size_t n = cells + 1;
    vertices.clear();
    vertices.reserve(n * n);
    for (std::size_t i = 0; i < n; ++i) {
        const double s = static_cast<double>(i) / static_cast<double>(cells);
        for (std::size_t k = 0; k < n; ++k) {
            const double t = static_cast<double>(k) / static_cast<double>(cells);
            double h = 0.0, amplitude = 1.0, total = 0.0, frequency = kBaseCells;
            for (int o = 0; o < kOctaves; ++o) {
                h += amplitude * noise(s * frequency + 17.0 * o, t * frequency + 31.0 * o);
                total += amplitude;
                amplitude *= 0.5;
                frequency *= 2.0;
            }
            vertices.push_back(
                toFloat(Vec3((s - 0.5) * size, 0.1 * size * h / total, (t - 0.5) * size)));
        }
    }
    triangles.clear();
    triangles.reserve(2 * cells * cells);
    for (std::size_t i = 0; i < cells; ++i) {
        for (std::size_t k = 0; k < cells; ++k) {
            // x along i, z along k: z x x = +y, so (a, d, c) and (a, c, b) face up.
            const auto a = static_cast<std::uint32_t>(i * n + k);
            const auto b = static_cast<std::uint32_t>((i + 1) * n + k);
            const std::uint32_t c = b + 1, d = a + 1;
            triangles.push_back({a, d, c});
            triangles.push_back({a, c, b});
        }
    }
}

} // namespace

std::string_view meshShapeName(MeshShape shape) {
    switch (shape) {
    case MeshShape::Sphere:
        return "sphere";
    case MeshShape::Torus:
        return "torus";
    case MeshShape::Terrain:
        return "terrain";
    }
    return "?";
}

std::optional<MeshShape> parseMeshShape(std::string_view name) {
    for (const MeshShape s : {MeshShape::Sphere, MeshShape::Torus, MeshShape::Terrain}) {
        if (name == meshShapeName(s)) {
            return s;
        }
    }
    return std::nullopt;
}

std::size_t generatedTriangleCount(const MeshOptions& o) {
    const auto n = static_cast<double>(std::max<std::size_t>(o.triangles, 1));
    switch (o.shape) {
    case MeshShape::Sphere: {
        const std::size_t f = nearestResolution(n, 20.0, 2, 1);
        return 20 * f * f;
    }
    case MeshShape::Torus: {
        const auto [u, v] = torusGrid(o.triangles);
        return 2 * u * v;
    }
    case MeshShape::Terrain: {
        const std::size_t c = nearestResolution(n, 2.0, 2, 1);
        return 2 * c * c;
    }
    }
    return 0;
}

std::shared_ptr<const TriangleMesh> generateMesh(const MeshOptions& o, MeshSource source) {
    checkOptions(o);
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
    const auto n = static_cast<double>(o.triangles);
    switch (o.shape) {
    case MeshShape::Sphere:
        geodesicSphere(nearestResolution(n, 20.0, 2, 1), 0.5 * o.size, vertices, triangles);
        break;
    case MeshShape::Torus: {
        const auto [u, v] = torusGrid(o.triangles);
        torus(u, v, o.size, vertices, triangles);
        break;
    }
    case MeshShape::Terrain:
        terrain(nearestResolution(n, 2.0, 2, 1), o.size, o.seed, vertices, triangles);
        break;
    }
    return TriangleMesh::make(std::move(vertices), std::move(triangles), std::move(source),
                              "generated " + std::string(meshShapeName(o.shape)));
}

Scene makeMeshScene(const MeshOptions& o, MeshSource source) {
    auto mesh = generateMesh(o, std::move(source));
    const Aabb local = mesh->localBounds();
    const Vec3 pad(0.25 * o.size);
    // Rounded outward to 1 µm, so the scene file's bounds read short.
    const auto down = [](const Vec3& v) { return glm::floor(v * 1e6) / 1e6; };
    const auto up = [](const Vec3& v) { return glm::ceil(v * 1e6) / 1e6; };
    std::vector<SceneObject> objects;
    objects.push_back(
        makeMesh(0, Vec3(0.0), std::move(mesh), Quat(1, 0, 0, 0), generatedMaterial()));
    return Scene(Aabb{down(local.min - pad), up(local.max + pad)}, std::move(objects));
}

void writeMeshPly(const TriangleMesh& mesh, std::ostream& out) {
    out << "ply\nformat binary_little_endian 1.0\ncomment hapto generated mesh\n"
        << "element vertex " << mesh.vertices().size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n"
        << "element face " << mesh.triangleCount() << "\n"
        << "property list uchar uint vertex_indices\nend_header\n";
    std::string chunk;
    chunk.reserve(1 << 20);
    const auto flush = [&] {
        out.write(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        chunk.clear();
    };
    const auto put32 = [&](std::uint32_t v) {
        for (int b = 0; b < 4; ++b) {
            chunk.push_back(static_cast<char>((v >> (8 * b)) & 0xffu));
        }
    };
    for (const Vec3& v : mesh.vertices()) {
        for (int a = 0; a < 3; ++a) {
            put32(std::bit_cast<std::uint32_t>(static_cast<float>(v[a])));
        }
        if (chunk.size() > (1u << 20) - 64) {
            flush();
        }
    }
    for (const TriangleIndices& t : mesh.triangles()) {
        chunk.push_back(3);
        put32(t[0]);
        put32(t[1]);
        put32(t[2]);
        if (chunk.size() > (1u << 20) - 64) {
            flush();
        }
    }
    flush();
}

} // namespace hapto
