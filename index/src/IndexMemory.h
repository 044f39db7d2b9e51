#pragma once
/// Index memory limits and accounting, shared by the builders and the estimate (internal).

#include "hapto/index/IndexSpec.h"

#include <cstdint>
#include <limits>
#include <string>

namespace hapto::detail {

/// Throws IndexTooLargeError: "index SPEC would need about X MB (DETAIL), more than the Y MB
/// limit; ...". `atLeast` says the figure is a floor (an octree stopped part way). [control]
[[noreturn]] void refuseIndexMemory(const IndexSpec& spec, std::uint64_t bytes,
                                    const std::string& detail, bool atLeast = false);

/// a + b, saturating at the largest value ("more than any limit"). [any thread]
constexpr std::uint64_t addSat(std::uint64_t a, std::uint64_t b) noexcept {
    return a > std::numeric_limits<std::uint64_t>::max() - b
               ? std::numeric_limits<std::uint64_t>::max()
               : a + b;
}
/// a * b, saturating at the largest value. [any thread]
constexpr std::uint64_t mulSat(std::uint64_t a, std::uint64_t b) noexcept {
    return b != 0 && a > std::numeric_limits<std::uint64_t>::max() / b
               ? std::numeric_limits<std::uint64_t>::max()
               : a * b;
}

/// The sizes an octree build holds at one step of one level (Octree.cpp's OctreeBuilder).
struct OctreeBuildFigures {
    std::uint64_t items = 0;        ///< Indexed items.
    std::uint64_t nodes = 0;        ///< Nodes once the level's children are added.
    std::uint64_t slots = 0;        ///< Leaf slots once the level's leaves are added.
    std::uint64_t levelNodes = 0;   ///< Nodes of the level being split.
    std::uint64_t levelEntries = 0; ///< Entries of the level's object lists.
    std::uint64_t nextEntries = 0;  ///< Entries of the next level's lists (0 before known).
};

/// octreeBuildBytes's bytes per leaf slot (the slots twice: a growing vector copies them), per
/// entry of the level's lists (its id and mask) and per entry of the next level's (its id).
inline constexpr std::uint64_t kSlotBytes = 2 * sizeof(std::uint32_t);
inline constexpr std::uint64_t kLevelEntryBytes = sizeof(std::uint32_t) + 1;
inline constexpr std::uint64_t kNextEntryBytes = sizeof(std::uint32_t);

/// The most memory an octree build holds at that step (bytes, saturating): per item its id,
/// outside flag and entry, local id, 192-byte shape, Morton key and flags; every node (40 B)
/// and its parent share twice, and every slot twice (a vector growing by one level copies the
/// old array into the new one, both alive); per level entry its id and mask; per next entry
/// its id; per level node its list's start and split rank (12 B) and its children's list
/// starts (64 B). An upper bound of the builder's live arrays, used both by the build's check
/// before each level's allocations and by the estimate's upper bound. [any thread]
std::uint64_t octreeBuildBytes(const OctreeBuildFigures& f) noexcept;

} // namespace hapto::detail
