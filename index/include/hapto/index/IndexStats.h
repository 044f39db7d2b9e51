#pragma once
/// What an index looks like once built: its size, shape, fill and memory.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace hapto {

/// Figures describing a built index (the same fields for every kind; "leaf" means grid cell
/// for the grid and the single whole-scene cell for brute force).
struct IndexStats {
    /// One histogram bin: leaves holding minObjects..maxObjects objects (inclusive).
    struct Bin {
        std::uint32_t minObjects = 0; ///< Lowest count in the bin.
        std::uint32_t maxObjects = 0; ///< Highest count in the bin.
        std::uint64_t leaves = 0;     ///< Leaves whose object count falls in the bin.
    };

    std::string index;                     ///< The spec, as IndexSpec::toString() writes it.
    std::uint32_t objects = 0;             ///< Items indexed: boxes, spheres and mesh
                                           ///< triangles (Scene::isIndexed); the "objects"
                                           ///< of every leaf count below are items too.
    std::uint64_t nodes = 0;               ///< Octree nodes; grid cells; 1 for brute force.
    std::uint64_t leaves = 0;              ///< Leaves (grid: cells).
    std::uint64_t emptyLeaves = 0;         ///< Leaves holding no object.
    std::uint32_t depth = 0;               ///< Octree: deepest leaf level (root = 0); else 0.
    std::uint64_t leavesAtMinimumSize = 0; ///< Octree leaves that may not split further.
    std::uint64_t objectCellPairs = 0;     ///< Sum over leaves of the objects each holds.
    std::uint32_t maxObjectsPerLeaf = 0;   ///< Fullest leaf.
    double meanObjectsPerLeaf = 0.0;       ///< objectCellPairs / leaves.
    std::vector<Bin> objectsPerLeaf;       ///< Histogram: bins 0, 1, 2, 3-4, 5-8, 9-16, ...
    std::uint64_t outsideObjects = 0;      ///< Objects reaching outside the bounds (grid and
                                           ///< octree: the candidates of outside points).
    std::uint64_t bytes = 0;               ///< Memory of the index's arrays (bytes).
    double bytesPerObject = 0.0;           ///< bytes / objects (per item: a mesh's memory
                                           ///< per triangle).
    std::uint64_t buildPeakBytes = 0;      ///< Octree: the most memory the build held by
                                           ///< its own accounting (bytes), what the limit
                                           ///< bounds; else 0.
    double buildSeconds = 0.0;             ///< Wall-clock build time (s).
    double buildCpuSeconds = 0.0;          ///< CPU time of all threads during the build (s).

    /// Fills leaves, emptyLeaves, objectCellPairs, max, mean and the histogram from the
    /// object count of every leaf. [control]
    void recordLeaves(std::span<const std::uint32_t> objectsPerLeafCounts);
};

} // namespace hapto
