#include "hapto/runtime/World.h"

#include "hapto/io/InputError.h"
#include "hapto/runtime/Realtime.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace hapto {

namespace {

/// The same body at the same pose, bit for bit.
bool samePose(const BodyRest& a, const BodyRest& b) noexcept {
    return a.id == b.id && a.center == b.center && a.rotation == b.rotation;
}

/// The entry for `id` in a list sorted by id, or null.
const BodyRest* findRest(const std::vector<BodyRest>& list, ObjectId id) noexcept {
    const auto it = std::lower_bound(list.begin(), list.end(), id,
                                     [](const BodyRest& r, ObjectId v) { return r.id < v; });
    return it != list.end() && it->id == id ? &*it : nullptr;
}

} // namespace

std::int64_t WorldSnapshot::restingBodyAt(std::uint32_t slot) const noexcept {
    if (restingCount == 0) {
        return -1;
    }
    const auto it = std::lower_bound(dynamic.begin(), dynamic.end(), slot);
    if (it == dynamic.end() || *it != slot) {
        return -1;
    }
    const auto i = static_cast<std::size_t>(it - dynamic.begin());
    return i < rest.size() && rest[i].indexed ? static_cast<std::int64_t>(i) : -1;
}

World::World(Scene scene, IndexSpec spec)
    : World(std::make_shared<const Scene>(std::move(scene)), spec) {}

World::World(std::shared_ptr<const Scene> scene, IndexSpec spec) : mSpec(spec) {
    if (!scene) {
        throw std::invalid_argument("World: no scene");
    }
    for (const SceneObject& o : scene->objects()) {
        if (o.body.dynamic) {
            mBodyIds.push_back(o.id);
        }
    }
    std::sort(mBodyIds.begin(), mBodyIds.end());
    std::shared_ptr<const SpatialIndex> index = buildIndex(*scene, mSpec);
    ++mBuildsPublished;
    publish(std::move(scene), std::move(index));
}

World::~World() {
    if (mBuild && mBuild->index.valid()) {
        mBuild->index.wait();
    }
}

SnapshotReader* World::registerReader() {
    const std::lock_guard lock(mReadersMutex);
    for (SnapshotReader& r : mReaders) {
        if (!r.inUse.load()) {
            r.held.store(nullptr);
            r.inUse.store(true);
            return &r;
        }
    }
    SnapshotReader& r = mReaders.emplace_back();
    r.inUse.store(true);
    return &r;
}

void World::unregisterReader(SnapshotReader* reader) {
    if (reader) {
        const std::lock_guard lock(mReadersMutex);
        reader->held.store(nullptr);
        reader->inUse.store(false);
    }
}

std::size_t World::readerCount() const {
    const std::lock_guard lock(mReadersMutex);
    return mReaders.size();
}

void World::publish(std::shared_ptr<const Scene> scene, std::shared_ptr<const SpatialIndex> index) {
    auto next = std::make_unique<WorldSnapshot>();
    next->version = ++mVersion;
    next->scene = std::move(scene);
    next->index = std::move(index);
    next->moving = movingSlotsFor(*next->scene);
    // The bodies keep their entries while they rest as static objects of the scene.
    for (std::uint32_t slot = 0; slot < next->scene->size(); ++slot) {
        const ObjectId id = next->scene->object(slot).id;
        if (std::binary_search(mBodyIds.begin(), mBodyIds.end(), id)) {
            next->dynamic.push_back(slot);
            const BodyRest* r = findRest(mRestPublished, id);
            next->rest.push_back(r != nullptr ? *r : BodyRest{id});
            next->rest.back().indexed = r != nullptr;
            next->restingCount += r != nullptr ? 1 : 0;
        }
    }
    mCurrent.store(next.get(), std::memory_order_seq_cst);
    if (mOwned) {
        mRetired.push_back(std::move(mOwned));
    }
    mOwned = std::move(next);
    reclaim();
}

std::vector<std::uint32_t> World::movingSlotsFor(const Scene& scene) const {
    std::vector<std::uint32_t> slots;
    for (const Mover& m : mMovers) {
        if (const auto slot = scene.slotOf(m.id)) {
            slots.push_back(*slot);
        }
    }
    std::sort(slots.begin(), slots.end());
    return slots;
}

void World::moveObject(ObjectId id, const Vec3& center, const Quat& rotation) {
    const WorldSnapshot& cur = current();
    const auto slot = cur.scene->slotOf(id);
    if (!slot) {
        throw InputError("move: no object with id " + std::to_string(id));
    }
    auto scene = std::make_shared<Scene>(*cur.scene);
    scene->setPose(*slot, center, rotation);
    const std::uint64_t now = nowNs();
    const auto it =
        std::find_if(mMovers.begin(), mMovers.end(), [&](auto& m) { return m.id == id; });
    if (it == mMovers.end()) {
        mMovers.push_back({id, now});
    } else {
        it->lastMoveNs = now;
    }
    publish(std::move(scene), cur.index);
}

