// Design note: see Cursor.h. The fast path is inline-sized: six compares against the cached
// leaf box, no call into the index except to fetch the leaf's span.

#include "hapto/index/Cursor.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapto {

Cursor::Cursor() noexcept {
    forget();
}

Cursor::Cursor(const SpatialIndex& index, CursorStrategy strategy) noexcept
    : mIndex(&index), mStrategy(strategy) {
    forget();
}

void Cursor::reset(const SpatialIndex& index) noexcept {
    mIndex = &index;
    forget();
}

void Cursor::forget() noexcept {
    constexpr double inf = std::numeric_limits<double>::infinity();
    mLo = Vec3(inf); // no point is >= +inf and < -inf: the fast path never fires
    mHiOpen = Vec3(-inf);
    mLeaf = kNoLeaf;
}

LocateResult Cursor::locate(const Vec3& p) noexcept {
    if (mIndex == nullptr) {
        return {};
    }
    if (mStrategy != CursorStrategy::FromRoot && p.x >= mLo.x && p.x < mHiOpen.x && p.y >= mLo.y &&
        p.y < mHiOpen.y && p.z >= mLo.z && p.z < mHiOpen.z) {
        return {mIndex->leafObjects(mLeaf), mLeaf, 0, false};
    }
    const LocateResult r = mLeaf == kNoLeaf || mStrategy == CursorStrategy::FromRoot
                               ? mIndex->locate(p)
                               : mIndex->locateFrom(mLeaf, p, mStrategy);
    if (!r.outside && r.leaf != mLeaf) {
        // Cache the new leaf as [lo, hiOpen): on the bounds' upper faces the closed end
        // becomes open one ulp further out, the same convention every locate uses.
        const Aabb box = mIndex->leafBounds(r.leaf);
        const Vec3& top = mIndex->bounds().max;
        mLo = box.min;
        for (int a = 0; a < 3; ++a) {
            mHiOpen[a] = box.max[a] >= top[a]
                             ? std::nextafter(box.max[a], std::numeric_limits<double>::infinity())
                             : box.max[a];
        }
        mLeaf = r.leaf;
    }
    return r;
}

Aabb Cursor::cachedBox() const noexcept {
    // locate() nudged an upper face on the bounds' top one ulp up; the closed box has it on
    // the top itself, which is the smaller of the two.
    const Vec3& top = mIndex->bounds().max;
    return {mLo, Vec3(std::min(mHiOpen.x, top.x), std::min(mHiOpen.y, top.y),
                      std::min(mHiOpen.z, top.z))};
}

SegmentWalk Cursor::firstLeafNotIn(const Vec3& a, const Vec3& b,
                                   std::span<const std::uint32_t> listed) const noexcept {
    Cursor walker = *this;
    return walker.walkToFirstLeafNotIn(a, b, listed);
}

SegmentWalk Cursor::walkToFirstLeafNotIn(const Vec3& a, const Vec3& b,
                                         std::span<const std::uint32_t> listed) noexcept {
    const Vec3 d = b - a;
    const double length = glm::length(d);
    double t = 0.0;
    for (int walked = 0; walked < kMaxWalkLeaves; ++walked) {
        const LocateResult at = locate(a + t * d);
        if (at.outside) {
            return {};
        }
        if (std::find(listed.begin(), listed.end(), at.leaf) == listed.end()) {
            return {at, t};
        }
        if (!(length > 0.0)) {
            return {};
        }
        // Where the segment leaves this leaf's box: the nearest exit over the three slabs.
        const Aabb box = cachedBox();
        double exit = 1.0;
        for (int i = 0; i < 3; ++i) {
            if (d[i] > 0.0) {
                exit = std::min(exit, (box.max[i] - a[i]) / d[i]);
            } else if (d[i] < 0.0) {
                exit = std::min(exit, (box.min[i] - a[i]) / d[i]);
            }
        }
        if (exit >= 1.0) {
            SegmentWalk reached;
            reached.endBox = box; // b's leaf, listed
            return reached;
        }
        t = std::max(exit, t) + 1e-9 / length; // a nanometre past the face
        if (t > 1.0) {
            return {};
        }
    }
    SegmentWalk unknown;
    unknown.unknown = true;
    return unknown;
}

} // namespace hapto
