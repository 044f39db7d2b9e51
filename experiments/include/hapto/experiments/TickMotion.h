#pragma once
/// The adversarial hand motions of `hapto bench tick --motion`: each a deterministic hand path
/// over its own generated scene, chosen to make the servo tick expensive.
///
/// Design note. The tick's cost depends on where the hand goes more than on the scene's size:
/// a proxy trapped behind a hand that pushed through, a hand crossing many index leaves in one
/// tick, a proxy caught on edges and vertices, a proxy sliding over facets smaller than one
/// tick's motion, a goal beyond several thin walls. Each motion pins one of these down as a
/// path the bench's device plays exactly, one point per 1 ms tick, with no regard for the
/// force (a stiff hand: the worst case, and the path is then what the tests check), except
/// `walk`, the bench's usual seeded hand, held back at 2 mm from the proxy. `rest` is the
/// baseline: a hand come to rest 0.5 mm inside a cube's face. Scenes are generated from a size
/// (objects or triangles), a seed and fixed shapes, so a motion is the same at every run.
/// Cost: building a case is building its scene (10^6 cubes: about a second); the path is
/// precomputed, so the device's read is an array load.

#include "hapto/core/Geometry.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/scenes/Scene.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace hapto::experiments {

/// The motions.
enum class TickMotion : std::uint8_t {
    Rest,    ///< Comes down onto a lattice cube's top face and rests 0.5 mm inside it.
    Walk,    ///< The bench's seeded walk over random cubes, held back 2 mm from the proxy.
    Trapped, ///< The same walk deep inside the random cubes, never held back.
    Sweep,   ///< Straight seeded lines through the random cubes at 1 m/s.
    Graze,   ///< Along the lines where the lattice's top cubes meet, 0.1 mm down, at 0.5 m/s.
    Sphere,  ///< Slides 1 mm inside a fine-faceted sphere at 0.5 m/s on great-circle arcs.
    Slabs,   ///< Up and down through a stack of thin slabs at 1 m/s.
    Body,    ///< Rests 1 mm inside a dynamic box's top while the box swings under it.
};

/// Every motion, in the order the bench runs them.
inline constexpr std::array<TickMotion, 8> kTickMotions{
    TickMotion::Rest,  TickMotion::Walk,   TickMotion::Trapped, TickMotion::Sweep,
    TickMotion::Graze, TickMotion::Sphere, TickMotion::Slabs,   TickMotion::Body};

/// "rest", "walk", "trapped", "sweep", "graze", "sphere", "slabs", "body". [any thread]
std::string_view tickMotionName(TickMotion motion);
/// Parses a motion's name; nullopt for anything else. [any thread]
std::optional<TickMotion> parseTickMotion(std::string_view name);
/// The names, comma separated, for messages. [any thread]
std::string tickMotionNames();

/// What every motion's scene and path are made from.
struct MotionOptions {
    /// Objects in the cube scenes (random cubes, lattice) and triangles in the sphere, about
    /// (the lattice rounds to a cube of a whole number, the sphere to 20 f^2). >= 8.
    std::size_t objects = 1'000'000;
    std::size_t ticks = 5000; ///< Path points (1 ms each); the device replays them cyclically.
    std::uint64_t seed = 1;   ///< The random scene's and the paths' seed.
};

/// Edge of every cube in the motions' cube scenes (m), as the benchmark scenes'.
inline constexpr double kMotionCubeM = 0.002;
/// Gap between neighbouring lattice cubes (m): none, they touch, so their top faces make one
/// floor of 2 mm tiles whose shared edges and vertices the grazing hand runs along.
inline constexpr double kMotionLatticeGapM = 0.0;
/// How far below the lattice's top faces the grazing hand runs, on the lines where they meet
/// (m).
inline constexpr double kGrazeDepthM = 0.0001;
/// How far the resting hand is inside the top face (m).
inline constexpr double kRestDepthM = 0.0005;
/// The sphere's diameter (m).
inline constexpr double kSphereDiameterM = 0.1;
/// How far inside the sphere's surface the sliding hand is (m).
inline constexpr double kSphereDepthM = 0.001;
/// Slabs in the stack.
inline constexpr int kSlabCount = 20;
/// Thickness of one slab (m).
inline constexpr double kSlabThicknessM = 0.0005;
/// Distance between the slabs' mid-planes (m).
inline constexpr double kSlabPitchM = 0.001;
/// Edge of the slabs' square (m).
inline constexpr double kSlabEdgeM = 0.1;
/// The sweeps' and the slab crossings' speed (m/s): a fast hand.
inline constexpr double kFastSpeedMPerS = 1.0;
/// The grazing and the sliding hand's speed (m/s): the walk's cap, a brisk hand.
inline constexpr double kSlideSpeedMPerS = 0.5;
/// The dynamic box's swing along x (m, amplitude) under the resting hand...
inline constexpr double kBodySwingM = 0.02;
/// ... and its period (s): 0.13 m/s at the middle of the swing.
inline constexpr double kBodySwingPeriodS = 1.0;

/// One motion, ready to run: its scene, the index to run it over, and its path.
struct MotionCase {
    TickMotion motion = TickMotion::Rest; ///< Which.
    Scene scene;                          ///< Its generated scene.
    std::string sceneText;                ///< How the scene was made, for the report.
    std::string pathText;                 ///< What the hand does, for the report.
    IndexSpec index;                      ///< octree:8:0.001, the tick bench's.
    /// The points the device plays, one per tick (m, world = device frame); empty for `walk`,
    /// whose seeded walk is held back by the force (walkIn, pushMm).
    std::vector<Vec3> path;
    Aabb walkIn{Vec3(0.0), Vec3(0.0)}; ///< `walk`'s box (m); the trapped path's region too.
    double pushMm = 0.0;               ///< `walk`: held back to 2 mm of the proxy; 0 otherwise.
    std::size_t approachTicks = 0;     ///< Leading path points that come in from free space.
    /// `body`: the dynamic box's pose at each tick (the bench stamps each with its tick's
    /// time); empty for the others.
    std::vector<BodyPose> bodyPoses;
};

/// Builds a motion's scene and path. Throws InputError naming the size when the scene
/// generators refuse it. [control]
MotionCase makeMotionCase(TickMotion motion, const MotionOptions& options);

/// The lattice of `objects` (about) touching 2 mm cubes that `rest` and `graze` use, its bounds
/// 5 mm beyond the cubes, with the cube count per side (K). [control]
Scene makeMotionLattice(std::size_t objects, int* perSide = nullptr);
/// The random 2 mm cubes that `walk`, `trapped` and `sweep` use: `objects` of them at the
/// density of 10^6 in the 25 cm work cube (the edge scales as the cube root). [control]
Scene makeMotionCubes(std::size_t objects, std::uint64_t seed);
/// The stack of kSlabCount slabs `slabs` uses, centred on the origin (y up). [control]
Scene makeSlabStack();
/// The dynamic 10 x 2 x 10 cm, 100 g box `body` uses, at the origin (y up). [control]
Scene makeDynamicSlab();

} // namespace hapto::experiments
