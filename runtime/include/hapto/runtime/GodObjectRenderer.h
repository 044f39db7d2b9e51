#pragma once
/// God-object (proxy) haptic rendering of a point tool against oriented boxes, spheres and
/// triangle meshes.

#include "hapto/core/ClosestPoint.h"
#include "hapto/runtime/CandidateSet.h"
#include "hapto/runtime/DynamicBodySet.h"
#include "hapto/runtime/RenderOutput.h"
#include "hapto/scenes/Scene.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace hapto {

/// Renders one point device against a scene with a god-object proxy (Zilles & Salisbury 1995,
/// Ruspini et al. 1997) and Coulomb friction. One instance per device: it holds that device's
/// proxy and scratch space, shares nothing, and never allocates after construction.
///
/// Size: 12416 bytes (64-byte aligned; checked by a static_assert in the source file), of which
/// 1280 are the near-object scratch list, 6912 the tick's copy of its first 32 candidate
/// triangles (plane, corners, edges: 216 bytes each), 2048 the table of the candidates a near
/// list has read (so an item two leaves list is read once) and 1608 the points the proxy
/// visited (visitedPath). A tick solved again restores only the 384-byte State.
class alignas(64) GodObjectRenderer {
public:
    /// Constraint planes solved at once (a corner needs three).
    static constexpr std::size_t kMaxContacts = 3;
    /// Nearby items (objects and triangles) one tick can track; beyond this the tick runs on
    /// the raw candidate spans. Triangles enter the list only when they come within the reach
    /// of this tick's proxy path plus 1 µm (not the objects' 1 mm margin), so a fine mesh under
    /// a pressing tool adds the few triangles around the contact, not every triangle in a
    /// millimetre.
    static constexpr std::size_t kMaxNearObjects = 256;
    /// Candidate triangles (a tick's first ones, in the candidates' order) whose plane, corners
    /// and edges the renderer copies once per tick for its near lists and solver passes; a
    /// triangle past them is read from the scene each time (the same result, more slowly).
    static constexpr std::size_t kCachedTriangles = 32;
    /// Upper bound for RendererConfig::maxIterations.
    static constexpr std::uint32_t kMaxIterations = 32;
    /// Points visitedPath() can hold: the tick's start, and each of two solves' start and
    /// passes.
    static constexpr std::size_t kMaxVisited = 2 * (kMaxIterations + 1) + 1;
    /// The proxy rides this far (m) outside every surface: a 10 nm skin that closes the cracks
    /// between flush objects. It adds stiffness x 1e-8 m to each force (8 µN at 800 N/m).
    static constexpr double kSkinM = 1e-8;

    /// Checks the configuration; throws std::invalid_argument on a negative/NaN damping or
    /// an iteration count outside 1..kMaxIterations. [control]
    explicit GodObjectRenderer(const RendererConfig& config = {});

    /// Puts the proxy on the device point with no contact and no friction state. If that point
    /// is inside an object, that object is ignored until the proxy has left it (a box or
    /// sphere is passed through while it contains the proxy; a mesh triangle is entered only
    /// from its front, so the inside of a closed mesh is left through its back faces). [servo]
    void reset(const Vec3& devicePosition) noexcept;

    /// One servo tick: moves the proxy toward `devicePosition` (m, world) without entering any
    /// candidate object, applies friction, and returns force = k (proxy - device) - damping
    /// (N). `deviceVelocity` (m/s) feeds damping; if it is not finite it is estimated from the
    /// last position over `dtSeconds`. Only objects named in `candidates` are looked at (slots
    /// outside the scene are skipped). With several contacts the smallest stiffness and the
    /// smallest friction coefficients among the touched objects apply (conservative). Never
    /// allocates, locks or throws.
    ///
    /// Candidates are items (Scene items): box and sphere slots, mesh triangle items, and a
    /// mesh object's own slot (a moving mesh, from the snapshot's moving list), for which the
    /// renderer visits that mesh's triangles near the proxy path in the mesh's own frame.
    /// Triangles are one-sided: a path entering one from behind passes through. [servo]
    RenderOutput update(const Scene& scene, const CandidateSet& candidates,
                        const Vec3& devicePosition, const Vec3& deviceVelocity,
                        double dtSeconds) noexcept;
    /// The same tick with the proxy's motion held short: the proxy moves toward `goal` (m,
    /// world; a point on the way from the proxy to the device point) instead of the device
    /// point, and the contacts and the force are still taken at `devicePosition`: the planes
    /// the proxy ends on that the device point is behind, force = k (proxy - device) - damping.
    /// HapticTick pulls the goal back this way when the proxy's path to the device point
    /// crosses more leaves than one tick can list, so a pulled-back tick moves the proxy less
    /// but pushes as hard. With `goal` == `devicePosition` it is update() above. [servo]
    RenderOutput update(const Scene& scene, const CandidateSet& candidates,
                        const Vec3& devicePosition, const Vec3& goal, const Vec3& deviceVelocity,
                        double dtSeconds) noexcept;