void World::addObject(const SceneObject& object) {
    const WorldSnapshot& cur = current();
    if (cur.scene->slotOf(object.id)) {
        throw InputError("add: an object with id " + std::to_string(object.id) + " exists already");
    }
    std::vector<SceneObject> objects(cur.scene->objects().begin(), cur.scene->objects().end());
    objects.push_back(object);
    auto scene = std::make_shared<const Scene>(cur.scene->bounds(), std::move(objects));
    mMovers.push_back({object.id, nowNs()});
    if (object.body.dynamic) {
        mBodyIds.insert(std::upper_bound(mBodyIds.begin(), mBodyIds.end(), object.id), object.id);
    }
    // The old index knows nothing of the new slot; slots of the others are unchanged.
    publish(std::move(scene), cur.index);
}

void World::removeObject(ObjectId id) {
    if (!current().scene->slotOf(id) ||
        std::find(mPendingRemovals.begin(), mPendingRemovals.end(), id) != mPendingRemovals.end()) {
        throw InputError("remove: no object with id " + std::to_string(id));
    }
    // Slots shift, so the current index cannot serve the smaller scene: the removal is
    // published with the index built without the object.
    mPendingRemovals.push_back(id);
}

bool World::isMoving(ObjectId id) const {
    return std::any_of(mMovers.begin(), mMovers.end(), [&](auto& m) { return m.id == id; });
}

std::shared_ptr<const Scene> World::without(const Scene& scene, const std::vector<ObjectId>& ids) {
    std::vector<SceneObject> objects;
    objects.reserve(scene.size());
    for (const SceneObject& o : scene.objects()) {
        if (std::find(ids.begin(), ids.end(), o.id) == ids.end()) {
            objects.push_back(o);
        }
    }
    return std::make_shared<const Scene>(scene.bounds(), std::move(objects));
}

void World::startBuild() {
    auto build = std::make_unique<PendingBuild>();
    build->removed = std::exchange(mPendingRemovals, {});
    build->startedNs = nowNs();
    // The bodies at rest for restDelay (or already at rest in the index) go in at rest.
    for (const BodyRest& r : mRestWanted) {
        const BodyRest* published = findRest(mRestPublished, r.id);
        if ((published != nullptr && samePose(*published, r)) ||
            (build->startedNs >= r.sinceNs &&
             build->startedNs - r.sinceNs >=
                 static_cast<std::uint64_t>(std::max<std::int64_t>(0, mRestDelay.count())))) {
            build->resting.push_back(r);
        }
    }
    std::shared_ptr<const Scene> scene = withResting(
        build->removed.empty() ? current().scene : without(*current().scene, build->removed),
        build->resting);
    if (mClock) { // deterministic mode: built here, published by the caller at once
        std::promise<std::shared_ptr<const SpatialIndex>> built;
        built.set_value(buildIndex(*scene, mSpec));
        build->index = built.get_future();
    } else {
        build->index = std::async(std::launch::async,
                                  [scene, spec = mSpec]() -> std::shared_ptr<const SpatialIndex> {
                                      return buildIndex(*scene, spec);
                                  });
    }
    mBuild = std::move(build);
}

void World::finishBuild() {
    std::shared_ptr<const SpatialIndex> index = mBuild->index.get();
    const std::uint64_t started = mBuild->startedNs;
    const std::vector<ObjectId> removed = std::move(mBuild->removed);
    // A body that woke (or moved) while the build ran is dynamic again: its items in the new
    // index are stale, and skipped as every dynamic object's are.
    mRestPublished = stillWanted(mBuild->resting);
    mBuild.reset();
    // Objects that moved after the build started stay on the brute-force path.
    std::erase_if(mMovers, [&](const Mover& m) {
        return m.lastMoveNs < started ||
               std::find(removed.begin(), removed.end(), m.id) != removed.end();
    });
    ++mBuildsPublished;
    // The scene built over was the then-current one less `removed`; since then objects only
    // moved (same slots) or were appended, so the current scene less `removed` has the same
    // slots for everything the new index holds, and the newest poses.
    const WorldSnapshot& cur = current();
    publish(withResting(removed.empty() ? cur.scene : without(*cur.scene, removed), mRestPublished),
            std::move(index));
}

