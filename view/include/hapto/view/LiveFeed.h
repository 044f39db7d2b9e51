#pragma once
/// The view's own thread: 30 times a second it reads what the servo threads already publish
/// without locks (metrics, contact reports) and the poses the control thread hands it, and
/// publishes one frame to the ViewServer.

#include "hapto/runtime/Runtime.h"
#include "hapto/view/LoadWindow.h"
#include "hapto/view/ViewDocuments.h"
#include "hapto/view/ViewServer.h"

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace hapto {

/// Feeds a live session to a ViewServer. Design note: the servo threads are never asked for
/// anything: the feed reads their single-writer atomics (DeviceMetrics) and their contact
/// mailboxes (seqlocks, which a reader retries and a writer never waits for), so a slow feed
/// or a stalled viewer costs the servo path nothing. Object poses come from the control
/// thread (World::current() is its to read): updatePoses() copies the moving objects' poses
/// when the world's version changes, under a mutex the servo threads never see. Frames carry,
/// per device: point, proxy, force (world frame, N), the objects in contact, ticks, misses,
/// the load p50 / p99.9 and the candidates per tick (objects handed to the renderer: the
/// cursor leaves' and the moving ones) over the last second, and the verdict over the run so
/// far (the
/// report's rule: p99.9 load < 1, misses <= 0.1 % of ticks, no fault).
class LiveFeed {
public:
    /// Reads the devices' names and rates from the runtime's report (so: [control]).
    LiveFeed(const Runtime& runtime, ViewServer& server, double frameHz = 30.0);
    ~LiveFeed();
    LiveFeed(const LiveFeed&) = delete;
    LiveFeed& operator=(const LiveFeed&) = delete;

    /// The devices as the page names them. [any thread]
    const std::vector<ViewDevice>& devices() const { return mDevices; }
    /// Starts the feed thread. [control]
    void start();
    /// Stops and joins it. [control]
    void stop();
    /// Takes the poses of the snapshot's moving objects when its version is new (cheap when
    /// not); an object that moved keeps its last pose in the frames after it rests. [control]
    void updatePoses(const WorldSnapshot& snapshot);
    /// Takes each device's cursor leaf (its box and the objects it lists, at most
    /// kMaxLeafObjects ids) when the servo's last tick used this snapshot's index; a leaf of
    /// another snapshot is left until the next call. Call it with every updatePoses. [control]
    void updateLeaves(const WorldSnapshot& snapshot);
    /// The most object ids a frame lists per leaf.
    static constexpr std::size_t kMaxLeafObjects = 64;
    /// Builds one frame at `sessionNs` since the feed started (the feed thread's work; public
    /// for tests). [feed thread, or a test's thread while the feed is not started]
    std::string frame(std::uint64_t sessionNs);

private:
    struct Pose {
        Vec3 center{0.0};
        Quat rotation{1, 0, 0, 0};
        bool moving = false;
    };
    void run();

    const Runtime& mRuntime;
    ViewServer& mServer;
    double mFrameHz;
    std::vector<ViewDevice> mDevices;
    std::vector<LoadWindow> mWindows; // per device, feed thread only
    struct Sums {
        std::uint64_t timeNs, ticks, candidates;
    };
    std::vector<std::deque<Sums>> mSums; // per device, about a second of frames; feed thread

    std::mutex mPoseMutex; // control thread writes, feed thread copies
    std::map<ObjectId, Pose> mPoses;
    struct Leaf {
        std::uint64_t leafAtVersion = ~std::uint64_t{0}; // as DeviceMetrics publishes it
        Aabb box;
        std::vector<ObjectId> objects; // distinct, ascending, at most kMaxLeafObjects
        std::size_t items = 0;         // what the leaf lists (triangles counted one by one)
        bool valid = false;
    };
    std::vector<Leaf> mLeaves;      // per device, under mPoseMutex
    std::uint64_t mPoseVersion = 0; // control thread only

    std::thread mThread;
    std::mutex mStopMutex;
    std::condition_variable mStopWake;
    bool mStop = false;
};

} // namespace hapto
