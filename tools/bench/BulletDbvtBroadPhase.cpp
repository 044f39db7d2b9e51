#include "BulletDbvtBroadPhase.h"

#include <cstdint>

namespace hapto::bench {
namespace {

btVector3 toBullet(const Vec3& v) {
    return btVector3(v.x, v.y, v.z);
}

/// Collects leaf slots into a vector (Bullet calls Process once per overlapping leaf).
struct Collector final : btDbvt::ICollide {
    explicit Collector(std::vector<std::uint32_t>& out) : mOut(out) {}
    void Process(const btDbvtNode* leaf) override {
        mOut.push_back(static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(leaf->data)));
    }
    std::vector<std::uint32_t>& mOut;
};

} // namespace

static_assert(sizeof(btScalar) == sizeof(double), "hapto_bench links Bullet's float64 build");

BulletDbvtBroadPhase::BulletDbvtBroadPhase(std::span<const Aabb> boxes) {
    for (std::size_t slot = 0; slot < boxes.size(); ++slot) {
        const btDbvtVolume volume =
            btDbvtVolume::FromMM(toBullet(boxes[slot].min), toBullet(boxes[slot].max));
        mTree.insert(volume, reinterpret_cast<void*>(static_cast<std::uintptr_t>(slot)));
    }
    mTree.optimizeTopDown();
    mStack.reserve(btDbvt::SIMPLE_STACKSIZE);
}

QueryCounts BulletDbvtBroadPhase::query(const Vec3& point, std::vector<std::uint32_t>& out) {
    out.clear();
    const btVector3 p = toBullet(point);
    Collector collector(out);
    mTree.collideTVNoStackAlloc(mTree.m_root, btDbvtVolume::FromMM(p, p), mStack, collector);
    return {static_cast<std::uint32_t>(out.size()), 0};
}

} // namespace hapto::bench
