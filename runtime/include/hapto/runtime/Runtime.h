#pragma once
/// The runtime: one servo thread per device over one shared World, and the load they measure.

#include "hapto/core/Mailbox.h"
#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/index/Cursor.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/runtime/DeviceMetrics.h"
#include "hapto/runtime/Effects.h"
#include "hapto/runtime/ForceSafety.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/ServoLoop.h"
#include "hapto/runtime/ServoStep.h"
#include "hapto/runtime/TickHook.h"
#include "hapto/runtime/World.h"

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

namespace hapto {

class TraceRecorder;
class BodyTraceRecorder;

// ContactReport (what a servo tells the control thread every tick) is in ServoStep.h.

/// How servo threads run.
struct RuntimeOptions {
    bool realtime = true;     ///< Ask for SCHED_FIFO and pin device i to core i % cores.
    int fifoPriority = 80;    ///< SCHED_FIFO priority when realtime.
    std::uint64_t spinNs = 0; ///< Spin this long before each deadline instead of sleeping (ns).
    /// Wake this long before each deadline, touch the tick's working set (warmUpTick in
    /// ServoLoop.h) and spin to the deadline (ns); 0 = off. At most half the device's period
    /// is used (a longer one is cut to that). The step
    /// mode runs the same warm-up before each tick (it has no sleep to wake from).
    /// Unset (the default): kDefaultWarmUpNs when every servo thread can have a core of its own
    /// (no more per-device servo threads than cores), else off: threads sharing a core keep
    /// its caches warm for each other, so there it costs CPU for little
    /// (docs/results/many-devices.md).
    /// Servo groups (devicesPerThread > 1) never warm up.
    std::optional<std::uint64_t> warmUpNs;
    int missLimit = 3;               ///< K: after K missed deadlines in a row, command zero force
                                     ///< until a tick meets its deadline again.
    double lateWakeupFraction = 0.1; ///< A wake-up later than this fraction of the period is late.
    std::uint64_t stallTimeoutNs =
        50'000'000; ///< Watchdog: no tick for this long faults the device.
    std::uint64_t reopenAfterNs =
        1'000'000'000;         ///< After a fault, close the device and try to open it again every
                               ///< this long (ns), then drive it again from zero force; 0 = never.
    RendererConfig renderer{}; ///< Proxy settings for every device (a device's own
                               ///< RendererSettings, RuntimeDevice::rendering, are laid over).
    /// Simulated devices only (kind sim or scripted): K > 1 runs devices [0, K), [K, 2K), ...
    /// on one servo thread per group (GroupedServo.cpp). Each device keeps its own deadline,
    /// cursor, renderer, load record, safety and faults; the thread sleeps once to the
    /// earliest deadline and ticks every device then due, earliest deadline first. 1 (the
    /// default, and the design): one servo thread per device. The constructor throws
    /// std::invalid_argument for K = 0 or K > 1 with a device of another kind.
    std::size_t devicesPerThread = 1;
    /// >= 0: while the servo threads run (start() to stop()), hold a CPU latency request of
    /// this many microseconds (rt::WakeLatencyHold): 0 keeps idle CPUs polling, so a servo
    /// thread's wake-up from its sleep does not wait for a halted CPU. -1 (the default): no
    /// request; idle CPUs spinning costs power and, on a VM, the host's CPU. Not in step mode.
    /// A request that cannot be held (not root, no such file) is reported in
    /// RunReport::realtimeNote and the run goes on without it.
    std::int32_t wakeLatencyUs = -1;
};

/// One device as the runtime drives it.
struct RuntimeDevice {
    std::unique_ptr<Device> device;    ///< The backend, not yet opened.
    DeviceConfig config;               ///< Name, transform, rate, max force.
    TraceRecorder* recorder = nullptr; ///< Optional per-tick recording (owned by the caller).
    /// Its force effects and renderer settings (a device file's, DeviceFile::renderingOf());
    /// none by default.
    DeviceRendering rendering{};
};

/// Summary of one device's run, loads as fractions of its period.
struct DeviceReport {
    std::string name;                  ///< The device's configured name.
    std::string kind;                  ///< sim, replay, falcon or phantom.
    double rateHz = 0;                 ///< Servo rate (Hz).
    std::uint64_t ticks = 0;           ///< Ticks run.
    HistogramSummary loadFraction;     ///< (wake-up to force written) / period.
    HistogramSummary latenessNs;       ///< Wake-up lateness (ns).
    HistogramSummary ioNs;             ///< Device I/O per tick (ns).
    std::uint64_t lateWakeups = 0;     ///< Wake-ups later than 10 % of the period.
    std::uint64_t missedDeadlines = 0; ///< Forces written after the next deadline.
    std::uint64_t zeroedForMisses = 0; ///< Ticks at zero force after K misses in a row.
    double locateStepsMean = 0;        ///< Cursor steps per tick, both cursors, mean.
    double candidatesMean = 0;         ///< Candidates handed to the renderer per tick, mean.
    std::uint64_t outsideTicks = 0;    ///< Ticks with the device point outside the bounds.
    std::uint64_t contactTicks = 0;    ///< Ticks in contact.
    std::uint64_t snapshotsSeen = 0;   ///< Distinct world versions picked up.
    SafetyCounters safety{};           ///< Clamps, rate limits, non-finite forces.
    std::uint64_t hookNonFinite = 0;   ///< Ticks whose hook returned a non-finite force (zeroed).
    std::string fault;                 ///< Empty, or what faulted the device and keeps it down now.
    std::uint64_t faults = 0;          ///< Faults while running (each zeroed the device at once).
    std::uint64_t reopens = 0;         ///< Times the device was opened again after a fault.
    /// Time from each fault to its reopen, summed, the current outage included (s).
    double downS = 0;
    std::vector<std::string> events; ///< "12.345 s: read-failed: disconnected", oldest first
                                     ///< (the first kMaxEvents).
    bool realtime = false;           ///< SCHED_FIFO was granted.
    bool stable = false;             ///< p99.9 load < 1 and misses <= 0.1 % of ticks, no fault.
};

/// What was measured of one dynamic body over the run (Dynamics' BodyStats).
struct BodyReport {
    ObjectId id = 0;                  ///< The scene object's id.
    double deepestPenetrationM = 0.0; ///< Largest overlap with anything, after a step (m).
    double largestEnergyGainJ = 0.0;  ///< Largest energy rise with no external work (J).
    bool stopped = false; ///< Its state turned non-finite: stopped at its last finite pose.
};

/// Summary of the dynamics thread's run, loads as fractions of its period.
struct DynamicsReport {
    double rateHz = 0;                 ///< Steps per second (ScenePhysics::rateHz).
    std::uint64_t steps = 0;           ///< Steps run.
    HistogramSummary stepNs;           ///< Wake-up to every pose published (ns).
    HistogramSummary loadFraction;     ///< stepNs / period.
    HistogramSummary latenessNs;       ///< Wake-up lateness (ns).
    std::uint64_t lateWakeups = 0;     ///< Wake-ups later than 10 % of the period.
    std::uint64_t missedDeadlines = 0; ///< Steps that ended after the next deadline.
    std::uint64_t stoppedBodies = 0;   ///< Bodies stopped for a non-finite state.
    bool realtime = false;             ///< SCHED_FIFO was granted.
    /// Empty, or why the bodies were frozen: "watchdog: no step for 60 ms (bound 51 ms);
    /// bodies frozen at step 40". A published state older than RuntimeOptions::stallTimeoutNs
    /// plus one period freezes every body where it was, at zero velocity, to the session's end.
    std::string fault;
    double faultS = 0; ///< When the watchdog froze the bodies (s since the start); 0 if not.
    /// p99.9 load < 1, misses <= 0.1 % of steps, no body stopped, no fault (the devices' rule,
    /// loadStable).
    bool stable = false;
    std::vector<BodyReport> bodies; ///< One per dynamic body, in the scene's slot order.
};

/// The verdict's rule for a thread with a period: some steps ran, the p99.9 of (step time /
/// period) is below 1 and at most 0.1 % of the steps missed their deadline. [any thread]
bool loadStable(std::uint64_t steps, const HistogramSummary& loadFraction,
                std::uint64_t missedDeadlines);

/// The whole run.
struct RunReport {
    std::vector<DeviceReport> devices; ///< One per device, in configuration order.
    /// The dynamics thread, when the scene has dynamic bodies.
    std::optional<DynamicsReport> dynamics;
    double loadSum = 0;       ///< Sum of the devices' mean loads (CPU cores' worth of servo work).
    double loadPerCore = 0;   ///< loadSum / cores.
    int cores = 1;            ///< Hardware threads.
    bool stable = false;      ///< Every device stable, and the dynamics when it runs.
    double durationS = 0;     ///< Wall time from start to stop (s).
    std::string realtimeNote; ///< Why SCHED_FIFO or pinning was not granted, if not.
    /// The CPU latency request held during the run (us; RuntimeOptions::wakeLatencyUs), or -1.
    std::int32_t wakeLatencyUs = -1;
    /// The warm-up before each deadline the per-device servo threads ran (ns; 0: none), and
    /// whether the runtime chose it (RuntimeOptions::warmUpNs unset).
    std::uint64_t warmUpNs = 0;
    bool warmUpAutomatic = false; ///< The runtime chose warmUpNs (see above).
};

/// Runs D servo threads (or D / K, RuntimeOptions::devicesPerThread) and a supervisor. Construct,
/// start(), call maintain() every few milliseconds for world upkeep, stop().
///
/// Supervision (the watchdog, closing a faulted device, reopening it, starting its new servo
/// thread) runs on the runtime's own supervisor thread, and every close and open on a worker
/// thread of that device: nothing a servo thread depends on waits for the control thread, a
/// terminal, a disk or another device's open (Falcon homing can take 30 s).
///
/// Step mode: startStepped() instead of start() opens the devices and starts no thread; the
/// caller then drives the same servo tick and the same supervision pass from its own thread
/// with a clock it gives (runUntil, stepAll, or step and supervise), so a test or a tool gets
/// the same results every run: same fault rules, same reports, same forces.
/// Threading: every public member is [control] except where marked.
class Runtime {
public:
    /// Events kept per device in the report; later ones are only counted.
    static constexpr std::size_t kMaxEvents = 64;