    /// The proxy position (m, world). [servo]
    const Vec3& proxy() const noexcept { return mState.proxy; }
    /// Where the proxy went during the last update() (m, world), as two polylines: path 0 is
    /// the proxy at the tick's start, then the frictionless solve's start and the end of each
    /// of its passes; path 1 the friction solve's start and passes (empty when there was
    /// none). The proxy moved only along these segments, so a caller that listed every leaf
    /// they cross gave the renderer every item the proxy could reach. [servo]
    std::span<const Vec3> visitedPath(int which) const noexcept {
        return which == 0 ? std::span<const Vec3>(mVisited.data(), mVisitedSecond)
                          : std::span<const Vec3>(mVisited.data() + mVisitedSecond,
                                                  mVisitedCount - mVisitedSecond);
    }
    /// Fault counters since construction. [servo] (copy them out to share)
    const RenderCounters& counters() const noexcept { return mState.counters; }
    /// True while the last tick ended in contact. [servo]
    bool inContact() const noexcept { return mState.contactCount > 0; }
    /// The configuration. [any thread]
    const RendererConfig& config() const noexcept { return mConfig; }
    /// The damping c (N s/m) the coupling adds on the velocity relative to a dynamic body
    /// touched with `stiffnessNPerM` (N/m) while the dynamics steps every `stepS` (s): c = k h.
    /// The discrete loop (the force from the pose the step published, symplectic Euler) then
    /// never raises the body's energy 1/2 m v^2 + sum 1/2 k_i x_i^2 while the touching
    /// stiffnesses sum to at most m / h^2 (a = sum k h^2 / m <= 1), whatever the number of
    /// hands, and is stable for a < 4/3; see the design note in GodObjectRenderer.cpp. 0 for
    /// a non-positive input. [any thread]
    static double dynamicCouplingDamping(double stiffnessNPerM, double stepS) noexcept;
    /// The dynamic bodies placed for the next update()s (null: none): a dynamic object's pose
    /// is read from here, never from the scene, and its items the static index lists are
    /// skipped (DynamicBodySet.h). The set must stay unchanged while an update() runs. [servo]
    void useDynamicBodies(const DynamicBodySet* bodies) noexcept { mDynamic = bodies; }
    /// Says that the next update() solves the same tick again (after restore(), with the same
    /// scene, bodies and device point) over candidates that extend this update's: the same
    /// spans in the same order, then maybe more. That update keeps the near list and reads only
    /// the new spans' items, which gives the list a full build would, so a tick solved again
    /// for one more leaf costs that leaf, not every candidate again (HapticTick's re-solves and
    /// pull-backs). The next update() with other spans builds its list afresh. [servo]
    void extendNextUpdate() noexcept { mExtendNear = true; }