std::shared_ptr<const Scene> World::withResting(std::shared_ptr<const Scene> scene,
                                                const std::vector<BodyRest>& resting) const {
    // Shared as it is when every body already has its flag and pose (a scene with no bodies).
    const bool same = std::all_of(mBodyIds.begin(), mBodyIds.end(), [&](ObjectId id) {
        const auto slot = scene->slotOf(id);
        if (!slot) {
            return true;
        }
        const SceneObject& o = scene->object(*slot);
        const BodyRest* r = findRest(resting, id);
        return r == nullptr ? o.body.dynamic
                            : !o.body.dynamic && o.center == r->center && o.rotation == r->rotation;
    });
    if (same) {
        return scene;
    }
    std::vector<SceneObject> objects(scene->objects().begin(), scene->objects().end());
    for (SceneObject& o : objects) {
        if (!std::binary_search(mBodyIds.begin(), mBodyIds.end(), o.id)) {
            continue;
        }
        const BodyRest* r = findRest(resting, o.id);
        o.body.dynamic = r == nullptr; // at rest: a static object of this scene
        if (r != nullptr) {
            o.center = r->center;
            o.rotation = r->rotation;
        }
    }
    auto out = std::make_shared<Scene>(scene->bounds(), std::move(objects));
    out->setPhysics(scene->physics());
    return out;
}

std::vector<BodyRest> World::stillWanted(const std::vector<BodyRest>& resting) const {
    std::vector<BodyRest> keep;
    for (const BodyRest& r : resting) {
        const BodyRest* wanted = findRest(mRestWanted, r.id);
        if (wanted != nullptr && samePose(*wanted, r)) {
            keep.push_back(r);
        }
    }
    return keep;
}

void World::setRestingBodies(std::vector<BodyRest> resting) {
    std::erase_if(resting, [&](const BodyRest& r) {
        return !std::binary_search(mBodyIds.begin(), mBodyIds.end(), r.id);
    });
    std::sort(resting.begin(), resting.end(),
              [](const BodyRest& a, const BodyRest& b) { return a.id < b.id; });
    resting.erase(std::unique(resting.begin(), resting.end(),
                              [](const BodyRest& a, const BodyRest& b) { return a.id == b.id; }),
                  resting.end());
    const std::uint64_t now = nowNs();
    for (BodyRest& r : resting) {
        const BodyRest* before = findRest(mRestWanted, r.id);
        r.indexed = false;
        r.sinceNs = before != nullptr && samePose(*before, r) ? before->sinceNs : now;
    }
    mRestWanted = std::move(resting);
    // Woken (or moved) bodies leave the static world at once, over the same index: no build.
    std::vector<BodyRest> keep = stillWanted(mRestPublished);
    if (keep.size() != mRestPublished.size()) {
        mRestPublished = std::move(keep);
        const WorldSnapshot& cur = current();
        publish(withResting(cur.scene, mRestPublished), cur.index);
    }
}

bool World::restDue(std::uint64_t now) const {
    const auto delay = static_cast<std::uint64_t>(std::max<std::int64_t>(0, mRestDelay.count()));
    return std::any_of(mRestWanted.begin(), mRestWanted.end(), [&](const BodyRest& r) {
        const BodyRest* published = findRest(mRestPublished, r.id);
        return (published == nullptr || !samePose(*published, r)) && now >= r.sinceNs &&
               now - r.sinceNs >= delay;
    });
}

void World::maintain() {
    if (mBuild) {
        if (mBuild->index.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
            finishBuild();
        }
        reclaim();
        return;
    }
    const std::uint64_t now = nowNs();
    const bool anyRested =
        std::any_of(mMovers.begin(), mMovers.end(), [&](const Mover& m) { return rested(m, now); });
    if (anyRested || !mPendingRemovals.empty() || restDue(now)) {
        startBuild();
        if (mClock) {
            finishBuild(); // built inline: publish it now
        }
    }
    reclaim();
}

void World::settle() {
    // Finish what is in flight, then anything it left to do (at most one more build).
    for (int round = 0; round < 3; ++round) {
        if (mBuild) {
            mBuild->index.wait();
            finishBuild();
        }
        const std::uint64_t now = nowNs();
        if (mPendingRemovals.empty() && !restDue(now) &&
            std::none_of(mMovers.begin(), mMovers.end(),
                         [&](const Mover& m) { return rested(m, now); })) {
            break;
        }
        startBuild();
    }
    reclaim();
}

std::uint64_t World::nowNs() const noexcept {
    return mClock ? mClock->nowNs() : rt::nowNs();
}

bool World::rested(const Mover& m, std::uint64_t now) const noexcept {
    return now >= m.lastMoveNs &&
           now - m.lastMoveNs >= static_cast<std::uint64_t>(std::max<std::int64_t>(
                                     0, static_cast<std::int64_t>(mRestDelay.count())));
}

void World::reclaim() {
    const std::lock_guard lock(mReadersMutex);
    std::erase_if(mRetired, [&](const std::unique_ptr<WorldSnapshot>& s) {
        for (const SnapshotReader& r : mReaders) {
            if (r.held.load(std::memory_order_seq_cst) == s.get()) {
                return false;
            }
        }
        return true;
    });
}

} // namespace hapto
