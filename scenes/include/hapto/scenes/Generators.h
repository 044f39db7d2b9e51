#pragma once
/// Seeded, reproducible scene generators for the paper's experiments and beyond.

#include "hapto/scenes/Scene.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace hapto {

/// The most objects a generator makes: 10^8 (about 11 GB of objects in memory, 18 GB of scene
/// file). Larger counts are refused before anything is allocated.
inline constexpr std::size_t kMaxGeneratedObjects = 100'000'000;
/// The largest length a generator takes (m): 10^6. Every generated coordinate then stays far
/// from overflow (and from losing the 1 µm rounding); larger, NaN or infinite lengths are
/// refused.
inline constexpr double kMaxGeneratedLength = 1e6;

/// The material generated scenes use: default stiffness, mu_s 0.3, mu_d 0.2.
Material generatedMaterial();

/// Experiment 1: K x K x K cubes on a regular lattice centred on the origin.
struct LatticeOptions {
    int perSide = 3;        ///< K, cubes per lattice side (>= 1).
    double cubeSize = 0.05; ///< Cube edge (m); the paper's e-Touch boxes are 5 cm.
    double gap = 0.01;      ///< Free space between neighbouring cubes (m).
};
/// Bounds are the lattice padded by half a gap on every side (at least 1 µm from the centre).
/// Throws InputError, naming the option, for K < 1, K^3 > kMaxGeneratedObjects, or a length
/// that is not finite, out of range or above kMaxGeneratedLength. [control]
Scene makeLatticeScene(const LatticeOptions& options);

/// Experiment 2: cubes placed uniformly at random in a work cube centred on the origin.
struct RandomOptions {
    std::size_t count = 200; ///< Number of cubes.
    std::uint64_t seed = 1;  ///< Same seed and options, same scene.
    double workspace = 0.25; ///< Edge of the work cube (m); cube centres stay inside it.
    double cubeSize = 0.05;  ///< Cube edge (m).
    bool rotate = false;     ///< Give each cube a uniformly random orientation.
    double keepClear = 0.0;  ///< No object within this distance of the centre (m).
};
/// Bounds are the work cube. Throws InputError when keepClear leaves no room, and for the
/// counts and lengths makeLatticeScene refuses. [control]
Scene makeRandomScene(const RandomOptions& options);

/// A strongly non-uniform scene: cubes in Gaussian clusters.
struct ClusterOptions {
    std::size_t count = 1000; ///< Number of cubes.
    int clusters = 8;         ///< Number of Gaussian clusters (>= 1).
    std::uint64_t seed = 1;   ///< Same seed and options, same scene.
    double workspace = 0.25;  ///< Edge of the work cube (m); centres are clamped into it.
    double cubeSize = 0.005;  ///< Cube edge (m).
    double spread = 0.01;     ///< Standard deviation of each cluster (m).
    bool rotate = false;      ///< Random orientations.
};
/// Bounds are the work cube. Throws InputError for the counts and lengths makeLatticeScene
/// refuses, and for clusters < 1 or > kMaxGeneratedObjects. [control]
Scene makeClusterScene(const ClusterOptions& options);

/// The two-handed grasp demo (y is up; the floor is the bounds' lowest y, -0.10 m): a rubbery
/// 5 cm cube (id 0, mu_s 0.6, mu_d 0.5) resting on the floor at x = -0.05 m, a low bar (id 1,
/// 2 cm high) in the path of a 10 cm carry along +x, and four more objects around (ids 2-5).
Scene makeGraspScene();

/// The object the physical grasp demo picks up (makeDynamicGraspScene).
enum class GraspObject {
    Box,    ///< A 5 cm cube.
    Sphere, ///< A 5 cm ball.
    Mesh,   ///< A closed triangle mesh: an octagonal prism 5 cm across its flats and 5 cm tall
            ///< (28 triangles), a flat side facing each hand.
};
/// "box", "sphere", "mesh". [any thread]
std::string_view graspObjectName(GraspObject object);
/// Parses a GraspObject name; nullopt for anything else. [any thread]
std::optional<GraspObject> parseGraspObject(std::string_view name);

/// The physical grasp demo's scene (format version 3, y up, gravity -9.81 m/s^2 along y,
/// dynamics at 1 kHz): makeGraspScene's objects, its object 0 now `object`, dynamic, 100 g,
/// rubbery (mu_s 0.6, mu_d 0.5, 800 N/m), resting on a static floor (id 6, top at y = -0.10 m),
/// and a 2 cm plinth (id 7, 6 cm square, centred at x = 0.05 m) where the grasp's 10 cm carry
/// sets it down. Objects 2-5 are static as before. Throws only on a failure to build the mesh
/// (never for these fixed values). [control]
Scene makeDynamicGraspScene(GraspObject object);

/// The embedded default scene: the paper's experiment 2 set-up, 200 random 5 cm cubes in a
/// 25 cm cube (seed 2004), with a 4 cm clear region around the centre where cursors start.
Scene makeDefaultScene();

} // namespace hapto