    /// Takes the devices (not yet opened) over `world`, which must outlive the runtime; nothing
    /// runs until start() or startStepped(). [control]
    Runtime(World& world, std::vector<RuntimeDevice> devices, RuntimeOptions options = {});
    ~Runtime();
    Runtime(const Runtime&) = delete;
    Runtime& operator=(const Runtime&) = delete;

    /// Opens every device, then (all opened) starts one servo thread per opened device and
    /// the supervisor thread. A device that fails to open is reported as faulted and the
    /// others run. Returns the number of servo threads started. [control]
    std::size_t start();
    /// Step mode: opens every device like start(), in order, and starts no thread; `clock`
    /// (which must outlive the runtime) is the time from now on, its value now the session's
    /// start. Drive it with runUntil(), stepAll(), or step() and supervise(). Returns the
    /// number of devices opened. [control]
    std::size_t startStepped(ManualClock& clock);
    /// Step mode: runs every device at each of its deadlines (an on-time wake-up) and a
    /// supervision pass after each, in time order, up to and including `untilNs`; a faulted
    /// device is reopened at its reopen times. The dynamics steps at its deadlines too, a step
    /// due at t before the servo ticks due at t. Ends with the clock at `untilNs`. [control]
    void runUntil(std::uint64_t untilNs);
    /// Step mode: at `nowNs`, first one dynamics step if its deadline has come, then one
    /// tick of every device whose deadline has come (a `nowNs`
    /// past a deadline is a late wake-up), in device order, then one supervision pass. Before
    /// each device's tick the clock is set to `nowNs`; the device may advance it inside its
    /// read() or write() (that tick then takes that long: its load, misses and next deadline
    /// follow); afterwards the clock is set back to `nowNs`, since the other devices' threads
    /// did not wait for it. A group's members (RuntimeOptions::devicesPerThread) tick as
    /// their one thread ticks them: those due, earliest deadline first, the clock carried from
    /// one member's tick to the next and set back to `nowNs` after the group. [control]
    void stepAll(std::uint64_t nowNs);
    /// Step mode: one tick of device i woken at `nowNs` (clock as in stepAll()), when its
    /// servo runs and its deadline has come; a device not stepped meanwhile is a thread that
    /// could not run. A servo stopped by the watchdog commands zero and leaves here. Returns
    /// true when a tick completed. [control]
    bool step(std::size_t i, std::uint64_t nowNs);
    /// Step mode: one supervision pass at `nowNs`: the watchdog over heartbeats, closing a
    /// faulted device, reopening it once reopenAfterNs has passed (open and close run inline,
    /// the clock set back to `nowNs` after each). [control]
    void supervise(std::uint64_t nowNs);
    /// When device i's next tick is due (ns, the runtime's clock). [control]
    std::uint64_t nextDeadlineNs(std::size_t i) const;
    /// True after startStepped(). [control]
    bool stepped() const { return mClock != nullptr; }
    /// World upkeep (re-indexing rested objects, freeing old snapshots): call every few
    /// milliseconds from the thread that updates the world. With dynamics, it also hands the
    /// world the bodies the table shows asleep (World::setRestingBodies): a body asleep for
    /// the world's rest delay re-enters the static index, a woken one leaves it; the servo and
    /// dynamics threads never wait for either. Supervision does not depend on
    /// it. [control]
    void maintain();
    /// Stops every thread: each commands zero force, then the devices are closed. Waits for a
    /// reopen in progress to return (the device is at zero force meanwhile). [control]
    void stop();
    /// The last resort when stop() cannot be waited for (a second Ctrl-C): tells every servo
    /// thread to stop, waits at most `waitNs` for them to command zero force and leave, and
    /// closes each device whose thread has left. Safe from a thread other than the control
    /// thread while the control thread is blocked; the process should exit right after. In
    /// step mode it commands zero and closes at once, and belongs to the stepping thread. [any
    /// thread]
    void emergencyStop(std::uint64_t waitNs = 200'000'000) noexcept;
    /// True while some device is driven or will be again (a faulted device waiting to be
    /// reopened counts when reopening is on), or the dynamics runs. [control]
    bool anyRunning() const;

