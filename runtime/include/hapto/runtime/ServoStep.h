#pragma once
/// One device's servo step, written once: read the device, the fault rules, the frame and the
/// tool tip, the velocity, HapticTick::tick (effects, hook, safety), the miss rules, write,
/// metrics, contacts, recording and the deadline bookkeeping.
///
/// Design note. Every caller of the device-side step runs this one: a servo thread
/// (Runtime's servoMain), a servo group's thread (GroupedServo.cpp), the step mode
/// (Runtime::step), `hapto bench tick` (experiments/TickBench.h, which passes a probe to time
/// the stages) and so the experiments built on them. A ServoStep is the servo's hot state:
/// what one step reads and writes, laid out for the cache, and pointers (ServoStepPorts) to
/// what it shares with other threads (metrics, mailboxes, the world). Invariant: run() never
/// allocates, locks, logs, throws or makes a syscall beyond the device's own I/O and the clock;
/// with a null probe it reads the clock exactly where the servo needs it (read done, write
/// start, write done). Faults become zero force and a FaultKind in the metrics, never an
/// exception.
///
/// The fault rules, per step:
///   - read() or write() fails: fault, zero, the servo ends (supervision closes and reopens);
///   - a non-finite position or velocity: fault, zero, the servo ends;
///   - the read returns more than the stall timeout after the last step: the watchdog's fault
///     (the supervisor may have seen it first, while the read hung), zero, the servo ends;
///   - K missed deadlines in a row, or a wake-up K periods late (the thread could not run
///     while the device held its last force): that step commands zero, and force grows from
///     zero at the safety filter's rate once steps are on time again.

