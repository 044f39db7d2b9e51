#pragma once
/// `hapto experiment grasp`: two simulated hands grasp, lift and carry a dynamic box in step
/// mode, swept one factor at a time (squeeze force, mass, surface stiffness, servo rate) around
/// a default cell; written as CSV, JSON, markdown and gnuplot figures.
///
/// Design note. Each distinct cell (GraspCell.h) runs `repeats` times. Step mode makes every
/// physical figure (slip, lift, penetration, energy gain, force error, held) the same every
/// run, and the experiment checks it: a cell whose repeats differ in any of them is flagged
/// (`repeatable` false). Only the dynamics step's cost varies (it is the stepping thread's CPU
/// time, a timing): its p50 and p99.9 are taken per run and reported as the median over the
/// runs with an order-statistic interval (Stats.h). Next to every row stands the analytic
/// expectation of Coulomb friction: two hands pressing F each on a body of mass m hold it iff
/// mu_s (F + F) >= m g, and a verdict column says whether the measured held/dropped agrees.
/// The default cell appears once per factor in the table, run once.

#include "hapto/experiments/Experiments.h"
#include "hapto/experiments/GraspCell.h"

#include <vector>

namespace hapto::experiments {

/// What `hapto experiment grasp` runs. `common.durationS` and `common.realtime` do not apply:
/// the grasp's timetable is fixed (GraspTimes) and step mode runs no thread.
struct GraspArgs {
    CommonArgs common;  ///< --out, --quick, --repeats (the runs the step cost is taken over).
    GraspCellSpec base; ///< The default cell every sweep varies one factor of.
    /// Squeeze forces (N a hand); the default box's hold limit is m g / (2 mu_s) = 0.41 N.
    std::vector<double> squeezesN{0.2, 0.3, 0.35, 0.4, 0.45, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0};
    /// Masses (kg); at the default 1.5 N squeeze the hold limit is 2 mu_s F / g = 0.18 kg.
    std::vector<double> massesKg{0.01, 0.02, 0.05, 0.1, 0.15, 0.2, 0.3};
    std::vector<double> stiffnessesNPerM{300.0, 1000.0, 3000.0, 10000.0}; ///< Stiffness (N/m).
    std::vector<double> ratesHz{500.0, 1000.0, 2000.0, 4000.0, 8000.0};   ///< Servo rates (Hz).
};

/// The smoke subset --quick runs: the default cell and one squeeze below the hold limit
/// (0.3 N), one run each, every other factor at its default; `common.quick` set, so the
/// report's header says it is the subset. [any thread]
GraspArgs quickGraspArgs(GraspArgs args);

/// Runs the cells `args` lists (as given: quickGraspArgs makes the smoke subset) into
/// `args.common.out` and prints its markdown; returns the
/// process exit code, 0 (a disagreement with the analytic rule is a result, said in the
/// summary, not a failure). Throws InputError for a list value a cell cannot run. [control]
int runGrasp(const GraspArgs& args);

} // namespace hapto::experiments
