// The live view's feed thread (LiveFeed.h). Each frame carries the devices' figures and the
// poses of what moves: objects the world moves, and the dynamic bodies at their live pose.

#include "hapto/view/LiveFeed.h"

#include "ViewJson.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>

namespace hapto {
namespace {

using detail::vec;

std::uint64_t steadyNs() {
    return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                          std::chrono::steady_clock::now().time_since_epoch())
                                          .count());
}

/// The dynamic bodies at their latest published pose (Runtime::bodyPoses, read without
/// locks), as the frame's poses: the view places each object by its id. Moving unless asleep.
void appendBodyPoses(const Runtime& runtime, nlohmann::json& poses) {
    const BodyPoseTable* table = runtime.bodyPoses();
    if (!table) {
        return;
    }
    const std::span<const ObjectId> ids = runtime.bodyIds();
    for (std::size_t i = 0; i < ids.size(); ++i) {
        const BodyPose p = table->read(i);
        poses.push_back({{"id", ids[i]},
                         {"center", vec(p.center)},
                         {"rotation", {p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z}},
                         {"moving", !p.sleeping}});
    }
}

} // namespace

LiveFeed::LiveFeed(const Runtime& runtime, ViewServer& server, double frameHz)
    : mRuntime(runtime), mServer(server), mFrameHz(frameHz) {
    for (const DeviceReport& d : runtime.report().devices) {
        mDevices.push_back({d.name, d.rateHz});
        // One second of copies at the frame rate, plus slack for a late frame.
        mWindows.emplace_back(1e9 / d.rateHz, 1'000'000'000, static_cast<std::size_t>(frameHz) + 2);
        mSums.push_back({{0, 0, 0}}); // the session's start: nothing yet
    }
    mLeaves.resize(mDevices.size());
}

LiveFeed::~LiveFeed() {
    stop();
}

void LiveFeed::start() {
    mStop = false;
    mThread = std::thread([this] { run(); });
}

void LiveFeed::stop() {
    {
        std::lock_guard lock(mStopMutex);
        mStop = true;
    }
    mStopWake.notify_all();
    if (mThread.joinable()) {
        mThread.join();
    }
}

void LiveFeed::updatePoses(const WorldSnapshot& snapshot) {
    if (snapshot.version == mPoseVersion) {
        return;
    }
    mPoseVersion = snapshot.version;
    std::lock_guard lock(mPoseMutex);
    for (auto& [id, pose] : mPoses) {
        const auto slot = snapshot.scene->slotOf(id);
        pose.moving = false;
        if (slot) { // the last pose of an object that rests now
            pose.center = snapshot.scene->object(*slot).center;
            pose.rotation = snapshot.scene->object(*slot).rotation;
        }
    }
    for (std::uint32_t slot : snapshot.moving) {
        const SceneObject& o = snapshot.scene->object(slot);
        mPoses[o.id] = Pose{o.center, o.rotation, true};
    }
}

void LiveFeed::updateLeaves(const WorldSnapshot& snapshot) {
    for (std::size_t i = 0; i < mDevices.size(); ++i) {
        const std::uint64_t packed =
            mRuntime.metrics(i).leafAtVersion.load(std::memory_order_relaxed);
        {
            std::lock_guard lock(mPoseMutex);
            if (packed == mLeaves[i].leafAtVersion) {
                continue; // the same leaf of the same snapshot: nothing new
            }
        }
        if (packed >> 32 != (snapshot.version & 0xFFFFFFFFu)) {
            continue; // the servo's last tick used another snapshot: wait for a matching one
        }
        Leaf leaf;
        leaf.leafAtVersion = packed;
        const auto id = static_cast<std::uint32_t>(packed & 0xFFFFFFFFu);
        if (id != kNoLeaf) {
            const SpatialIndex& index = *snapshot.index;
            const Scene& scene = *snapshot.scene;
            leaf.box = index.leafBounds(id);
            const std::span<const std::uint32_t> items = index.leafObjects(id);
            leaf.items = items.size();
            for (const std::uint32_t item : items) {
                if (leaf.objects.size() >= kMaxLeafObjects) {
                    break;
                }
                const ObjectId oid = scene.object(scene.objectSlotOf(item)).id;
                if (std::find(leaf.objects.begin(), leaf.objects.end(), oid) ==
                    leaf.objects.end()) {
                    leaf.objects.push_back(oid);
                }
            }
            std::sort(leaf.objects.begin(), leaf.objects.end());
            leaf.valid = true;
        }
        std::lock_guard lock(mPoseMutex);
        mLeaves[i] = std::move(leaf);
    }
}

std::string LiveFeed::frame(std::uint64_t sessionNs) {
    nlohmann::json devices = nlohmann::json::array();
    for (std::size_t i = 0; i < mDevices.size(); ++i) {
        const DeviceMetrics& m = mRuntime.metrics(i);
        const WindowLoad load = mWindows[i].sample(m.tickNs, sessionNs);
        const std::uint64_t ticks = m.ticks.load(std::memory_order_relaxed);
        const std::uint64_t misses = m.missedDeadlines.load(std::memory_order_relaxed);
        // Candidates per tick over the same second: two sums about a second apart.
        std::deque<Sums>& sums = mSums[i];
        sums.push_back({sessionNs, ticks, m.candidatesSum.load(std::memory_order_relaxed)});
        while (sums.size() > 2 && sessionNs - sums[1].timeNs >= 1'000'000'000) {
            sums.pop_front();
        }
        const std::uint64_t windowTicks = ticks - sums.front().ticks;
        const double candidates =
            windowTicks > 0
                ? static_cast<double>(sums.back().candidates - sums.front().candidates) /
                      static_cast<double>(windowTicks)
                : 0.0;
        const FaultKind fault = m.fault.load(std::memory_order_relaxed);
        const double periodNs = 1e9 / mDevices[i].rateHz;
        const double p999 = m.tickNs.summary().p999 / periodNs;
        const bool stable = fault == FaultKind::None && p999 < 1.0 && misses * 1000 <= ticks;
        nlohmann::json d{{"name", mDevices[i].name},
                         {"ticks", ticks},
                         {"misses", misses},
                         {"loadP50", load.p50},
                         {"loadP999", load.p999},
                         {"windowS", load.spanS},
                         {"candidates", candidates},
                         {"verdict", fault != FaultKind::None
                                         ? std::string("FAULT ") + faultName(fault)
                                     : stable ? "stable"
                                              : "UNSTABLE"}};
        // Why it is unstable when its ticks stayed short: the run report's note, over the run
        // so far (the fields lateWakeupNote reads).
        DeviceReport sofar;
        sofar.ticks = ticks;
        sofar.missedDeadlines = misses;
        sofar.loadFraction.p999 = p999;
        sofar.latenessNs = m.latenessNs.summary();
        sofar.fault = fault != FaultKind::None ? faultName(fault) : "";
        sofar.stable = stable;
        if (std::string note = lateWakeupNote(sofar); !note.empty()) {
            d["note"] = std::move(note);
        }
        ContactReport c;
        if (mRuntime.lastTick(i, c)) {
            nlohmann::json contacts = nlohmann::json::array();
            for (std::uint32_t k = 0; k < c.contactCount && k < c.objects.size(); ++k) {
                contacts.push_back(c.objects[k]);
            }
            d["point"] = vec(c.devicePoint);
            d["proxy"] = vec(c.proxy);
            d["force"] = vec(c.force);
            d["forceN"] = glm::length(c.force);
            d["contacts"] = contacts;
        }
        {
            std::lock_guard lock(mPoseMutex);
            const Leaf& leaf = mLeaves[i];
            if (leaf.valid) {
                d["leaf"] = {{"min", vec(leaf.box.min)},
                             {"max", vec(leaf.box.max)},
                             {"objects", leaf.objects},
                             {"items", leaf.items}};
            }
        }
        devices.push_back(std::move(d));
    }
    nlohmann::json poses = nlohmann::json::array();
    {
        std::lock_guard lock(mPoseMutex);
        for (const auto& [id, p] : mPoses) {
            poses.push_back({{"id", id},
                             {"center", vec(p.center)},
                             {"rotation", {p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z}},
                             {"moving", p.moving}});
        }
    }
    appendBodyPoses(mRuntime, poses); // after the world's: a body's pose is its live one
    return nlohmann::json{
        {"t", static_cast<double>(sessionNs) * 1e-9}, {"devices", devices}, {"poses", poses}}
        .dump();
}

void LiveFeed::run() {
    const std::uint64_t startNs = steadyNs();
    const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / mFrameHz));
    auto next = std::chrono::steady_clock::now();
    std::unique_lock lock(mStopMutex);
    while (!mStop) {
        lock.unlock();
        mServer.publish(frame(steadyNs() - startNs));
        lock.lock();
        next += period;
        mStopWake.wait_until(lock, next, [this] { return mStop; });
    }
}

} // namespace hapto