    /// What carries over from one tick to the next (the proxy, the friction and contact state,
    /// the counters), without the per-tick scratch: a tick solved again restores it. [servo]
    struct State {
        RenderCounters counters;       ///< Fault counters since construction.
        Vec3 proxy{0.0};               ///< God-object position (m).
        Vec3 lastDevice{0.0};          ///< Device position of the previous tick (m).
        bool hasLastDevice = false;    ///< lastDevice is set.
        bool slipping = false;         ///< Friction state: kinetic (true) or static (false).
        std::uint8_t contactCount = 0; ///< Last tick's contacts.
        std::array<std::uint32_t, kMaxContacts> contactSlots{}; ///< Last tick's touched items.
        /// Pose of a touched object at the end of the last tick, to carry the proxy when it
        /// moves.
        struct ContactPose {
            ObjectId id = 0;           ///< The touched object.
            Vec3 center{0.0};          ///< Its centre then (m).
            Quat rotation{1, 0, 0, 0}; ///< Its orientation then.
        };
        std::array<ContactPose, kMaxContacts> contactPoses{}; ///< One per last tick's contact.
        /// The planes the proxy rested on at the end of the last tick, as items and normals:
        /// the next tick's first solve starts on those its start still touches (restingPlanes).
        std::uint8_t restCount = 0;
        std::array<std::uint32_t, kMaxContacts> restItems{}; ///< Each plane's item.
        std::array<Vec3, kMaxContacts> restNormals{};        ///< Each plane's outward normal.
    };
    /// The state that the next update() starts from. [servo]
    const State& state() const noexcept { return mState; }
    /// Puts back a state taken with state(): the next update() runs as if the updates since
    /// had not happened. [servo]
    void restore(const State& state) noexcept { mState = state; }

private:
    /// A constraint half-space {x : dot(normal, x) >= offset}, from one object's face or one
    /// mesh triangle (`item`, as in Contact::slot).
    struct Plane {
        Vec3 normal{0.0};
        double offset = 0.0;
        std::uint32_t item = 0;
        std::uint32_t near = kNotCached; ///< The item's place in mTriangleData, if there.
    };
    /// A candidate triangle as the near list reads it: its world plane, read once per tick,
    /// and for a triangle that got near, its corners, edges and mesh slot; so that a second
    /// near list (the friction solve's) reads nothing from the scene again, and the solver's
    /// passes read this compact array, not the scene's meshes.
    struct NearTriangle {
        std::uint32_t item = 0;
        std::uint32_t mesh = 0; ///< Its mesh's slot, once `hasEdges`.
        bool hasCorners = false;
        bool hasEdges = false;
        WorldFace face;
        std::array<Vec3, 3> corners{};
        TriangleEdges edges; ///< Its edges in its plane.
    };
    static constexpr std::uint32_t kNotCached = 0xffffffffu;
    /// Slots of the table of candidates read (mSeen); past kSeenFull items a build looks the
    /// rest up in the earlier spans instead.
    static constexpr std::size_t kSeenSlots = 256;
    static constexpr std::uint32_t kSeenFull = 192;
    /// Where a solve ended.
    struct Solve {
        Vec3 proxy{0.0};
        std::array<Plane, kMaxContacts> planes{};
        std::uint32_t planeCount = 0;
        bool touched = false; ///< The proxy reached a surface this solve.
        Vec3 firstTouch{0.0}; ///< Where it first did.
        std::uint32_t iterations = 0;

        /// Drops the planes the proxy at `at` is not on (within the on-plane tolerance).
        void keepPlanesOn(const Vec3& at) noexcept;
        /// Adds a plane unless the same plane is there; false when there is no room.
        bool addPlane(const Plane& plane) noexcept;
    };
    /// What the friction step decided: the final solve, the passes of both solves, and
    /// whether the proxy held its anchor.
    struct Friction {
        Solve solve;
        std::uint32_t iterations = 0;
        bool stuck = false;
    };
    struct Hit;

    // The tick (GodObjectRenderer.cpp).
    /// The device velocity (m/s): the given one, or estimated from the last position.
    Vec3 velocityAt(const Vec3& devicePosition, const Vec3& deviceVelocity,
                    double dtSeconds) const noexcept;
    /// The proxy's start: carried by a touched object that moved, pushed out of one that moved
    /// into it.
    Vec3 startOfTick(const Scene& scene, const CandidateSet& candidates, const Vec3& goal,
                     std::uint32_t& tested) noexcept;
    /// Fills out.contacts from the final planes; returns the smallest stiffness among them.
    double takeContacts(const Scene& scene, const Solve& fin, bool stuck,
                        const Vec3& devicePosition, RenderOutput& out) const noexcept;
    /// k (proxy - device) with the contact damping (and a dynamic body's coupling damping, on
    /// the velocity relative to the body's surface); zero (and no slipping) without contact.
    Vec3 contactForce(const Scene& scene, const RenderOutput& out, double stiffness,
                      const Vec3& devicePosition, const Vec3& velocity) noexcept;
    /// The coupling damping (N s/m) of the touched dynamic bodies (the largest), and the
    /// velocity of that body's surface at the proxy (m/s); 0 without one.
    double couplingDampingOf(const Scene& scene, const RenderOutput& out, double stiffness,
                             Vec3& surfaceVelocity) const noexcept;
    /// The status and counters, a non-finite result zeroed, and the state the next tick
    /// starts from.
    void finishTick(const Scene& scene, const CandidateSet& candidates, const Vec3& start,
                    const Vec3& goal, RenderOutput& out) noexcept;

