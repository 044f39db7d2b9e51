#pragma once
/// The harness behind `hapto bench tick`: the servo's own step (ServoStep) over one scene along
/// a seeded hand walk, timed stage by stage, each tick started back to back, after a sleep, or
/// after a sleep with the servo loop's warm-up.
///
/// Design note. The bench runs no copy of the tick: each (index, mode) owns a ServoStep set up
/// as the runtime sets up a device's (1 kHz, the default renderer and safety filter, the
/// runtime's miss rules) and calls ServoStep::run with a probe, which stamps the clock at
/// each stage's end. So read, fault checks, frame and tool tip, velocity, effects, hook,
/// safety, miss rules, write, metrics and contacts all run and are timed as a servo runs them.
/// Two things differ from a servo thread, both outside the step: the bench sets each tick's
/// deadline itself (the wake-up when back to back, the end of the sleep otherwise), and it has
/// no watchdog, since its runs take turns in blocks and a run waits while the others tick.
/// The device plays the walk (WalkDevice); with `sim` it reads and writes a simulated hand
/// too, so their cost is timed, but the walk still gives the point.

#include "hapto/core/Geometry.h"
#include "hapto/devices/Device.h"
#include "hapto/experiments/HandWalk.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/runtime/BodyPoses.h"
#include "hapto/runtime/RenderOutput.h"
#include "hapto/runtime/ServoLoop.h"
#include "hapto/runtime/ServoStep.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/Scene.h"

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hapto::experiments {

/// A device that plays a hand walk: read() hands over the walk's next point (device frame =
/// world frame) without a velocity, write() keeps the force; given a path, it plays the path's
/// points in turn instead (cyclically), and the walk is not used. Over an `inner` device (a
/// simulated hand) it reads and writes that one too and reports its status, with the walk's
/// point in place of its position. Kind "scripted": made by a program, never by a device file.
class WalkDevice final : public Device {
public:
    /// A walk over `bounds` (m) from `seed`, or `path` (m) when it is not empty; `inner` may
    /// be null. [control]
    WalkDevice(const Aabb& bounds, std::uint64_t seed, std::unique_ptr<Device> inner = nullptr,
               std::vector<Vec3> path = {});
    std::string_view name() const override { return "walk"; }
    DeviceKind kind() const override { return DeviceKind::Scripted; }
    DeviceCapabilities capabilities() const override { return {}; }
    DeviceStatus open() override;
    void close() override;
    DeviceStatus read(DeviceState& state) noexcept override;
    DeviceStatus write(const Vec3& forceN) noexcept override;
    void periodsSkipped(std::uint64_t periods) noexcept override;
    std::string errorMessage() const override;
    /// The walk, to hold the hand back. [control]
    HandWalk& walk() { return mWalk; }
    /// The last force written (N, device frame). [control]
    const Vec3& lastForceN() const { return mForceN; }

private:
    HandWalk mWalk;
    std::vector<Vec3> mPath;
    std::size_t mPathAt = 0;
    std::unique_ptr<Device> mInner;
    Vec3 mForceN{0.0};
};

/// A hand that feels the force: after a tick it is held back to at most `pushM` (m, > 0) from
/// the proxy when it is farther (beyond the proxy only where a surface holds it back); 0
/// leaves it alone. [control]
void holdHandBack(HandWalk& hand, const Vec3& devicePointM, const Vec3& proxyM, double pushM);

/// How a tick is started: back to back, after a sleep, or after a sleep with the servo loop's
/// warm-up before the deadline.
enum class TickMode : std::uint8_t { Hot, Sleep, Warm };

/// The box the walk roams: `bounds`, or with `edgeM` > 0 their part within the cube of that
/// edge (m) centred on their centre.
Aabb walkBox(const Aabb& bounds, double edgeM);

/// What to run.
struct TickBenchSettings {
    std::vector<IndexSpec> indices; ///< One target each.
    bool simDevice = false;         ///< Read and write a simulated hand too (--device sim).
    std::size_t ticks = 5000;       ///< Ticks per mode and index.
    double sleepUs = 1000;          ///< Sleep before each tick of the sleep modes (us).
    double warmUs = static_cast<double>(kDefaultWarmUpNs) / 1000.0; ///< Warm-up (us).
    std::uint64_t seed = 1;                                         ///< The walk's seed.
    Aabb walkIn{Vec3(0.0), Vec3(0.0)}; ///< The box the walk roams (m; walkBox()).
    /// After each tick the hand is held back to at most this far from the proxy (mm); 0: it
    /// ignores the force and walks through everything, leaving the proxy behind.
    double pushMm = 2.0;
    std::int32_t wakeLatencyUs = -1; ///< >= 0: also the sleep modes with this request held.
    /// The modes to run; empty: hot, sleep, sleep+warm (and the held ones with wakeLatencyUs).
    std::vector<TickMode> modes;
    /// Not empty: the device plays these points (m), one a tick, cyclically, in place of the
    /// walk (pushMm should then be 0: a path is not held back).
    std::vector<Vec3> path;
    /// Not empty: the scene's one dynamic body takes these poses (m, m/s), one a tick
    /// (cyclically), each published into the step's BodyPoseTable just before the tick and
    /// stamped with that moment, as a 1 kHz dynamics thread would; the impulses handed back
    /// are taken and dropped (the dynamics step is not timed here).
    std::vector<BodyPose> bodyPoses;
    /// Also read this thread's CPU clock around each tick (TickRun::cpuNs): the tick's own
    /// time without the time other processes held the core. Two clock_gettime calls per tick,
    /// outside the stages' stamps.
    bool cpuTime = false;
    /// Runs every (index, mode) this many times over the same ticks (the same seed, path and
    /// poses: the same work), each time with a fresh device and step over the same index, and
    /// keeps in TickRun::ownNs each tick's least wall time: its own cost, with the host's
    /// interruptions taken out (one that lands on a tick in one repeat rarely lands on it in
    /// every one). The other samples are the first repeat's. At least 1.
    std::size_t repeats = 1;
};

/// What one tick did, the work that explains its time.
struct TickCounts {
    std::uint32_t candidates = 0; ///< Candidate slots the renderer examined, every solve.
    std::uint8_t solves = 0;      ///< Renderer solves (TickOutput::solves).
    std::uint8_t passes = 0;      ///< Solver passes of the last solve (RenderOutput::iterations).
    std::uint8_t extraLeaves = 0; ///< Extra leaves listed (TickOutput::extraLeaves).
    std::uint8_t pullBacks = 0;   ///< Pull-backs (TickOutput::pullBacks).
    std::uint8_t contacts = 0;    ///< Active constraints at the end (0 to 3).
    std::uint8_t bodies = 0;      ///< Dynamic bodies placed near the tool.
    /// Facets entered: the tick's contact planes (item and normal) that the previous tick's
    /// contacts did not hold: the faces, edges' sides and triangles the proxy moved onto.
    std::uint8_t facetsEntered = 0;

    bool operator==(const TickCounts&) const = default; ///< Every count the same.
};

/// One (index, mode) being driven: its device, its step and its per-tick samples.
struct TickRun {
    TickMode mode = TickMode::Hot;           ///< How its ticks are started.
    bool holdLatency = false;                ///< Holds the wake-latency request while it ticks.
    WalkDevice* device = nullptr;            ///< The device `owned` holds.
    std::unique_ptr<Device> owned;           ///< Owns the device (a WalkDevice).
    std::unique_ptr<ServoStep> step;         ///< The servo step it times.
    std::unique_ptr<ServoStepShared> shared; ///< Its metrics and mailboxes.
    std::unique_ptr<BodyPoseTable> bodies;   ///< The dynamic body's poses (bodyPoses), or null.
    ServoStepProbe probe;                    ///< The last tick's stage ends and what it computed.
    std::array<std::vector<double>, ServoStepProbe::kStages> stageNs; ///< Per stage, per tick.
    std::vector<double> tickNs; ///< Per tick: wake-up to the end of the metrics stage (ns).
    /// Per tick with TickBenchSettings::cpuTime: this thread's CPU time over the step (ns,
    /// including about half of one clock_gettime call); empty otherwise.
    std::vector<double> cpuNs;
    std::vector<Vec3> forceN;       ///< Per tick: the force sent (N, world).
    std::vector<double> gapM;       ///< Per tick: the device point's distance from the proxy (m).
    std::uint64_t ticks = 0,        ///< Ticks run.
        locateSteps = 0,            ///< Cursor steps, both cursors, summed.
        candidates = 0,             ///< Candidate slots the renderer examined, summed.
        contactTicks = 0;           ///< Ticks with at least one contact.
    std::uint64_t solves = 0,       ///< Renderer solves, summed.
        extraLeaves = 0,            ///< Extra leaves listed, summed.
        pullBacks = 0;              ///< Pull-backs, summed.
    std::uint64_t passes = 0,       ///< Solver passes of each tick's last solve, summed.
        multiContactTicks = 0,      ///< Ticks with two or three contacts (an edge, a corner).
        facetsEntered = 0;          ///< TickCounts::facetsEntered, summed.
    std::vector<TickCounts> counts; ///< Per tick: the work it did.
    RenderOutput lastRender;        ///< The last tick's render (for TickCounts::facetsEntered).
    std::uint64_t kept = 0;         ///< What the warm-up read, kept.
    /// Warm-ups still running at their deadline: those ticks started late by the overrun,
    /// which the tick's time (from the wake-up) does not show.
    std::uint64_t warmOverruns = 0;
    /// Per tick after a sleep: how long after its deadline it started (ns; 0 if on time): the
    /// wake-up's lateness, plus a warm-up's overrun. A servo reads its device this late.
    std::vector<double> startLateNs;
    /// Per tick with TickBenchSettings::repeats > 1: its least wall time over the repeats
    /// (ns); empty otherwise.
    std::vector<double> ownNs;
    /// Ticks whose work (TickCounts) differed between repeats: 0 when every repeat did the
    /// same work, as a deterministic step does; otherwise ownNs mixes different work.
    std::uint64_t workDiffered = 0;
};

/// One index: its world (scene copy, index, snapshots) and its runs.
struct TickTarget {
    IndexSpec spec;                             ///< The index it builds.
    std::unique_ptr<World> world;               ///< The scene's copy, indexed by `spec`.
    std::vector<std::unique_ptr<TickRun>> runs; ///< One per mode it runs.
};

/// "hot", "sleep", "sleep+warm", "sleep+lat", "sleep+warm+lat". [any thread]
const char* modeName(const TickRun& run);

/// Builds every target over `scene` and runs every (index, mode) for settings.ticks ticks, the
/// runs taking turns in blocks of kTickBlock ticks (each block starting with another run), so
/// a slow spell of the machine falls on all of them alike; then again settings.repeats - 1
/// times, folding each tick's least time into TickRun::ownNs. Throws std::invalid_argument for
/// 0 repeats, std::runtime_error when a device does not open, a wake-latency request cannot
/// be held, or a step faults. [control]
std::vector<TickTarget> runTickBench(const Scene& scene, const TickBenchSettings& settings);
/// Folds `again`, a repeat of `first`'s ticks, into `first`: each tick's TickRun::ownNs
/// becomes the least of it and `again`'s wall time, and TickRun::workDiffered counts the ticks
/// whose TickCounts differ. `first.ownNs` must already hold a time per tick (the first
/// repeat's, to begin with); `again` must have as many ticks. [control]
void foldRepeat(TickRun& first, const TickRun& again);
/// Ticks a run takes in one turn.
inline constexpr std::size_t kTickBlock = 256;

/// Nearest-rank quantiles and the mean of some samples.
struct Quantiles {
    double p50 = 0, ///< The median (the samples' unit).
        p99 = 0,    ///< The 99th percentile.
        p999 = 0,   ///< The 99.9th percentile.
        max = 0,    ///< The largest sample.
        mean = 0;   ///< The mean.
};
/// The nearest-rank quantile `q` of `sorted` samples (0 when empty). [any thread]
double quantileOfSorted(const std::vector<double>& sorted, double q);
/// The quantiles of `samples` (all zero when empty). [any thread]
Quantiles quantilesOf(std::vector<double> samples);

/// What a run's slowest ticks did: those whose time is at or above the nearest-rank quantile
/// of the times (the p99.9 ticks, say), as means of their counts.
struct TailWork {
    std::size_t ticks = 0;  ///< Ticks at or above the quantile.
    double solvedAgain = 0; ///< The share of them the renderer solved more than once.
    double solves = 0;      ///< Their mean renderer solves.
    double passes = 0;      ///< Their mean solver passes (of the last solve).
    double candidates = 0;  ///< Their mean candidates.
    double extraLeaves = 0; ///< Their mean extra leaves.
};
/// The tail of `ns` (a time per tick, as `counts` has counts) at or above its nearest-rank
/// quantile `q`; all zero when there are no ticks. Throws std::invalid_argument when the two
/// differ in length or q is not in (0, 1]. [any thread]
TailWork tailWork(const std::vector<TickCounts>& counts, const std::vector<double>& ns, double q);

} // namespace hapto::experiments
