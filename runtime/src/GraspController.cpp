// Two-handed grasping. Design note: grasping is a control-thread affair. Each servo thread
// publishes its contacts every tick (a lock-free mailbox); at ~1 kHz the controller reads both,
// and when the two hands touch one object from opposing sides hard enough that static friction
// holds its weight (mu_s (Fn_l + Fn_r) >= m g) for a few steps, the object is grasped. It then
// follows the two device points: translation from their midpoint, rotation from the turn of
// the axis between them (the one rotation two points define). Each move is published through
// World::moveObject, so the object leaves the index and is rendered by the brute-force path
// while it moves; the hands' proxies ride along with it (the renderer carries a proxy with the
// object it touches). Each hand is given half the weight as an external force. When either
// hand lets go, the object falls under gravity onto the highest support below it, or onto the
// bounds' floor, and the World puts it back into the index once it has rested. A move that
// would push the object into another is cut short (bisection on the straight path), so it
// never passes through anything. Cost per step: O(N) over the scene for the collision checks.
//
// Meshes are grasped like boxes: the hands' contacts name the mesh's ObjectId (whichever of
// its triangles they touch), the object moves by its pose (its triangles are never copied),
// and the carry and fall checks use the mesh's OBB (its placed local bounds), a conservative
// stand-in for its triangles: a carried torus keeps the clearance from its bounding box, not
// from its tube. Its mass is density x the volume it encloses (a closed mesh) or x its OBB's
// volume (an open one, which encloses none).

#include "hapto/runtime/GraspController.h"

#include "hapto/index/Overlap.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace hapto {

namespace {

// The volume a closed mesh encloses (m^3): the sum of the signed tetrahedra from the local
// origin to each outward triangle (the divergence theorem). O(triangles), once per grasp.
double enclosedVolume(const TriangleMesh& mesh) {
    double sixTimes = 0.0;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const auto c = mesh.corners(t);
        sixTimes += glm::dot(c[0], glm::cross(c[1], c[2]));
    }
    return std::abs(sixTimes) / 6.0;
}

} // namespace

double objectMassKg(const SceneObject& o, double density) {
    double volume = 8.0 * o.halfExtents.x * o.halfExtents.y * o.halfExtents.z;
    if (o.shape == Shape::Sphere) {
        volume = 4.0 / 3.0 * std::numbers::pi * std::pow(o.halfExtents.x, 3);
    } else if (o.shape == Shape::Mesh && o.mesh && o.mesh->closed()) {
        volume = enclosedVolume(*o.mesh);
    }
    return density * volume;
}

GraspController::GraspController(World& world, Runtime& runtime, std::size_t left,
                                 std::size_t right, GraspOptions options)
    : mWorld(world), mRuntime(runtime), mLeft(left), mRight(right), mOptions(options) {}

namespace {

const SceneObject* find(const WorldSnapshot& s, ObjectId id) {
    const auto slot = s.scene->slotOf(id);
    return slot ? &s.scene->object(*slot) : nullptr;
}

// The rotation that turns unit vector a onto unit vector b (the shortest arc).
Quat arc(const Vec3& a, const Vec3& b) {
    const double d = glm::dot(a, b);
    if (d > 1.0 - 1e-12) {
        return Quat(1, 0, 0, 0);
    }
    if (d < -1.0 + 1e-12) {
        Vec3 axis = glm::cross(a, Vec3(0, 1, 0));
        if (glm::length(axis) < 1e-6) {
            axis = glm::cross(a, Vec3(1, 0, 0));
        }
        return glm::angleAxis(std::numbers::pi, glm::normalize(axis));
    }
    const Vec3 c = glm::cross(a, b);
    return glm::normalize(Quat(1.0 + d, c.x, c.y, c.z));
}

} // namespace

bool GraspController::opposed(const ContactReport& l, const ContactReport& r, ObjectId& id,
                              double& fn) const {
    for (std::uint32_t i = 0; i < l.contactCount; ++i) {
        for (std::uint32_t j = 0; j < r.contactCount; ++j) {
            if (l.objects[i] != r.objects[j] || l.objects[i] == kNoObject) {
                continue;
            }
            const Vec3& nl = l.normals[i];
            const Vec3& nr = r.normals[j];
            if (glm::dot(nl, nr) > -mOptions.minOpposition) {
                continue;
            }
            id = l.objects[i];
            // The force pushes each hand out of the object: its normal part is the squeeze.
            fn = std::max(0.0, glm::dot(l.force, nl)) + std::max(0.0, glm::dot(r.force, nr));
            return true;
        }
    }
    return false;
}

void GraspController::step(double dtS) {
    mTime += dtS;
    // A read that races a servo thread's write (the writer preempted mid-publish) keeps the
    // last report: "no fresh news" is not "no contact".
    ContactReport l = mLastLeft, r = mLastRight;
    const bool haveL = mRuntime.lastTick(mLeft, l) || mHaveLeft;
    const bool haveR = mRuntime.lastTick(mRight, r) || mHaveRight;
    mLastLeft = l;
    mLastRight = r;
    mHaveLeft = haveL;
    mHaveRight = haveR;
    ObjectId id = kNoObject;
    double fn = 0.0;
    const bool touching = haveL && haveR && opposed(l, r, id, fn);

    switch (mState) {
    case GraspState::Idle:
    case GraspState::Falling: {
        bool holds = false;
        if (touching) {
            if (const SceneObject* o = find(mWorld.current(), id)) {
                const double weight =
                    objectMassKg(*o, mOptions.densityKgPerM3) * mOptions.gravityMPerS2;
                holds = o->material.staticFriction * fn >= mOptions.holdMargin * weight;
            }
        }
        mHoldCount = holds ? mHoldCount + 1 : 0;
        if (holds && mHoldCount >= mOptions.graspSteps) {
            startGrasp(id, l, r);
        } else if (mState == GraspState::Falling) {
            fall(dtS);
        }
        break;
    }
    case GraspState::Grasped: {
        bool keeps = touching && mObject && id == *mObject;
        if (keeps) {
            const double weight = mMassKg * mOptions.gravityMPerS2;
            const SceneObject* o = find(mWorld.current(), id);
            keeps = o && o->material.staticFriction * fn >= mOptions.holdMargin * weight;
        }
        mLoseCount = keeps ? 0 : mLoseCount + 1;
        if (mLoseCount >= mOptions.releaseSteps) {
            release();
        } else {
            ++mGraspedSteps;
            carry(l, r);
        }
        break;
    }
    }
    record();
}