    /// True when the world's scene has dynamic bodies: the runtime then builds a Dynamics
    /// from the world's current snapshot (its scene and index) at construction, runs it on a
    /// dynamics thread of its own from start() (stepped: between the servo ticks), and hands
    /// every servo its BodyPoseTable (ServoStepPorts::bodies). [any thread]
    bool hasDynamics() const;
    /// The dynamic bodies' latest poses (read without locks; BodyPoseTable::read) and where
    /// the hands' impulses go; null without dynamics. Body i is bodyIds()[i]. [any thread]
    const BodyPoseTable* bodyPoses() const;
    /// The same, to add impulses to a body (BodyPoseTable::addImpulse: an application's push;
    /// it reaches the body at the next dynamics step, once). [any thread]
    BodyPoseTable* bodyPoses();
    /// Each body's scene object id, in body order; empty without dynamics. [any thread]
    std::span<const ObjectId> bodyIds() const;
    /// The dynamics' step rate (Hz), 0 without dynamics. [any thread]
    double dynamicsRateHz() const;
    /// Records every body's state at every dynamics step into `recorder` (owned by the
    /// caller, drained by the control thread; Session does). Before start() or
    /// startStepped(); ignored without dynamics. [control]
    void setBodyRecorder(BodyTraceRecorder* recorder);
    /// When the next dynamics step is due (ns, the runtime's clock); UINT64_MAX when none
    /// runs. [control]
    std::uint64_t nextDynamicsDeadlineNs() const;

