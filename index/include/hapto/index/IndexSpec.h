#pragma once
/// Which index to build, parsed from a short text such as "grid:5" or "octree:2:0.005:aabb".

#include "hapto/index/Overlap.h"

#include <cstdint>
#include <string>
#include <string_view>

namespace hapto {

/// Which index and with which parameters: `brute`, `grid:N` or `octree:M:MIN` (MIN in metres),
/// each optionally followed by `:aabb` (place objects by their AABB instead of their OBB).
struct IndexSpec {
    /// The three indices.
    enum class Kind : std::uint8_t { BruteForce, Grid, Octree };

    static constexpr int kMaxGridCells = 256;       ///< Largest n of an n^3 grid.
    static constexpr int kMaxLeafObjects = 1 << 20; ///< Largest M of an octree.
    /// Default memory limit of a build, in MB (2^20 bytes each): `--max-index-mb`'s default.
    static constexpr std::uint64_t kDefaultMaxMegabytes = 1024;
    /// The same in bytes.
    static constexpr std::uint64_t kDefaultMaxBytes = kDefaultMaxMegabytes << 20;

    Kind kind = Kind::BruteForce; ///< Which index.
    int gridCells = 0;            ///< Grid only: n, cells per side (1..kMaxGridCells).
    int maxObjects = 0;           ///< Octree only: M, objects a leaf may hold above min size.
    double minLeafSize = 0.0;     ///< Octree only: minimum leaf edge (m), > 0.
    OverlapMode mode = OverlapMode::Obb; ///< How objects are placed into cells.
    /// The most memory the build may take (bytes); a larger index is refused with an
    /// IndexTooLargeError (SpatialIndex.h). Not part of the text form: parse() sets the default.
    std::uint64_t maxBytes = kDefaultMaxBytes;

    /// The brute-force "index" (every object is a candidate). [any thread]
    static IndexSpec brute();
    /// An n x n x n grid. [any thread]
    static IndexSpec grid(int cells, OverlapMode mode = OverlapMode::Obb);
    /// The paper's modified octree: at most M objects per leaf unless at minimum size (m).
    /// [any thread]
    static IndexSpec octree(int maxObjects, double minLeafSize,
                            OverlapMode mode = OverlapMode::Obb);

    /// Parses "brute", "grid:5", "octree:2:0.005", each optionally with ":aabb" (or ":obb").
    /// Throws InputError saying what is wrong and what is expected. [any thread]
    static IndexSpec parse(std::string_view text);
    /// This spec with a memory limit of `megabytes` MB (2^20 bytes each; saturates). For the
    /// commands' `--max-index-mb`. [any thread]
    IndexSpec withMaxMegabytes(std::uint64_t megabytes) const {
        IndexSpec s = *this;
        s.maxBytes = megabytes >= (std::uint64_t(1) << 44) ? ~std::uint64_t(0) : megabytes << 20;
        return s;
    }
    /// The text form; parse(toString()) gives this spec back. [any thread]
    std::string toString() const;

    /// Every field equal (the same text form and the same memory limit).
    bool operator==(const IndexSpec&) const = default;
};

} // namespace hapto
