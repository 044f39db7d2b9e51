#pragma once
/// What every `hapto experiment` shares: timed servo runs of simulated hands through the real
/// Runtime, medians over repeats, clear start points, output files and markdown tables.
///
/// Design note. A measurement is one short session of the real Runtime (servo thread,
/// absolute deadlines, SCHED_FIFO when permitted) over one World, so the load reported is the
/// load DESIGN.md defines: wake-up to force written, over the period. The paper's "touch" and
/// "sliding" conditions need the hand in contact before the clock starts, but the scripted
/// hand takes 1.3 s or more to approach and press. WarmedSimDevice therefore plays the
/// approach offline, on the control thread, against a small local index of the objects near
/// the hand, with the same proxy renderer the servo thread uses; the timed session then
/// starts with the hand already pressing. Each cell is run `repeats` times and every figure
/// reported is the median over the repeats, because the machine is shared and noisy.

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/World.h"
#include "hapto/scenes/Scene.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace hapto::experiments {

/// The JSON the experiments write: nlohmann's, keys kept in the order they were added.
using Json = nlohmann::ordered_json;

/// The paper's three hand conditions, as simulated hand scripts.
enum class Condition : std::uint8_t {
    NoTouch, ///< Moving through free space near objects (script `free`).
    Touch,   ///< Pressing still on a surface (script `touch`, measured while holding).
    Sliding, ///< Pressing while sliding along a surface (script `slide`, measured while sliding).
};

/// All three, in the paper's column order.
inline constexpr Condition kConditions[] = {Condition::NoTouch, Condition::Touch,
                                            Condition::Sliding};

/// "no touch", "touch", "sliding": the paper's column names. [any thread]
std::string_view conditionName(Condition condition);
/// "free", "touch", "slide": the SimConfig script of a condition. [any thread]
std::string_view conditionScript(Condition condition);

/// Which load percentile a verdict reads.
///
/// A verdict asks whether the tail of the load stays under the period. p99.9 is the design's
/// figure, but it needs thousands of ticks to mean anything: a `--quick` run (0.15 s at 1 kHz,
/// 150 ticks) has no p99.9 other than its maximum, so one preempted tick would decide it. Quick
/// runs therefore judge on p99 (the second-largest of 150 ticks) and say so in every output.
enum class Tail : std::uint8_t {
    P999, ///< p99.9 load: full runs (the design's verdict).
    P99,  ///< p99 load: quick runs, whose few hundred ticks make p99.9 their maximum.
};
/// "p99.9" or "p99". [any thread]
std::string_view tailName(Tail tail);
/// A sentence for reports: which percentile the verdicts read, and why when it is p99.
/// [any thread]
std::string verdictNote(Tail tail);
/// The tail a run of `quick` settings judges on. [any thread]
inline Tail tailFor(bool quick) {
    return quick ? Tail::P99 : Tail::P999;
}

/// Settings shared by every servo measurement.
struct ServoSettings {
    double durationS = 0.5;     ///< Timed run per repeat (s).
    int repeats = 3;            ///< Runs per cell; figures are medians over them.
    bool realtime = true;       ///< Ask for SCHED_FIFO and pinning (the Runtime falls back).
    double warmupSettleS = 0.1; ///< Simulated time in the measured phase before timing (s).
    Tail tail = Tail::P999;     ///< The load percentile verdicts read.
};

/// A simulated hand that can be brought into its measured phase (holding for `touch`,
/// sliding for `slide`) offline before the Runtime opens it. Forwards everything else to a
/// SimDevice. The first reading after warm-up reports the offline proxy (on the surface) so
/// that the Runtime's renderer starts outside the solid, as the offline one ended.
class WarmedSimDevice final : public Device {
public:
    /// `planScene` is what the script plans against (it may hold only the objects near the
    /// hand, with the full scene's bounds); it must outlive open(). [control]
    WarmedSimDevice(const DeviceConfig& config, const Scene& planScene);

    /// Opens the hand and, for `touch` and `slide`, plays it offline until it has spent
    /// `settleS` of simulated time holding or sliding (at most `maxS`). Returns the simulated
    /// time spent (s). Throws std::runtime_error when the hand cannot open. [control]
    double warmUp(double settleS, double maxS = 20.0);
    /// True when warm-up reached the measured phase (always true for other scripts). [control]
    bool reachedPhase() const { return mReached; }

    std::string_view name() const override { return mSim.name(); }
    DeviceKind kind() const override { return mSim.kind(); }
    DeviceCapabilities capabilities() const override { return mSim.capabilities(); }
    /// Opens the hand unless warmUp() already did. [control]
    DeviceStatus open() override;
    void close() override { mSim.close(); }
    /// The hand's reading; the first one after warm-up shows the proxy instead. [servo]
    DeviceStatus read(DeviceState& state) noexcept override;
    /// Forwards the force. [servo]
    DeviceStatus write(const Vec3& forceN) noexcept override { return mSim.write(forceN); }
    /// Forwards the skipped periods (the hand's time runs on). [servo]
    void periodsSkipped(std::uint64_t periods) noexcept override { mSim.periodsSkipped(periods); }
    std::string errorMessage() const override { return mSim.errorMessage(); }

private:
    DeviceConfig mConfig;
    const Scene& mPlanScene;
    SimDevice mSim;
    bool mOpened = false;
    bool mReached = true;
    bool mPrimePending = false;
    Vec3 mPrimeDevice{0.0}; // device frame (m)
};