    /// Live metrics of device i. [any thread]
    const DeviceMetrics& metrics(std::size_t i) const;
    /// Number of devices. [any thread]
    std::size_t deviceCount() const;
    /// The device (to inspect after stop, or for tests). [control]
    Device& device(std::size_t i);
    /// Builds the report from the metrics (live or final). [control]
    RunReport report() const;

    /// One line per device for a terminal live view. [control]
    std::string liveLine(std::size_t i) const;

    /// What device i's servo last sent: its newest tick's force (N, world, external force
    /// included), device point, proxy and contacts; once its servo has stopped (stop(), a
    /// fault), zero force and no contacts: the force the device feels at the end of a session.
    /// False before its first tick. [any thread]
    bool lastTick(std::size_t i, ContactReport& report) const;
    /// Adds a world-frame force (N) to every force device i renders from its next tick on,
    /// before the safety filter (e.g. the weight of a carried object). [control]
    void setExternalForce(std::size_t i, const Vec3& forceN);

    /// Replaces device i's force effects (springs, dampers, constant forces; Effects.h) from
    /// its next tick on, running or not. Never waits for the servo thread: the whole set goes
    /// through a lock-free mailbox and the servo copies it in at its next tick. Throws
    /// std::invalid_argument naming the effect and its field when there are more than
    /// EffectSet::kCapacity or one fails checkForceEffect(), std::out_of_range for a bad i.
    /// [control]
    void setEffects(std::size_t i, std::span<const ForceEffect> effects);
    /// As above, from a list: `setEffects(0, {ForceEffect::damper(2.0)})`. [control]
    void setEffects(std::size_t i, std::initializer_list<ForceEffect> effects);
    /// Turns effect k of device i on or off from its next tick on, as setEffects(). Throws
    /// std::out_of_range when there is no such device or effect. [control]
    void setEffectEnabled(std::size_t i, std::size_t k, bool enabled);
    /// Device i's effects as last set (its RuntimeDevice::rendering's, then setEffects() and
    /// setEffectEnabled()). [control]
    const EffectSet& effects(std::size_t i) const;
    /// Registers device i's per-tick hook (see TickHook.h for what it may do), called on its
    /// servo thread every tick from the first on; `hook.context` must stay valid until stop().
    /// Only before start() or startStepped(): afterwards it throws std::logic_error (the hook
    /// is a plain field of the servo's state; starting the thread publishes it, so the servo
    /// reads it without any synchronisation). [control]
    void setTickHook(std::size_t i, const TickHook& hook);

private:
    struct Channel;
    struct Group;
    struct DynamicsChannel;
    // DynamicsLoop.cpp: the dynamics thread, threaded or stepped.
    void startDynamics(std::uint64_t nowNs);
    void dynamicsMain();
    void runDynamicsStep(DynamicsChannel& dc, std::uint64_t wakeNs) noexcept;
    void publishBodies(DynamicsChannel& dc, std::uint64_t timeNs) noexcept;
    bool publishUnlessFrozen(DynamicsChannel& dc, std::uint64_t timeNs) noexcept;
    bool stepDynamicsIfDue(std::uint64_t nowNs);
    void stopDynamics();
    std::optional<DynamicsReport> dynamicsReport() const;
    // Runtime.cpp: set-up and shutdown.
    std::size_t openAll();
    std::uint64_t now() const noexcept;
    void requireStepped(const char* what) const;
    // ServoLoop.cpp: the servo, threaded or stepped.
    void startServo(Channel& channel, std::uint64_t nowNs) noexcept;
    void leaveServo(Channel& channel) noexcept;
    std::uint64_t warm(Channel& channel) noexcept;
    void startThread(Channel& channel);
    void servoMain(Channel& channel);
    // Supervision.cpp: the watchdog, closing and reopening.
    void superviseMain();
    void superviseChannel(Channel& channel, std::uint64_t nowNs);
    void superviseDynamics(std::uint64_t nowNs) noexcept;
    void recoverMain(Channel& channel);
    void closeFaulted(Channel& channel);
    /// The channel's current fault as a report and its events say it: "watchdog: no tick for
    /// 50 ms", "read-failed: disconnected", ...
    std::string faultText(const Channel& channel) const;
    bool openAgain(Channel& channel, std::uint64_t& backNs);
    void markReopened(Channel& channel, std::uint64_t backNs);
    void reopenStepped(Channel& channel, std::uint64_t nowNs);
    bool waitUnlessStopping(std::uint64_t ns);
    void addEvent(Channel& channel, std::uint64_t nowNs, const std::string& what);
    // GroupedServo.cpp: several simulated devices on one servo thread.
    void makeGroups();
    void restartServo(Channel& channel);
    void tickDue(Group& group) noexcept;
    void groupMain(Group& group);
    void stepGroups(std::uint64_t nowNs);
    void stopGroups();