    // The poses, dynamic bodies placed (GodObjectNearList.cpp).
    /// The render copy of an object slot: a placed dynamic body's, or the scene's.
    const RenderBody& bodyAt(const Scene& scene, std::uint32_t slot) const noexcept;
    /// An object's pose (centre, rotation) as SceneObject spells it, placed or the scene's.
    void poseAt(const Scene& scene, std::uint32_t slot, Vec3& center,
                Quat& rotation) const noexcept;
    /// A valid triangle item's plane at its mesh's (placed) pose (m, world).
    WorldFace faceAt(const Scene& scene, std::uint32_t item) const noexcept;
    /// A valid triangle item's corners at its mesh's (placed) pose (m, world).
    std::array<Vec3, 3> cornersAt(const Scene& scene, std::uint32_t item) const noexcept;
    /// True for an item of a dynamic object that a span lists but this tick does not render
    /// there: every triangle item of a dynamic mesh (its slot stands for them), and a box or
    /// sphere slot of a body not placed.
    bool skipItem(const Scene& scene, std::uint32_t item) const noexcept;

    // The candidate gathering (GodObjectNearList.cpp).
    /// Builds the near list around `goal` unless the current one covers a reach of `need`.
    void ensureNear(const Scene& scene, const CandidateSet& candidates, const Vec3& goal,
                    double need, std::uint32_t& tested) noexcept;
    void buildNear(const Scene& scene, const CandidateSet& candidates, const Vec3& center,
                   double radius, std::uint32_t& tested) noexcept;
    /// Adds the items of the spans after those the list has read (all of them after a fresh
    /// buildNear) within the list's ball.
    void addNearSpans(const Scene& scene, const CandidateSet& candidates,
                      std::uint32_t& tested) noexcept;
    /// Asks the cache for the render copies of the objects in those spans (up to
    /// kPrefetchBodies), before they are read. A hint.
    void prefetchBodies(const Scene& scene, const CandidateSet& candidates,
                        std::size_t count) const noexcept;
    /// True when `candidates` begins with the spans the near list has read (extendNextUpdate).
    bool extendsNearSpans(const CandidateSet& candidates) const noexcept;
    /// Lists a candidate triangle (the tick's k-th) if it is within the near ball.
    void considerTriangle(const Scene& scene, std::uint32_t item, std::uint32_t k) noexcept;
    /// Lists a box or sphere, or a mesh's triangles, within the ball of `radius` (m).
    void considerObject(const Scene& scene, std::uint32_t item, double radius) noexcept;
    bool addNear(std::uint32_t item) noexcept;
    /// True when the near list has read `item` since it was built (an earlier span listed it,
    /// or this one did already), as listedEarlier over span `s` decides; records it otherwise.
    bool seenBefore(const CandidateSet& candidates, std::size_t s, std::uint32_t item) noexcept;
    /// Distance (m) from p to an item's skin, 0 inside; a cached triangle's (`near` <
    /// kCachedTriangles) from its copy.
    double distanceToSkinOf(const Scene& scene, std::uint32_t item, std::uint32_t near,
                            const Vec3& p) const noexcept;
    template <class Fn>
    void forEachNear(const Scene& scene, const CandidateSet& candidates, Fn&& fn) const noexcept;
    template <class Fn>
    void forEachMeshTriangleNear(const Scene& scene, std::uint32_t slot, const Vec3& center,
                                 double radius, Fn&& fn) const noexcept;

