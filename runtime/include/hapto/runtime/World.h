#pragma once
/// The shared world: immutable snapshots of the scene and its index, published by the control
/// thread and read by every servo thread without locks, waiting or allocation.

#include "hapto/index/SpatialIndex.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/scenes/Scene.h"

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

namespace hapto {

/// A dynamic body at rest, as the control thread hands it to the world
/// (World::setRestingBodies; Runtime::maintain reads it from the BodyPoseTable), and as a
/// snapshot records it (WorldSnapshot::rest).
struct BodyRest {
    ObjectId id = 0;           ///< The scene object's id.
    bool indexed = false;      ///< In a snapshot: the body rests in its scene and index.
    Vec3 center{0.0};          ///< The rest pose's SceneObject::center (m), as published.
    Quat rotation{1, 0, 0, 0}; ///< The rest pose's rotation, as published (bit for bit).
    Vec3 centerOfMass{0.0};    ///< The centre of mass at rest (m).
    std::uint64_t sinceNs = 0; ///< [control] Handed to the world at this pose since (ns).
};

/// One immutable state of the world. Servo threads hold a raw pointer to it for a tick.
///
/// Sleeping bodies. A dynamic body that sleeps (BodyPose::sleeping) re-enters the static world
/// once the control thread's upkeep has indexed it: in such a snapshot its object is a static
/// object of `scene` (`body.dynamic` false) at its rest pose, the index holds its items there,
/// `dynamic` still lists its slot (body i stays entry i) and `rest[i]` says so, with the rest
/// pose bit for bit as the table published it. A servo renders it from the index like any
/// static object while the table shows it asleep at that pose, and from the table (placed in
/// its DynamicBodySet) as soon as the table shows it awake or elsewhere: waking needs no new
/// snapshot.
struct WorldSnapshot {
    std::uint64_t version = 0;                 ///< Increases with every publication.
    std::shared_ptr<const Scene> scene;        ///< Every object at its current pose.
    std::shared_ptr<const SpatialIndex> index; ///< Built over the resting objects.
    /// Slots of objects not (or not correctly) in the index: moving, or added since the last
    /// build. The renderer tests them by brute force every tick, the paper's section 3.
    std::vector<std::uint32_t> moving;
    /// Slots of the scene's dynamic objects (BodyProperties::dynamic) in slot order: entry i
    /// is body i of the BodyPoseTable. Their poses come from that table, never from `scene`.
    std::vector<std::uint32_t> dynamic;
    /// One per entry of `dynamic`: whether body i rests in this snapshot's scene and index
    /// (`indexed`), and at which pose.
    std::vector<BodyRest> rest;
    /// Bodies with `rest[i].indexed`.
    std::uint32_t restingCount = 0;

    /// The moving slots as a span. [servo]
    std::span<const std::uint32_t> movingSlots() const noexcept { return moving; }
    /// The dynamic slots as a span (body i is entry i). [servo]
    std::span<const std::uint32_t> dynamicSlots() const noexcept { return dynamic; }
    /// The body whose object is in `slot` and rests in this snapshot's index, or -1. O(log
    /// bodies). [servo]
    std::int64_t restingBodyAt(std::uint32_t slot) const noexcept;
};

/// A servo thread's published claim on a snapshot (a hazard pointer), one cache line each.
struct alignas(64) SnapshotReader {
    std::atomic<const WorldSnapshot*> held{nullptr}; ///< The snapshot this reader may be using.
    std::atomic<bool> inUse{false};                  ///< Allocated to a thread.
};

/// Owns the snapshots. Design note: publication is one atomic pointer store. A reader claims
/// the current snapshot by storing it in its SnapshotReader and re-checking that it is still
/// current (the hazard-pointer protocol); the control thread frees a retired snapshot only
/// when no reader holds it. Readers never wait or allocate; a claim retries only if a
/// publication raced it, and publications are rare next to ticks. An update copies the scene
/// (O(N) on the control thread) and reuses the index: while an object moves, its stale index
/// entries only add candidates (harmless: the renderer tests real geometry) and the moving
/// list makes sure it is tested where it now is. Once it has rested for `restDelay`, a new
/// index is built on a background thread (TBB inside) and published. Time is CLOCK_MONOTONIC,
/// or a ManualClock given to useClock(), which also makes builds run inline: deterministic.
class World {
public:
    /// Builds the index over the scene and publishes version 1. [control]
    World(Scene scene, IndexSpec spec);
    /// The same over a scene the caller shares (not null): version 1 holds this very scene,
    /// not a copy, so a command that also needs the scene (its devices, its view) keeps one
    /// copy in memory. [control]
    World(std::shared_ptr<const Scene> scene, IndexSpec spec);
    ~World();
    World(const World&) = delete;
    World& operator=(const World&) = delete;

    /// Registers a reader (one per servo thread). There is no fixed cap: a reader given back
    /// is reused, otherwise a new one is made (allocates; its address stays valid for the
    /// world's life). Takes a mutex that only register, unregister and reclamation use: the
    /// servo path (acquire) never touches it. [control]
    SnapshotReader* registerReader();
    /// Gives a reader back; it must not be inside a tick. [control]
    void unregisterReader(SnapshotReader* reader);
    /// Readers made so far (in use or free). [control]
    std::size_t readerCount() const;

