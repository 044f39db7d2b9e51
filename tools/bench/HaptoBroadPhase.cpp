#include "HaptoBroadPhase.h"

#include <utility>

namespace hapto::bench {

HaptoBroadPhase::HaptoBroadPhase(std::span<const Aabb> boxes,
                                 std::shared_ptr<const SpatialIndex> index, CursorStrategy strategy)
    : mIndex(std::move(index)), mBoxes(boxes), mCursor(*mIndex, strategy) {}

namespace {

/// Two doubles in one SSE2 (or NEON) register: GCC's and Clang's vector extension, which
/// compiles to the target's vector instructions or to scalar code where there are none.
using Pair = double __attribute__((vector_size(16)));

/// The point (m) paired as the box test reads it.
struct PairedPoint {
    Pair xy, yz;
    double x, z;
};

/// Whether `b` holds the point (boundary included; never with a NaN), as three pairwise
/// comparisons instead of six scalar ones: min.x, min.y <= x, y; y, z <= max.y, max.z; and
/// min.z, x <= z, max.x. The filter is throughput-bound on its instructions (the leaf's boxes
/// are in the first-level cache: the cursor stays in its leaf on 93 % of the walk's queries),
/// and this takes about 22 a candidate with the loop, where six scalar comparisons took 30
/// (docs/results/benchmarks.md, "The box test in pairs").
bool holds(const Aabb& b, const PairedPoint& p) {
    const Pair lo = {b.min.x, b.min.y}, hi = {b.max.y, b.max.z};
    const Pair crossLo = {b.min.z, p.x}, crossHi = {p.z, b.max.x};
    const auto inside = (lo <= p.xy) & (p.yz <= hi) & (crossLo <= crossHi); // lanes 0 or -1
    return ((inside[0] & inside[1]) & 1) != 0;
}

} // namespace

QueryCounts HaptoBroadPhase::query(const Vec3& point, std::vector<std::uint32_t>& out) {
    const LocateResult r = mCursor.locate(point);
    // Branch-free: whether a candidate's box holds the point is a coin toss along the walk (a
    // branch per comparison mispredicts about once a query); every candidate is written and
    // the count advances only past the ones inside.
    const PairedPoint p{{point.x, point.y}, {point.y, point.z}, point.x, point.z};
    out.resize(r.candidates.size());
    std::size_t n = 0;
    for (const std::uint32_t slot : r.candidates) {
        out[n] = slot;
        n += holds(mBoxes[slot], p) ? 1 : 0;
    }
    out.resize(n);
    return {static_cast<std::uint32_t>(r.candidates.size()), r.steps};
}

QueryCounts HaptoBroadPhase::locateAndTouch(const Vec3& point, std::uint64_t& sum) {
    const LocateResult r = mCursor.locate(point);
    for (const std::uint32_t slot : r.candidates) {
        sum += slot;
    }
    return {static_cast<std::uint32_t>(r.candidates.size()), r.steps};
}

} // namespace hapto::bench