#include "hapto/core/Geometry.h"
#include "hapto/core/Mailbox.h"
#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/DeviceMetrics.h"
#include "hapto/runtime/Effects.h"
#include "hapto/runtime/HapticTick.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/World.h"

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace hapto {

class TraceRecorder;

/// No object: a ContactReport slot that holds no contact.
inline constexpr ObjectId kNoObject = 0xFFFFFFFFu;

/// What a servo step tells the control thread every tick: the force it sent and its contacts
/// (world frame); Runtime::lastTick() reads the newest.
struct ContactReport {
    std::uint64_t tick = 0; ///< The servo tick it describes.
    Vec3 devicePoint{0.0};  ///< Device point (m).
    Vec3 proxy{0.0};        ///< God-object proxy (m).
    Vec3 force{0.0};        ///< Force sent, external force included (N).
    std::array<ObjectId, 3> objects{kNoObject, kNoObject, kNoObject}; ///< Touched object ids.
    std::array<Vec3, 3> normals{};  ///< Their outward contact normals.
    std::uint32_t contactCount = 0; ///< How many of the above are set.
};

/// What a step shares with other threads, and where its time comes from. Every pointer must
/// be set (and outlive the step's use) before the first run().
struct ServoStepPorts {
    World* world = nullptr;                               ///< Snapshots come from here.
    DeviceMetrics* metrics = nullptr;                     ///< Step -> any thread.
    Mailbox<ContactReport>* contacts = nullptr;           ///< Step -> control, every step.
    const Mailbox<Vec3>* externalForce = nullptr;         ///< Control -> step, world (N).
    const Mailbox<EffectSet>* effects = nullptr;          ///< Control -> step, when changed.
    const std::atomic<std::uint64_t>* effectsPublished{}; ///< Sets published to `effects`.
    ManualClock* clock = nullptr; ///< The step mode's clock; null: CLOCK_MONOTONIC.
    std::uint64_t startNs = 0;    ///< The session's start: a recorded sample's time is from it.
    /// The dynamic bodies' poses and the impulses handed back to them; null: the scene has no
    /// dynamic body (or no dynamics runs).
    BodyPoseTable* bodies = nullptr;
};

/// The parts a step shares, owned together, for a step that runs outside a Runtime (the
/// bench, the experiments): nobody else reads the metrics or publishes effects, but the step
/// runs exactly as in a Runtime's channel.
struct ServoStepShared {
    DeviceMetrics metrics;                          ///< The step's metrics.
    Mailbox<ContactReport> contacts;                ///< The step's contact reports.
    Mailbox<Vec3> externalForce;                    ///< External force for the step (N, world).
    Mailbox<EffectSet> effects;                     ///< Effect sets for the step.
    std::atomic<std::uint64_t> effectsPublished{0}; ///< Sets published to `effects`.

    /// Ports to these, snapshots from `world`, time from `clock` (null: CLOCK_MONOTONIC).
    /// [control]
    ServoStepPorts portsFor(World& world, ManualClock* clock = nullptr) noexcept {
        return {&world, &metrics, &contacts, &externalForce, &effects, &effectsPublished,
                clock,  0,        nullptr};
    }
};

/// The stage ends of one step and what it computed, for `hapto bench tick`. Filled only when
/// passed to run(); a null probe costs nothing.
struct ServoStepProbe {
    /// The stages, in the order run() runs them.
    static constexpr std::array<const char*, 9> kStageNames{"read",       "snapshot", "locate",
                                                            "candidates", "render",   "effects",
                                                            "safety",     "write",    "metrics"};
    static constexpr std::size_t kStages = kStageNames.size(); ///< How many stages: 9.
    /// The steady clock (ns, rt::nowNs; the step's clock for read and write) at the end of
    /// each stage: read (the device's read()), snapshot (the fault checks, the claim, the
    /// frame, the tool tip, the velocity, new effects), the five of HapticTick::tick, write
    /// (the miss rules and the device's write()), metrics (metrics, contacts, recording, the
    /// next deadline).
    std::array<std::uint64_t, kStages> endNs{};
    HapticTick::StageStamps tickStages{}; ///< Where HapticTick::tick writes its stage ends.
    TickOutput tick;                      ///< What HapticTick::tick computed.
    Vec3 devicePointM{0.0};               ///< The device point (m, world).
    Vec3 forceN{0.0};                     ///< The force sent (N, world), after the miss rules.
};

/// One device's servo step: its hot state and run(). One per device, used by one thread at a
/// time. The fields are the servo's own: [control] before start() and while it does not run,
/// [servo] (the thread that steps) while it runs.
///
/// Size: 21824 bytes, 64-byte aligned (a static_assert in the source file), of which 21312 are
/// the HapticTick.
struct alignas(64) ServoStep {
    // Fixed from construction (reader: from open).
    Device* device = nullptr;          ///< The device it reads and writes (not owned).
    TraceRecorder* recorder = nullptr; ///< Records every step when set; null: no recording.
    SnapshotReader* reader = nullptr;  ///< Its reader of the world's snapshots.
    WorkspaceTransform transform;      ///< Device frame -> world frame.
    Vec3 toolTip{0.0}; ///< The contact point in the stylus frame (m); 0 = the gimbal centre.
    std::uint64_t periodNs = 1'000'000; ///< The servo period (ns); set by setTiming().
    std::uint64_t lateNs = 0;           ///< A wake-up later than this is counted late.
    std::uint64_t starvedNs = 0;        ///< One this late (K periods) commands zero.
    std::uint64_t stallNs = 0;          ///< The watchdog's limit between two steps.
    double dtS = 1e-3;                  ///< The period (s).
    int missLimit = 3;                  ///< K.
    ServoStepPorts ports;               ///< What it shares with other threads, and its clock.

    // Per step.
    std::uint64_t deadlineNs = 0;     ///< The next wake-up.
    std::uint64_t tick = 0;           ///< Steps completed, over every start of the servo.
    std::uint64_t effectsApplied = 0; ///< Effect sets published that the haptic tick holds.
    int consecutiveMisses = 0;        ///< Saturates at missLimit.
    bool first = true;                ///< The next step is the first since the servo started.
    /// Raised by another thread to end the servo (run() returns false); start() lowers it.
    std::atomic<bool> stop{false};
    Vec3 lastPosition{0.0}; ///< The last device point (m, world).
    Vec3 lastStep{0.0};     ///< The last step's move of the device point (m, world).
    DeviceState sample;     ///< The last reading.
    HapticTick haptic;      ///< The haptic tick: cursors, renderer, effects, safety filter.

    /// Checks both configurations (std::invalid_argument). [control]
    ServoStep(const RendererConfig& renderer, const SafetyConfig& safety)
        : haptic(renderer, safety) {}
    ServoStep(const ServoStep&) = delete;
    ServoStep& operator=(const ServoStep&) = delete;

    /// Sets the period (ns, > 0) and the rules timed by it: dtS, the late threshold
    /// (`lateWakeupFraction` of the period), K = max(1, `missLimit`), the starved wake-up (K
    /// periods) and the watchdog's `stallTimeoutNs`. [control]
    void setTiming(std::uint64_t periodNs, int missLimit, double lateWakeupFraction,
                   std::uint64_t stallTimeoutNs) noexcept;
    /// The servo starts (or starts again) at `nowNs`: the proxy starts on the next point, force
    /// grows from zero, the first deadline is one period on; the metrics show it running.
    /// [control] (before its thread starts, or from the stepping thread)
    void start(std::uint64_t nowNs) noexcept;
    /// One step woken at `wakeNs` (the step's clock); `probe`, if not null, gets the stage
    /// ends and what the step computed. Returns false when the servo must end: a fault (zero
    /// was written, the metrics hold it), the watchdog, or `stop` raised during the step (the
    /// caller's leave() writes zero). [servo]
    bool run(std::uint64_t wakeNs, ServoStepProbe* probe = nullptr) noexcept;
    /// Touches the next step's working set without changing anything it reads (warmUpTick in
    /// ServoLoop.h); returns what it read, to keep. [servo]
    std::uint64_t warm() noexcept;
    /// The servo leaves: zero force written, no contact published, the metrics show it
    /// stopped. [servo]
    void leave() noexcept;
    /// The step's clock (ns): ports.clock's, or CLOCK_MONOTONIC. [servo]
    std::uint64_t now() const noexcept;

private:
    bool readDevice(std::uint64_t& readDoneNs) noexcept;
    Vec3 devicePoint(Vec3& velocity) noexcept;
    void takeNewEffects() noexcept;
    void fault(FaultKind kind, DeviceStatus status, std::uint64_t atNs) noexcept;
    void publish(const TickOutput& out, const Vec3& p, const Vec3& force,
                 std::uint64_t version) noexcept;
    void record(const TickOutput& out, const Vec3& deviceForce, std::uint64_t wakeNs,
                std::uint64_t tickNs, std::uint64_t ioNs, bool missed) noexcept;
    void advanceDeadline(std::uint64_t doneNs, bool missed) noexcept;
};

} // namespace hapto