    // The proxy solve (GodObjectSolver.cpp).
    /// Solves toward `goal` from `start`, adding start and each pass's end to the visited
    /// points.
    /// Moves the proxy from `start` toward `goal`; `from`, when given, is a solve that ended at
    /// `start`, whose planes (those the proxy rests on there) this one starts with.
    Solve solve(const Scene& scene, const CandidateSet& candidates, const Vec3& start,
                const Vec3& goal, const Solve* from = nullptr) noexcept;
    void visit(const Vec3& p) noexcept {
        if (mVisitedCount < kMaxVisited) {
            mVisited[mVisitedCount++] = p;
        }
    }
    Hit sweep(const Scene& scene, const CandidateSet& candidates, const Vec3& from,
              const Vec3& to) const noexcept;
    /// Adds the plane the hit entered and, on an edge or corner, those beside it that the goal
    /// is behind; false when the entered plane found no room.
    bool addHitPlanes(const Scene& scene, const CandidateSet& candidates, Solve& s, const Hit& hit,
                      const Vec3& p, const Vec3& target, const Vec3& goal) noexcept;
    void addTriangleNeighbourPlanes(const Scene& scene, const CandidateSet& candidates, Solve& s,
                                    const Hit& hit, const Vec3& p, const Vec3& goal) noexcept;
    void addBoxEdgePlanes(const Scene& scene, const CandidateSet& candidates, Solve& s,
                          const Hit& hit, const Vec3& p, const Vec3& goal) noexcept;
    bool covered(const Scene& scene, const CandidateSet& candidates, const Vec3& probe,
                 std::uint32_t self) const noexcept;
    /// Drops the planes whose item the proxy at p has slid off; true when one was dropped.
    bool dropSlidOff(const Scene& scene, Solve& s, const Vec3& p) const noexcept;
    /// The planes the last tick ended on (State::restItems), taken again from the scene as it
    /// is now and kept only while `start` touches their item; none when `start` is not where
    /// the last tick left the proxy (carried or pushed out).
    Solve restingPlanes(const Scene& scene, const Vec3& start) const noexcept;
    /// A triangle item's place in mTriangleData, or kNotCached.
    std::uint32_t cachedTriangle(std::uint32_t item) const noexcept;

    // Friction (GodObjectFriction.cpp).
    Friction friction(const Scene& scene, const CandidateSet& candidates, const Vec3& start,
                      const Vec3& goal, const Solve& free, std::uint32_t& tested) noexcept;

    RendererConfig mConfig;
    State mState;
    const DynamicBodySet* mDynamic = nullptr; ///< This tick's placed dynamic bodies, or none.

    // Per-tick scratch: the deduplicated candidates that can matter this tick.
    Vec3 mNearCenter{0.0};
    /// The near ball's radius for triangles (m): the proxy's reach + 1 µm (objects get twice
    /// the reach + 1 mm); < 0: no list built this tick.
    double mNearRadius = -1.0;
    double mNearReach = 0.0; ///< The proxy's reach the list was built for (m).
    bool mNearOverflow = false;
    bool mNearTriangles = false; ///< The list saw triangles: its triangle ball is the tight one.
    bool mExtendNear = false;    ///< extendNextUpdate() was called since the last update().
    std::uint8_t mNearSpans = 0; ///< Candidate spans the list has read.
    std::span<const std::uint32_t> mNearLastSpan; ///< The last of them, to recognise the set.
    std::uint32_t mNearTriangleItems = 0;         ///< Candidate triangles the list has read.
    std::uint32_t mNearCount = 0;
    std::array<std::uint32_t, kMaxNearObjects> mNear{};
    /// mNear[i]'s place in mTriangleData, or kNotCached (boxes, spheres, triangles past it).
    std::array<std::uint8_t, kMaxNearObjects> mNearCached{};
    std::uint32_t mTriangleCount = 0; ///< mTriangleData entries read this tick.
    std::array<NearTriangle, kCachedTriangles> mTriangleData{};
    /// The candidates the near list has read since it was built (seenBefore): an open-addressed
    /// table of (build << 32 | item), so a new build empties it by counting, not by clearing.
    std::array<std::uint64_t, kSeenSlots> mSeen{};
    std::uint32_t mSeenBuild = 0; ///< This build's number in mSeen (0: none).
    std::uint32_t mSeenCount = 0; ///< Items in mSeen this build.
    // Per-tick scratch: where the proxy went (visitedPath).
    std::uint32_t mVisitedCount = 0;
    std::uint32_t mVisitedSecond = 0; ///< Where the friction solve's points begin.
    std::array<Vec3, kMaxVisited> mVisited{};
};

} // namespace hapto