    World& mWorld;
    RuntimeOptions mOptions;
    std::vector<std::unique_ptr<Channel>> mChannels;
    std::vector<std::unique_ptr<Group>> mGroups; // empty: one servo thread per device
    std::unique_ptr<DynamicsChannel> mDynamics;  // null: the scene has no dynamic body
    ManualClock* mClock = nullptr; // step mode's clock; nullptr: threaded, CLOCK_MONOTONIC
    bool mStarted = false;         // start() or startStepped() was called (hooks are fixed)
    std::uint64_t mStartNs = 0;
    std::atomic<std::uint64_t> mStopNs{0};
    std::string mRealtimeNote;
    rt::WakeLatencyHold mWakeLatency;     // held from start() to stop() when asked for
    std::int32_t mHeldWakeLatencyUs = -1; // what it held (us), for the report
    std::uint64_t mWarmUpNs = 0;          // RuntimeOptions::warmUpNs, resolved
    std::thread mSupervisor;
    std::atomic<bool> mStopping{false};
    std::mutex mWakeMutex; // with mWake: stop() interrupts supervision's waits
    std::condition_variable mWake;
};

/// Renders a report as JSON text (the `hapto run --report` format). [control]
std::string reportToJson(const RunReport& report);

/// Why a device is unstable when its ticks were short and it missed too many deadlines: how
/// many of the misses, at least, were ticks shorter than their period that started late, and
/// the latest wake-up. At most 0.1 % of the ticks can have taken their whole period when the
/// p99.9 load is below it, so the other misses woke too late: the operating system or the
/// virtual machine did not run the servo thread on time. Empty when that does not apply
/// (stable, faulted, or a p99.9 load of 90 % or more). [any thread]
std::string lateWakeupNote(const DeviceReport& device);

} // namespace hapto