void GraspController::startGrasp(ObjectId id, const ContactReport& l, const ContactReport& r) {
    const SceneObject* o = find(mWorld.current(), id);
    if (!o) {
        return;
    }
    mState = GraspState::Grasped;
    mObject = id;
    mMassKg = objectMassKg(*o, mOptions.densityKgPerM3);
    mGripCenter0 = 0.5 * (l.devicePoint + r.devicePoint);
    mGripAxis0 = glm::normalize(r.devicePoint - l.devicePoint);
    mObjectCenter0 = o->center;
    mObjectRotation0 = o->rotation;
    mLoseCount = 0;
    mFallSpeed = 0;
    mStarts.push_back(mTime);
    const Vec3 halfWeight(0.0, -0.5 * mMassKg * mOptions.gravityMPerS2, 0.0);
    mRuntime.setExternalForce(mLeft, halfWeight);
    mRuntime.setExternalForce(mRight, halfWeight);
    record(true);
}

void GraspController::release() {
    mState = GraspState::Falling;
    mHoldCount = 0;
    mFallSpeed = 0;
    mEnds.push_back(mTime);
    mRuntime.setExternalForce(mLeft, Vec3(0.0));
    mRuntime.setExternalForce(mRight, Vec3(0.0));
    record(true);
}

void GraspController::carry(const ContactReport& l, const ContactReport& r) {
    const SceneObject* o = find(mWorld.current(), *mObject);
    if (!o) {
        release();
        return;
    }
    const Vec3 center = 0.5 * (l.devicePoint + r.devicePoint);
    const Vec3 d = r.devicePoint - l.devicePoint;
    if (glm::length(d) < 1e-6) {
        return;
    }
    const Quat turn = arc(mGripAxis0, glm::normalize(d));
    moveTo(*o, center + turn * (mObjectCenter0 - mGripCenter0),
           glm::normalize(turn * mObjectRotation0));
}

void GraspController::fall(double dtS) {
    const SceneObject* o = find(mWorld.current(), *mObject);
    if (!o) {
        mState = GraspState::Idle;
        return;
    }
    mFallSpeed += mOptions.gravityMPerS2 * dtS;
    const Vec3 target = o->center - Vec3(0.0, mFallSpeed * dtS, 0.0);
    const Vec3 before = o->center;
    moveTo(*o, target, o->rotation);
    const SceneObject* after = find(mWorld.current(), *mObject);
    // At rest once the fall is cut short by a support or the floor.
    if (!after || after->center.y > target.y + 1e-9 || after->center == before) {
        mState = GraspState::Idle;
        mFallSpeed = 0;
        record(true);
    }
}

bool GraspController::blocked(const SceneObject& moved) const {
    const WorldSnapshot& s = mWorld.current();
    // The floor: the bounds' lowest y.
    if (moved.aabb().min.y < s.scene->bounds().min.y - 1e-12) {
        return true;
    }
    // Keep a small clearance: shrink nothing, grow the moved box by the clearance and test
    // against the others' boxes with the exact (not the biased) test.
    Obb a = moved.obb();
    a.halfExtents += Vec3(mOptions.clearanceM * 0.5);
    const Aabb reach{a.aabb().min, a.aabb().max};
    for (const SceneObject& other : s.scene->objects()) {
        if (other.id == moved.id || !reach.overlaps(other.aabb())) {
            continue;
        }
        if (overlapsObbObb(a, other.obb())) {
            return true;
        }
    }
    return false;
}

void GraspController::moveTo(const SceneObject& object, Vec3 center, const Quat& rotation) {
    SceneObject trial = object;
    trial.center = center;
    trial.rotation = rotation;
    if (blocked(trial) && rotation != object.rotation) {
        trial.rotation = object.rotation; // a move that only turns into something: translate
    }
    if (blocked(trial)) {
        // Bisect along the straight path for the farthest pose that is free.
        double lo = 0.0, hi = 1.0;
        for (int i = 0; i < 20; ++i) {
            const double mid = 0.5 * (lo + hi);
            trial.center = glm::mix(object.center, center, mid);
            (blocked(trial) ? hi : lo) = mid;
        }
        if (lo == 0.0) {
            return; // cannot move at all this step
        }
        trial.center = glm::mix(object.center, center, lo);
    }
    mWorld.moveObject(object.id, trial.center, trial.rotation);
}

void GraspController::record(bool force) {
    if (!mObject) {
        return;
    }
    if (!force && (mState == GraspState::Idle || mTime - mLastRecord < 0.01)) {
        return;
    }
    mLastRecord = mTime;
    if (const SceneObject* o = find(mWorld.current(), *mObject)) {
        mPath.push_back({mTime, mState, o->center});
    }
}

} // namespace hapto