/// A copy of `scene` holding only the objects whose AABB meets `region`, with the same bounds
/// (what a script needs to plan near its start; planning against it is much cheaper). [control]
Scene sceneNear(const Scene& scene, const Aabb& region);

/// Throws std::logic_error when `point` lies inside an object or closer than `marginM` to
/// one (by AABB): a start point a placement promised to be clear. [control]
void requireClear(const Scene& scene, const Vec3& point, double marginM, std::string_view what);

/// One device's figures from one run, loads in percent of the period.
struct LoadFigures {
    double meanPct = 0;         ///< Mean load (%).
    double p50Pct = 0;          ///< Median load (%).
    double p99Pct = 0;          ///< p99 load (%).
    double p999Pct = 0;         ///< p99.9 load (%).
    double maxPct = 0;          ///< Largest load (%).
    double tickNsP50 = 0;       ///< Median tick, wake-up to force written (ns).
    double tickNsP999 = 0;      ///< p99.9 tick, wake-up to force written (ns).
    double tickNsMax = 0;       ///< Longest tick, wake-up to force written (ns).
    double ticks = 0;           ///< Ticks run.
    double missed = 0;          ///< Missed deadlines.
    double missedPct = 0;       ///< Missed deadlines, % of ticks.
    double lateWakeups = 0;     ///< Wake-ups later than 10 % of the period.
    double contactPct = 0;      ///< Ticks in contact, % of ticks.
    double candidatesMean = 0;  ///< Candidate slots the renderer examined per tick.
    double locateStepsMean = 0; ///< Cursor steps per tick (both cursors).
    double lateP999Us = 0;      ///< Wake-up lateness, p99.9 (us): the platform's share of misses.
    double lateMaxUs = 0;       ///< Wake-up lateness, max (us).
    bool realtime = false;      ///< SCHED_FIFO was granted.
    std::string fault;          ///< Empty, or why the device stopped.
    Tail tail = Tail::P999;     ///< The percentile the verdicts read.

    /// The load the verdicts read: p99.9, or p99 for quick runs (%). [any thread]
    double tailPct() const { return tail == Tail::P99 ? p99Pct : p999Pct; }
    /// DESIGN.md's verdict: tail load < 100 %, misses <= 0.1 % of ticks, no fault. [any thread]
    bool stable() const { return loadStable() && missedPct <= 0.1; }
    /// The renderer's own verdict: tail load < 100 % (so at most 0.1 % of ticks, 1 % for the
    /// p99 of quick runs, overran their period from their wake-up), no fault; misses caused by
    /// late wake-ups do not count.
    bool loadStable() const { return fault.empty() && ticks > 0 && tailPct() < 100.0; }
};

/// Which verdict decides "stable" in a sweep.
enum class Verdict : std::uint8_t {
    Design, ///< DESIGN.md: p99.9 load < 100 % and <= 0.1 % deadlines missed.
    Load,   ///< p99.9 load < 100 % only (for machines whose wake-ups are late by themselves).
};
/// "design" or "load". [any thread]
std::string_view verdictName(Verdict verdict);
/// Parses "design" or "load"; throws InputError naming `option`. [any thread]
Verdict parseVerdict(const std::string& text, const std::string& option);

/// Figures of one DeviceReport, judged on `tail`. [control]
LoadFigures figuresOf(const DeviceReport& report, Tail tail = Tail::P999);
/// The per-field median of several runs (fault: the first non-empty; realtime: all). [control]
LoadFigures medianOf(const std::vector<LoadFigures>& runs);
/// The median of values (0 for none). [any thread]
double median(std::vector<double> values);

/// One hand to run: its configuration and the scene its script plans against.
struct HandPlan {
    DeviceConfig config;              ///< kind "sim", rate, script, seed, start.
    const Scene* planScene = nullptr; ///< Scene the script plans against; outlives the run.
};

/// The outcome of one timed session.
struct SessionResult {
    RunReport report;          ///< The Runtime's report.
    std::vector<bool> reached; ///< Per hand: warm-up reached the measured phase.
};

/// Runs one timed session of the hands over `world` for settings.durationS: warm-up offline,
/// Runtime start, maintain every 5 ms, stop. [control]
SessionResult runSession(World& world, const std::vector<HandPlan>& hands,
                         const ServoSettings& settings);

/// A simulated hand configuration: name, rate, script, seed and start (world = device). [control]
DeviceConfig simHand(const std::string& name, double rateHz, std::string_view script,
                     std::uint64_t seed, const Vec3& start);

/// Median seconds of `runs` servo steps (ServoStep: read, the haptic tick, write, metrics) of a
/// 1 kHz device held at `point` over `world`, outside any Runtime: a probe to skip sizes whose
/// tick obviously overruns. [control]
double probeTickSeconds(World& world, const Vec3& point, int runs);

/// Output folder: created; throws InputError when it cannot be. [control]
std::filesystem::path prepareOutDir(const std::string& dir);
/// Writes text to a file, whole or not at all (a temporary renamed into place); throws
/// InputError or std::runtime_error on failure. [control]
void writeText(const std::filesystem::path& path, const std::string& text);

/// A number as text: fixed with `decimals` places. [any thread]
std::string fmt(double value, int decimals);
/// A markdown table. [any thread]
std::string markdownTable(const std::vector<std::string>& header,
                          const std::vector<std::vector<std::string>>& rows);

/// What a results file says about where it was measured: CPU model, cores, load average,
/// kernel, and the command line. [control]
Json machineJson();

} // namespace hapto::experiments
