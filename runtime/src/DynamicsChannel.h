#pragma once
/// The dynamics thread's block inside the Runtime (private to runtime/src): the Dynamics it
/// steps, the BodyPoseTable it publishes into (the servo threads' ServoStepPorts::bodies), what
/// it measures about itself, and its thread.
///
/// Design note. Like a device's Channel, the block is sized before the thread starts: the
/// table, the per-body flags and measured figures, the last finite pose of each body. The step
/// (DynamicsLoop.cpp) reads and writes only these and the Dynamics' own preallocated state, so
/// it never allocates, locks or throws. Figures the control thread reads while the thread runs
/// (counters, histograms, each body's BodyStats) are relaxed atomics with one writer.
///
/// The watchdog (Supervision.cpp, superviseDynamics). `stateNs` is the time the published
/// state is due at (the last step's deadline). When it is older than `stallBoundNs` (the
/// servos' stallTimeoutNs plus one dynamics period) the supervision freezes the bodies: it
/// republishes each body's last pose with zero velocities, so a servo extrapolates nothing and
/// renders the body where it last was. The table has one writer at a time by a token,
/// `DynamicsMetrics::publisher`: the dynamics step takes it (0 -> 1) around each publication,
/// the supervision takes it for good (0 -> 2) to freeze, by compare-exchange, so neither waits
/// on the other (a supervision pass that finds the token held tries again at its next pass).
/// The freeze lasts to the end of the session: the hands' impulses during the stall were
/// reactions to a body that did not move, so the solver's state no longer matches what they
/// felt; the dynamics thread then takes and drops the impulses and steps no more.

#include "hapto/dynamics/Dynamics.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/runtime/DeviceMetrics.h"
#include "hapto/runtime/LoadHistogram.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/Runtime.h"

#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

namespace hapto {

/// What the dynamics thread measures: one writer, any reader.
struct DynamicsMetrics {
    LoadHistogram stepNs;     ///< Wake-up to every pose published (ns): the load numerator.
    LoadHistogram latenessNs; ///< Wake-up minus deadline (ns).
    std::atomic<std::uint64_t> steps{0};           ///< Steps run.
    std::atomic<std::uint64_t> missedDeadlines{0}; ///< Steps that ended after the next deadline.
    std::atomic<std::uint64_t> lateWakeups{0};     ///< Wake-ups later than the late threshold.
    std::atomic<std::uint64_t> stoppedBodies{0};   ///< Bodies stopped for a non-finite state.
    std::atomic<bool> running{false};              ///< The loop (or the step mode's) is live.
    std::atomic<std::uint64_t> stateNs{0}; ///< The published state's time (ns, runtime clock).
    /// Who may publish into the table: kFree, kStepping (the dynamics step, while it
    /// publishes) or kFrozen (the supervision froze the bodies: no one, ever again).
    std::atomic<int> publisher{0};
    std::atomic<FaultKind> fault{FaultKind::None}; ///< Watchdog once frozen.
    std::atomic<std::uint64_t> faultNs{0};         ///< When the watchdog froze the bodies (ns).
    std::atomic<std::uint64_t> frozenAtStep{0};    ///< The step whose poses were frozen.
    static constexpr int kFree = 0;                ///< No one is publishing.
    static constexpr int kStepping = 1;            ///< The dynamics step is publishing.
    static constexpr int kFrozen = 2;              ///< Frozen by the watchdog for good.
    std::atomic<bool> realtime{false};             ///< The thread was granted SCHED_FIFO.
};

/// One body's figures as the control thread reads them.
struct alignas(64) DynamicsBodyRecord {
    std::atomic<double> deepestPenetrationM{0.0}; ///< BodyStats, published after each step.
    std::atomic<double> largestEnergyGainJ{0.0};  ///< BodyStats, published after each step.
    std::atomic<bool> stopped{false};             ///< Stopped for a non-finite state.
    BodyPose lastGood{};                          ///< [dynamics] The last finite pose.
};

struct Runtime::DynamicsChannel {
    std::unique_ptr<Dynamics> dynamics;
    BodyPoseTable poses;
    std::unique_ptr<DynamicsBodyRecord[]> records; ///< One per body.
    std::vector<ObjectId> ids;                     ///< Each body's scene object id.
    DynamicsMetrics metrics;
    double rateHz = 0;
    std::uint64_t periodNs = 0;
    std::uint64_t lateNs = 0;     ///< A wake-up later than this is late.
    std::uint64_t deadlineNs = 0; ///< [dynamics] The next step's deadline.
    /// The watchdog's bound: a published state older than this freezes the bodies (ns).
    std::uint64_t stallBoundNs = 0;
    BodyTraceRecorder* recorder = nullptr;
    std::atomic<bool> stop{false};
    std::thread thread;
    rt::RealtimeGrant grant;

    /// Builds the Dynamics over `snapshot`'s scene and index. [control]
    DynamicsChannel(const WorldSnapshot& snapshot, const RuntimeOptions& options);
};

} // namespace hapto
