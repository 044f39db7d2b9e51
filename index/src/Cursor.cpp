// Design note: see Cursor.h. The fast path is inline-sized: six compares against the cached
// leaf box, no call into the index except to fetch the leaf's span.

#include "hapto/index/Cursor.h"

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

} // namespace hapto
