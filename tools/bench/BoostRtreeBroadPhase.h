#pragma once
/// Baseline: Boost.Geometry's rtree (quadratic<16> nodes, bulk-loaded), queried by intersects.

#include "BroadPhase.h"

#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace hapto::bench {

/// `bgi::rtree<std::pair<box, slot>, bgi::quadratic<16>>` built with the packing constructor
/// (Boost's STR-like bulk load, the best tree Boost builds for a static set). A query is
/// `query(bgi::intersects(point), back_inserter(out))` (closed boxes, so a point on a face
/// counts, as everywhere else here).
class BoostRtreeBroadPhase {
public:
    /// 3-D point in metres, double precision.
    using Point = boost::geometry::model::point<double, 3, boost::geometry::cs::cartesian>;
    /// Axis-aligned box in metres.
    using Box = boost::geometry::model::box<Point>;
    /// What the tree stores: a box and its slot.
    using Value = std::pair<Box, std::uint32_t>;
    /// The tree.
    using Tree = boost::geometry::index::rtree<Value, boost::geometry::index::quadratic<16>>;

    /// Bulk-loads the tree over the boxes (m). [control]
    explicit BoostRtreeBroadPhase(std::span<const Aabb> boxes);

    /// Clears `out` and appends the slot of every box holding the point. [one thread]
    QueryCounts query(const Vec3& point, std::vector<std::uint32_t>& out);

private:
    Tree mTree;
};

} // namespace hapto::bench
