#pragma once
/// Seeded, reproducible triangle meshes for the mesh experiments and benchmarks: a geodesic
/// sphere, a torus and a noise heightfield, from 10^2 to 10^7 triangles.
///
/// Design note. Each shape is a regular grid of triangles whose resolution is the one integer
/// that brings the triangle count nearest N (in ratio), so triangles are about equally large
/// and a count sweep changes only the density:
///   - sphere: a class-I geodesic sphere, every icosahedron face cut into f x f triangles
///     (20 f^2), vertices pushed onto the sphere. Shared vertices are made once per
///     icosahedron corner, edge and face, so the mesh is closed;
///   - torus: U x V quads, two triangles each (2 U V), U / V = 3 (the major over the minor
///     radius), so the triangles are nearly square; closed;
///   - terrain: a C x C cell heightfield (2 C^2), heights from seeded value noise (4 octaves),
///     normals up (+y); open, one-sided.
/// Count: within a factor 1 + 1/f (sphere), 1 + 1/C (terrain) or 1 + 1/U (torus) of N, so
/// within 1.5x for N >= 100 and 1.15x for N >= 1000 (the sphere's 20 f^2 is the coarsest).
/// Same options, same mesh, bit for bit: only integer loops, IEEE arithmetic and the
/// project's own Random (xoshiro256**). Only the terrain uses the seed; the sphere and torus
/// are the same for every seed.
/// Vertices are rounded to float, so the mesh read back from writeMeshPly's file is this mesh.
/// Cost: O(N) time; about half a vertex per triangle, so about 24 B per triangle in memory
/// (24 B per vertex, 12 B per triangle; 10^7 triangles: about 0.25 GB).

#include "hapto/scenes/Scene.h"
#include "hapto/scenes/TriangleMesh.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>

namespace hapto {

/// The shapes generateMesh makes.
enum class MeshShape { Sphere, Torus, Terrain };

/// "sphere", "torus", "terrain". [any thread]
std::string_view meshShapeName(MeshShape shape);
/// Parses a shape name; nullopt for anything else. [any thread]
std::optional<MeshShape> parseMeshShape(std::string_view name);

/// The fewest triangles a generator is asked for.
inline constexpr std::size_t kMinGeneratedTriangles = 100;
/// The most triangles a generator is asked for.
inline constexpr std::size_t kMaxGeneratedTriangles = 10'000'000;

/// What to generate.
struct MeshOptions {
    /// Sphere, torus or terrain.
    MeshShape shape = MeshShape::Sphere;
    std::size_t triangles = 1000; ///< N, the triangles asked for (see the design note).
    double size = 0.1;            ///< Extent along x (m): the sphere's diameter, the torus's
                                  ///< outer diameter (tube radius size / 8), the terrain's edge.
    std::uint64_t seed = 1;       ///< The terrain's noise; same seed, same mesh.
};

/// The triangles generateMesh makes for these options, without making them. [any thread]
std::size_t generatedTriangleCount(const MeshOptions& options);

/// Generates the mesh, centred on its local origin (the terrain's heights are within
/// +-size/10 of y = 0), CCW outward triangles, shared vertices. `source` is kept in the mesh
/// (MeshSource) for writing the scene back. Throws InputError naming the option for a count
/// outside [kMinGeneratedTriangles, kMaxGeneratedTriangles], or a size that is not finite, not
/// positive or above kMaxGeneratedLength. [control]
std::shared_ptr<const TriangleMesh> generateMesh(const MeshOptions& options,
                                                 MeshSource source = {});

/// A scene of one generated mesh (id 0) at the origin, with the generated material
/// (generatedMaterial()); bounds are the mesh's padded by a quarter of `size` on every side,
/// so a hand has room to approach. Throws as generateMesh. [control]
Scene makeMeshScene(const MeshOptions& options, MeshSource source = {});

/// Writes the mesh as binary little-endian PLY ("vertex" x y z as float, "face"
/// vertex_indices as uchar count + uint indices): 12 B per vertex and 13 B per triangle,
/// about 190 MB for 10^7 triangles, against about 0.5 GB as JSON. Same mesh, same bytes.
/// [control]
void writeMeshPly(const TriangleMesh& mesh, std::ostream& out);

} // namespace hapto