    /// Claims the current snapshot for `reader` until its next acquire. Lock-free, never
    /// allocates. [servo]
    const WorldSnapshot& acquire(SnapshotReader& reader) const noexcept {
        const WorldSnapshot* s = mCurrent.load(std::memory_order_acquire);
        for (;;) {
            reader.held.store(s, std::memory_order_seq_cst);
            const WorldSnapshot* again = mCurrent.load(std::memory_order_seq_cst);
            if (again == s) {
                return *s;
            }
            s = again;
        }
    }
    /// The current snapshot, for the control thread (which also owns reclamation). [control]
    const WorldSnapshot& current() const noexcept {
        return *mCurrent.load(std::memory_order_acquire);
    }

    /// Moves an object now: the next tick of every servo thread sees it at its new pose, and
    /// it is rendered by brute force until it rests. Throws InputError for an unknown id. [control]
    void moveObject(ObjectId id, const Vec3& center, const Quat& rotation);
    /// Adds an object: rendered by brute force at once, indexed once it rests. [control]
    void addObject(const SceneObject& object);
    /// Removes an object: takes effect when the index without it is built (background). [control]
    void removeObject(ObjectId id);
    /// True while the object is rendered by the brute-force path. [control]
    bool isMoving(ObjectId id) const;

    /// Re-indexes objects that have rested for `restDelay`, publishes finished builds, and
    /// frees snapshots no reader holds. Call it often from the control thread. [control]
    void maintain();
    /// Waits for any background build and publishes it; then reclaims. For tests and
    /// shutdown. [control]
    void settle();

    /// The dynamic bodies asleep now (id, rest pose as the table published it; `indexed` and
    /// `sinceNs` are ignored). A body listed at the same pose for `restDelay` is put into the
    /// static index by a later maintain() (a new index built over the scene with the body at
    /// that pose as a static object, published with it); a body no longer listed, or listed
    /// at another pose, becomes dynamic again at once in a snapshot that shares the current
    /// index (its items there are then stale and skipped, as every dynamic object's are).
    /// Ids of objects that are not dynamic bodies are ignored. [control]
    void setRestingBodies(std::vector<BodyRest> resting);
    /// Bodies resting in the current snapshot's index. [control]
    std::uint32_t restingIndexed() const { return current().restingCount; }

    /// How long an object must stay still before it goes back into the index.
    void setRestDelay(std::chrono::nanoseconds delay) { mRestDelay = delay; }
    /// Deterministic mode, for the runtime's step mode, tests and tools: times (moves, the
    /// rest delay, build starts) come from `clock` (which must outlive the world), and an
    /// index build runs inline in the maintain() that starts it and is published there, not
    /// on a background thread; the same calls at the same clock times give the same
    /// snapshots. Call it before any update. [control]
    void useClock(const ManualClock& clock) { mClock = &clock; }
    /// The index specification every build uses. [any thread]
    const IndexSpec& spec() const { return mSpec; }
    /// Index builds published so far (the first one included). [control]
    std::uint64_t buildsPublished() const { return mBuildsPublished; }
    /// Snapshots retired but still held by some reader. [control]
    std::size_t retiredCount() const { return mRetired.size(); }

private:
    struct Mover {
        ObjectId id;
        std::uint64_t lastMoveNs;
    };
    struct PendingBuild {
        std::vector<ObjectId> removed; // ids this build leaves out
        std::vector<BodyRest> resting; // bodies this build's scene holds at rest, by id
        std::uint64_t startedNs;
        std::future<std::shared_ptr<const SpatialIndex>> index;
    };

    void publish(std::shared_ptr<const Scene> scene, std::shared_ptr<const SpatialIndex> index);
    std::vector<std::uint32_t> movingSlotsFor(const Scene& scene) const;
    void startBuild();
    static std::shared_ptr<const Scene> without(const Scene& scene,
                                                const std::vector<ObjectId>& ids);
    void finishBuild();
    std::shared_ptr<const Scene> withResting(std::shared_ptr<const Scene> scene,
                                             const std::vector<BodyRest>& resting) const;
    std::vector<BodyRest> stillWanted(const std::vector<BodyRest>& resting) const;
    bool restDue(std::uint64_t nowNs) const;
    void reclaim();
    std::uint64_t nowNs() const noexcept;
    bool rested(const Mover& mover, std::uint64_t nowNs) const noexcept;

    IndexSpec mSpec;
    std::atomic<const WorldSnapshot*> mCurrent{nullptr};
    std::unique_ptr<WorldSnapshot> mOwned; // the current snapshot's owner
    std::vector<std::unique_ptr<WorldSnapshot>> mRetired;
    mutable std::mutex mReadersMutex;    // register, unregister, reclaim; never the servo path
    std::deque<SnapshotReader> mReaders; // grows at the back only: addresses stay valid
    std::vector<Mover> mMovers;
    std::unique_ptr<PendingBuild> mBuild;
    std::vector<ObjectId> mPendingRemovals; // removals wait for a build
    std::vector<ObjectId> mBodyIds;         // the dynamic bodies' ids, sorted
    std::vector<BodyRest> mRestWanted;      // asleep now, by id (setRestingBodies)
    std::vector<BodyRest> mRestPublished;   // at rest in the current snapshot, by id
    std::chrono::nanoseconds mRestDelay = std::chrono::milliseconds(100);
    const ManualClock* mClock = nullptr; // deterministic mode; nullptr: CLOCK_MONOTONIC
    std::uint64_t mVersion = 0;
    std::uint64_t mBuildsPublished = 0;
};

} // namespace hapto
