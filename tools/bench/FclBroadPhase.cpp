#include "FclBroadPhase.h"

#include <cstdint>

namespace hapto::bench {
namespace {

/// FCL's broad-phase callback: o1 is the tree's object, o2 the query; false = keep going.
bool collectSlot(fcl::CollisionObjectd* o1, fcl::CollisionObjectd*, void* data) {
    auto* out = static_cast<std::vector<std::uint32_t>*>(data);
    out->push_back(static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(o1->getUserData())));
    return false;
}

} // namespace

FclBroadPhase::FclBroadPhase(std::span<const Aabb> boxes)
    : mQuery(std::make_shared<fcl::Boxd>(0.0, 0.0, 0.0)) {
    mObjects.reserve(boxes.size());
    std::vector<fcl::CollisionObjectd*> raw;
    raw.reserve(boxes.size());
    for (std::size_t slot = 0; slot < boxes.size(); ++slot) {
        const Vec3 size = boxes[slot].size();
        const Vec3 c = boxes[slot].center();
        auto object = std::make_unique<fcl::CollisionObjectd>(
            std::make_shared<fcl::Boxd>(size.x, size.y, size.z), fcl::Matrix3d::Identity(),
            fcl::Vector3d(c.x, c.y, c.z));
        object->setUserData(reinterpret_cast<void*>(static_cast<std::uintptr_t>(slot)));
        raw.push_back(object.get());
        mObjects.push_back(std::move(object));
    }
    mManager.registerObjects(raw);
    mManager.setup();
}

FclBroadPhase::~FclBroadPhase() {
    mManager.clear();
}

QueryCounts FclBroadPhase::query(const Vec3& point, std::vector<std::uint32_t>& out) {
    out.clear();
    mQuery.setTranslation(fcl::Vector3d(point.x, point.y, point.z));
    mQuery.computeAABB();
    mManager.collide(&mQuery, &out, collectSlot);
    return {static_cast<std::uint32_t>(out.size()), 0};
}

} // namespace hapto::bench
