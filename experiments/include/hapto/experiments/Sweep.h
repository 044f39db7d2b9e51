#pragma once
/// The sweep both paper experiments run: growing scenes, each renderer, each rate, each
/// condition, measured until a renderer is no longer stable.
///
/// Design note. Work is ordered by size, then scene, then renderer (one World, so one index
/// build, per renderer and scene), then rate and condition. A renderer stops growing at a rate
/// after the first size at which any of its cells was unstable (DESIGN.md's verdict on the
/// medians over repeats); that size is still measured in full, so "some of the 500-object
/// scenes" shows. Two guards keep hopeless cells cheap: a probe times a few renderer ticks
/// offline and skips the cell when one takes more than `skipTickPeriods` periods, and an
/// index whose memory, extrapolated from the previous size, would pass `maxIndexMb` is not
/// built. A skipped cell counts as unstable.

#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/experiments/Experiments.h"
#include "hapto/experiments/Plot.h"
#include "hapto/experiments/Progress.h"
#include "hapto/experiments/Stats.h"

#include "hapto/index/IndexSpec.h"

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace hapto::experiments {

/// A renderer as the paper names it, and the index behind it.
struct SweepRenderer {
    std::string name;        ///< "standard", "grid 2x2x2", "octree M=2", ...
    IndexSpec spec;          ///< The index.
    std::string paperResult; ///< What the paper reports as its limit, for the summary.
};

/// One scene of a sweep step, and where each condition's hand starts in it.
struct SweepScene {
    std::uint64_t seed = 0;      ///< The generator seed (paper2), 0 when there is none.
    std::function<Scene()> make; ///< Generates the scene (only when some renderer needs it).
    std::function<Vec3(const Scene&, Condition)> start; ///< A clear start point (m, world).
};

/// One size of a sweep: the scenes of that size.
struct SweepStep {
    std::size_t objects = 0;          ///< Objects in each scene.
    int size = 0;                     ///< K (paper1) or the count (paper2).
    std::vector<SweepScene> scenes;   ///< One per seed (paper2) or one (paper1).
    std::vector<std::string> mustRun; ///< Renderers measured here even once unstable.
};

/// How a sweep runs.
struct SweepOptions {
    std::string experiment;            ///< "paper1" or "paper2" (labels only).
    std::vector<double> ratesHz;       ///< Servo rates (Hz).
    ServoSettings servo;               ///< Duration, repeats, realtime.
    double maxIndexMb = 3000.0;        ///< Largest index (MB, extrapolated) the sweep builds.
    double skipTickPeriods = 10.0;     ///< Skip a cell whose probed tick exceeds this many periods.
    Verdict verdict = Verdict::Design; ///< What "unstable" means for the stop rule.
};

/// The sweep options an experiment's arguments give: any `Args` with `ratesHz`, `common`
/// (CommonArgs: duration, repeats, realtime, quick), `maxIndexMb` and `verdict`.
/// [control]
template <class Args> SweepOptions sweepOptionsOf(std::string experiment, const Args& args) {
    SweepOptions options;
    options.experiment = std::move(experiment);
    options.ratesHz = args.ratesHz;
    options.servo.durationS = args.common.durationS;
    options.servo.repeats = args.common.repeats;
    options.servo.realtime = args.common.realtime;
    options.servo.tail = tailFor(args.common.quick);
    options.maxIndexMb = args.maxIndexMb;
    options.verdict = args.verdict;
    return options;
}

/// One measured (or skipped) cell: renderer x rate x scene x condition.
struct SweepRow {
    std::string renderer;    ///< Paper name.
    std::string index;       ///< IndexSpec text.
    double rateHz = 0;       ///< Servo rate (Hz).
    int size = 0;            ///< K or count.
    std::size_t objects = 0; ///< Items the index holds: boxes, spheres and mesh triangles.
    std::uint64_t seed = 0;  ///< Scene seed (paper2).
    Condition condition = Condition::NoTouch; ///< No touch, touch or sliding.
    LoadFigures median;                       ///< Medians over the repeats.
    std::vector<LoadFigures> runs;            ///< Each repeat.
    bool skipped = false;     ///< Not run (probe, memory or build failure); see note.
    bool reachedPhase = true; ///< Touch/slide hands were holding/sliding when timed.
    double buildS = 0;        ///< Index build time (s).
    double indexMb = 0;       ///< Index memory (MB).
    double probeTickUs = 0;   ///< Offline probe: median tick (us).
    std::string note;         ///< Why skipped, or anything odd.

    /// DESIGN.md's verdict on the medians; a skipped cell is not stable. [any thread]
    bool stable() const { return !skipped && median.stable(); }
    /// p99.9 load < 100 % on the medians (late wake-ups forgiven); skipped is not. [any thread]
    bool loadStable() const { return !skipped && median.loadStable(); }
    /// The verdict asked for. [any thread]
    bool stable(Verdict v) const { return v == Verdict::Design ? stable() : loadStable(); }
    /// One figure's median over the repeats and its order-statistic interval. [any thread]
    MedianInterval interval(double LoadFigures::*figure) const;
};

/// Per renderer and rate: how far it went.
struct SweepLimit {
    std::string renderer;                            ///< Paper name.
    double rateHz = 0;                               ///< Servo rate (Hz).
    std::optional<std::size_t> maxStableObjects;     ///< Largest size with every cell stable.
    std::optional<int> maxStableSize;                ///< Its K or count.
    std::optional<std::size_t> firstUnstableObjects; ///< The first size with an unstable cell.
    std::optional<int> firstUnstableSize;            ///< Its K or count.
    int scenesStableAtFirstUnstable = 0;    ///< Scenes all of whose cells were stable there.
    int scenesAtFirstUnstable = 0;          ///< Scenes measured there.
    std::size_t largestMeasuredObjects = 0; ///< The largest size measured at all.
};

/// Finishes a measured row from its runs: the medians, and what was odd. A row with no run, or
/// with a run that measured no tick, is skipped with a note saying which (nothing was measured:
/// that is not a load of zero); otherwise a hand that did not reach its condition's phase, or
/// a fault, is noted. [any thread]
void concludeRow(SweepRow& row);

/// Runs the sweep; rows in measurement order. [control]
std::vector<SweepRow> runSweep(const std::vector<SweepRenderer>& renderers,
                               const std::vector<SweepStep>& steps, const SweepOptions& options,
                               Progress& progress);

/// The limits under a verdict, per renderer (in `renderers` order) and rate, from the rows in
/// size order. [control]
std::vector<SweepLimit> sweepLimits(const std::vector<SweepRenderer>& renderers,
                                    const std::vector<double>& ratesHz,
                                    const std::vector<SweepRow>& rows, Verdict verdict);

/// The CSV of the rows; `sizeColumn` names the size ("per_side" or "count"). [control]
void writeSweepCsv(const std::filesystem::path& path, const std::vector<SweepRow>& rows,
                   const std::string& sizeColumn);
/// The rows, the verdict and the limits under both verdicts (`limits`: the sweep's verdict)
/// as JSON. [control]
Json sweepJson(const std::vector<SweepRenderer>& renderers, const std::vector<double>& ratesHz,
               const std::vector<SweepRow>& rows, Verdict verdict, const std::string& sizeColumn);

/// The markdown "max stable" table: both verdicts, the first unstable size under the sweep's
/// verdict, and the paper's figure. [control]
std::string limitsTable(const std::vector<SweepRenderer>& renderers,
                        const std::vector<double>& ratesHz, const std::vector<SweepRow>& rows,
                        Verdict verdict, const std::string& sizeName);

/// The files every sweep experiment writes besides its tables: NAME.csv, NAME.json (the
/// machine, `options` with the common settings added, the rows, the verdict and the limits)
/// and the plots. Returns the plots drawn. [control]
std::vector<std::filesystem::path>
writeSweepFiles(const std::filesystem::path& out, const std::string& name, Json options,
                const CommonArgs& common, double maxIndexMb,
                const std::vector<SweepRenderer>& renderers, const std::vector<double>& ratesHz,
                const std::vector<SweepRow>& rows, Verdict verdict, const std::string& sizeColumn,
                Progress& progress);

/// Appends the list of files written to `markdown`, writes it as NAME.md and prints it.
/// [control]
void finishSweepReport(const std::filesystem::path& out, const std::string& name,
                       std::string markdown, const std::vector<std::filesystem::path>& plots);

/// A load cell as the tables show it: "p50 / p99.9 / max" in %, or UNSTABLE/skipped marks.
std::string loadCell(const SweepRow& row);

/// The first row of one cell: `renderer` at `rateHz`, step size `size` (K, count or triangles
/// asked), scene `seed` (0 where the step has no seed), `condition`; nullptr when the sweep did
/// not reach that cell. [any thread]
const SweepRow* findSweepRow(const std::vector<SweepRow>& rows, const std::string& renderer,
                             double rateHz, int size, std::uint64_t seed, Condition condition);

/// The lines of one renderer's table at one rate (empty: the renderer has no table there).
using RendererLines =
    std::function<std::vector<std::vector<std::string>>(const SweepRenderer&, double rateHz)>;
/// Per renderer at `rateHz`: a markdown heading "### NAME (SPEC), RATE" followed by `suffix`,
/// and the table of `header` over the lines `linesOf` gives. [control]
std::string rendererTables(const std::vector<SweepRenderer>& renderers, double rateHz,
                           const std::vector<std::string>& header, const std::string& suffix,
                           const RendererLines& linesOf);

/// The sentence a sweep report opens with: what the load is, then `figures` (": p50 / p99.9 /
/// max," or ";"), the runs each cell is the median of, `per` (" per scene" or empty), and what
/// UNSTABLE means under the percentile `tail`. [any thread]
std::string loadNote(const CommonArgs& common, Tail tail, const std::string& figures,
                     const std::string& per);

/// The figure of one rate: load (%) against objects, a panel per condition on one shared y
/// scale, per renderer a solid p99.9 line and a dashed p50 line of one colour (medians over a
/// size's scenes), a tic at every size measured, and a ring on each p99.9 point where some
/// cell of that size was unstable under `verdict`. [any thread]
PlotSpec sweepPlot(const std::string& experiment, const std::vector<SweepRenderer>& renderers,
                   double rateHz, const std::vector<SweepRow>& rows, Verdict verdict);
/// Draws `spec` into `dir` and appends the files drawn to `files`; a plot that cannot be drawn
/// (no gnuplot, a failed run) is noted on `progress`, not thrown. [control]
void drawPlotNoting(const std::filesystem::path& dir, const PlotSpec& spec, Progress& progress,
                    std::vector<std::filesystem::path>& files);
/// One sweepPlot() per rate with `caption` under its title, drawn. Returns the files drawn;
/// notes problems. [control]
std::vector<std::filesystem::path> plotSweep(const std::filesystem::path& dir,
                                             const std::string& experiment,
                                             const std::vector<SweepRenderer>& renderers,
                                             const std::vector<double>& ratesHz,
                                             const std::vector<SweepRow>& rows, Verdict verdict,
                                             Progress& progress, const std::string& caption = {});

/// The caption of a figure of medians over repeats: the runs per point and their duration, a
/// smoke-test mark for --quick, and what the bars are (with their coverage). [any thread]
std::string repeatsCaption(const CommonArgs& common);

/// A paragraph on how the cells were measured: the verdict driving the sweep, whether
/// SCHED_FIFO was granted, and the platform's wake-up lateness and misses (medians over the
/// measured cells), so that misses can be told apart from overload. [control]
std::string platformNote(const std::vector<SweepRow>& rows, Verdict verdict);

/// The verdict a sweep uses: the one --verdict names; a --quick run without it uses the load
/// verdict (`quickDefault`), the renderer's own time against the period, which is what the
/// paper judged (its limits are servo-loop load, e.g. "load < 40 %"), while the design verdict
/// would also count the deadlines a short run on a shared machine misses by late wake-ups.
/// [any thread]
Verdict sweepVerdict(bool quick, bool verdictGiven, Verdict given);

/// The header a --quick run's report opens with: that it is a smoke test (the experiment runs
/// and writes every file), the runs it made, which claims it `cannotJudge`, and the verdict
/// its table uses (`verdict`, said in full). [any thread]
std::string smokeTestHeader(const CommonArgs& common, const std::string& cannotJudge,
                            const std::string& verdict);
/// smokeTestHeader for a sweep: `limits` (e.g. "the paper's max-stable claims") cannot be
/// judged from a sweep that stops at `largest` objects, nor p99.9 from a few hundred ticks; the
/// verdict is `verdict` read on the quick tail (p99). Empty for a full run. [any thread]
std::string sweepSmokeHeader(const CommonArgs& common, Verdict verdict, std::size_t largest,
                             const std::string& limits = "the paper's max-stable claims");

/// "1 kHz", "20 kHz", "500 Hz". [any thread]
std::string rateText(double rateHz);

} // namespace hapto::experiments
