#include "BoostRtreeBroadPhase.h"

#include <boost/iterator/function_output_iterator.hpp>

namespace hapto::bench {
namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;

namespace {

BoostRtreeBroadPhase::Point toBoost(const Vec3& v) {
    return {v.x, v.y, v.z};
}

BoostRtreeBroadPhase::Tree bulkLoad(std::span<const Aabb> boxes) {
    std::vector<BoostRtreeBroadPhase::Value> values;
    values.reserve(boxes.size());
    for (std::size_t slot = 0; slot < boxes.size(); ++slot) {
        values.emplace_back(
            BoostRtreeBroadPhase::Box(toBoost(boxes[slot].min), toBoost(boxes[slot].max)),
            static_cast<std::uint32_t>(slot));
    }
    return BoostRtreeBroadPhase::Tree(values.begin(), values.end());
}

} // namespace

BoostRtreeBroadPhase::BoostRtreeBroadPhase(std::span<const Aabb> boxes) : mTree(bulkLoad(boxes)) {}

QueryCounts BoostRtreeBroadPhase::query(const Vec3& point, std::vector<std::uint32_t>& out) {
    out.clear();
    mTree.query(bgi::intersects(toBoost(point)),
                boost::iterators::make_function_output_iterator(
                    [&out](const Value& v) { out.push_back(v.second); }));
    return {static_cast<std::uint32_t>(out.size()), 0};
}

} // namespace hapto::bench
