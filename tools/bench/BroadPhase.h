#pragma once
/// What every structure in hapto_bench answers: the ids of the boxes holding a point.
///
/// Each structure (hapto's indices through a cursor, and the baselines Bullet btDbvt, FCL's
/// dynamic AABB tree and Boost.Geometry's rtree) is a class with a constructor that builds it
/// over the scene's world AABBs and a `query(point, out)` that clears `out` and appends, in any
/// order, the slot of every box that holds the point. That is the broad phase's job, the same
/// for all, so their times compare. `query` is defined out of line in every class, so each pays
/// the same one call.

#include "hapto/core/Geometry.h"

#include <cstdint>

namespace hapto::bench {

/// What one query did, for the benchmark's counters.
struct QueryCounts {
    std::uint32_t candidates = 0; ///< Ids the structure handed over before any exact test:
                                  ///< hapto: the leaf's objects; trees: the boxes they hit.
    std::uint32_t steps = 0;      ///< hapto: links the cursor followed; baselines: 0.
};

} // namespace hapto::bench
