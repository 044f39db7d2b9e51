#pragma once
/// Two-handed grasping: two devices that squeeze one object from opposite sides pick it up,
/// carry it, and put it down; let go and it falls.

#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/World.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace hapto {

/// How grasping behaves. Gravity is along -y (world frame, y up).
struct GraspOptions {
    double densityKgPerM3 = 500.0; ///< Object mass = density x volume (a 5 cm cube: 62.5 g).
    double gravityMPerS2 = 9.81;   ///< |g|.
    double minOpposition = 0.5;    ///< Contact normals must satisfy n_left . n_right <= -this.
    double holdMargin = 1.0;       ///< Grasp when mu_s (Fn_left + Fn_right) >= margin x m g.
    int graspSteps = 20;           ///< Control steps the grasp condition must hold to grasp.
    int releaseSteps = 50;         ///< Control steps it must fail to release (~50 ms: a
                                   ///< transient dip in contact does not drop the object).
    double clearanceM = 1e-4;      ///< Gap kept to other objects while carried or falling (m).
};

/// What the controller is doing.
enum class GraspState : std::uint8_t {
    Idle,    ///< Nothing held.
    Grasped, ///< The object follows the two hands.
    Falling, ///< Released, falling under gravity.
};

/// One sample of the held or falling object's path.
struct GraspPathPoint {
    double timeS = 0;   ///< Since the controller started (s).
    GraspState state{}; ///< What it was doing then.
    Vec3 position{0.0}; ///< Object centre (m).
};

/// Runs on the control thread next to a Runtime: reads the two devices' contact reports,
/// decides grasp and release, moves the object through World::moveObject (so it leaves the
/// index and is rendered by brute force while it moves, and goes back in at rest), and gives
/// each hand half the object's weight through Runtime::setExternalForce. Never blocks a servo
/// thread. Every member is [control].
class GraspController {
public:
    /// Watches devices `left` and `right` of `runtime`.
    GraspController(World& world, Runtime& runtime, std::size_t left, std::size_t right,
                    GraspOptions options = {});

    /// Advances by dtS seconds (call at ~1 kHz).
    void step(double dtS);

    /// The current state.
    GraspState state() const { return mState; }
    /// The object held or falling, if any; else the last one.
    std::optional<ObjectId> object() const { return mObject; }
    /// Control steps spent grasped, in total.
    std::uint64_t graspedSteps() const { return mGraspedSteps; }
    /// Times (s) grasps started and ended.
    const std::vector<double>& graspStarts() const { return mStarts; }
    /// Times (s) grasps ended.
    const std::vector<double>& graspEnds() const { return mEnds; }
    /// The object's path (one point every 10 ms while it moves, plus every state change).
    const std::vector<GraspPathPoint>& path() const { return mPath; }
    /// Mass of the current object (kg).
    double massKg() const { return mMassKg; }

private:
    bool opposed(const ContactReport& l, const ContactReport& r, ObjectId& id, double& fn) const;
    void startGrasp(ObjectId id, const ContactReport& l, const ContactReport& r);
    void release();
    void carry(const ContactReport& l, const ContactReport& r);
    void fall(double dtS);
    bool blocked(const SceneObject& moved) const;
    void moveTo(const SceneObject& object, Vec3 center, const Quat& rotation);
    void record(bool force = false);

    World& mWorld;
    Runtime& mRuntime;
    std::size_t mLeft, mRight;
    GraspOptions mOptions;
    GraspState mState = GraspState::Idle;
    std::optional<ObjectId> mObject;
    int mHoldCount = 0, mLoseCount = 0;
    double mTime = 0, mLastRecord = -1;
    double mMassKg = 0, mFallSpeed = 0;
    Vec3 mGripCenter0{0.0}, mGripAxis0{1, 0, 0}, mObjectCenter0{0.0};
    Quat mObjectRotation0{1, 0, 0, 0};
    std::uint64_t mGraspedSteps = 0;
    std::vector<double> mStarts, mEnds;
    std::vector<GraspPathPoint> mPath;
    ContactReport mLastLeft, mLastRight; // the newest reports read
    bool mHaveLeft = false, mHaveRight = false;
};

/// Mass of an object at a density (kg): a closed mesh's enclosed volume (O(triangles)), an open
/// mesh's OBB volume. [any thread]
double objectMassKg(const SceneObject& object, double densityKgPerM3);

} // namespace hapto
