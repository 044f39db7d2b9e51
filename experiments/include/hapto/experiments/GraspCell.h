#pragma once
/// One cell of `hapto experiment grasp`: two simulated hands grasp, lift and carry a dynamic box
/// in the runtime's step mode, and what that achieved (GraspProbe) and cost.
///
/// Design note. The scene is built in code (scene format version 3): a static floor, its top at
/// y = 0, and one dynamic box resting on it, of the cell's mass, friction and surface stiffness
/// (the stiffness the god-object renderer renders it with: Material::stiffness, N/m). Two
/// simulated hands run the grasp scripts (grasp-left from -x, grasp-right from +x; SimScript's
/// planGrasp on GraspTimes' fixed timetable), each pressing with SimConfig::pressForceN, the
/// squeeze. The Runtime runs in step mode on a ManualClock: its dynamics step due at t before
/// the servo ticks due at t, so every figure but the step's cost is the same every run. The
/// session is driven in increments of the shortest period (servo or dynamics; the rates offered
/// divide 1 s into whole nanoseconds that are multiples of it), so each increment holds at most
/// one event instant. Measured after each dynamics step: the slip and held/dropped (GraspProbe)
/// from the end of the squeeze (GraspTimes::kSqueezeEnd) to the end of the carry (kCarryEnd);
/// the hands' vertical force against m g while the box is up, from the end of the lift
/// (kLiftEnd) to kCarryEnd (a horizontal carry: no vertical acceleration asked for, so the hands
/// should carry exactly m g); the deepest penetration and the largest energy gain of the body
/// from the run report.
///
/// The step's cost. In step mode the runtime measures its steps on the ManualClock, so its
/// report says 0; the cell measures instead the CPU time of the stepping thread
/// (CLOCK_THREAD_CPUTIME_ID) from the start of the increment to the first hand's read() in
/// it, which the step mode runs right after the dynamics step (Runtime::stepAll: the step, then
/// the ticks in device order, each beginning with its read). That is the step with its impulse
/// intake and pose publication, the span the threaded runtime's report measures, plus a few
/// atomics. It is a timing: it varies from run to run, unlike everything else here.

#include "hapto/core/Geometry.h"
#include "hapto/experiments/GraspProbe.h"

#include <cstdint>
#include <vector>

namespace hapto::experiments {

/// What one cell runs.
struct GraspCellSpec {
    double squeezeN = 1.5;          ///< Each hand's press force (N): SimConfig::pressForceN.
    double massKg = 0.05;           ///< The box's mass (kg).
    double stiffnessNPerM = 1000.0; ///< The box's surface stiffness, as rendered (N/m).
    double servoRateHz = 1000.0;    ///< Both hands' servo rate (Hz).
    double dynamicsRateHz = 1000.0; ///< The dynamics step rate (Hz).
    double staticFriction = 0.6;    ///< mu_s of the box and the floor (the pair's smaller).
    double dynamicFriction = 0.5;   ///< mu_d of the box and the floor.
    double halfExtentM = 0.02;      ///< The box's half side (m): a 4 cm cube.
    std::uint64_t seed = 1;         ///< The hands' seeds are seed and seed + 1.
};

/// Refuses a spec the cell cannot run, naming the field (std::invalid_argument): every value
/// finite and > 0 (the squeeze >= 0), a servo and a dynamics rate whose periods are whole
/// nanoseconds and multiples of the shorter one. [any thread]
void checkGraspCellSpec(const GraspCellSpec& spec);

/// mu_s (F1 + F2) / (m g): the analytic hold margin; the box holds iff it is >= 1. [any thread]
double graspHoldMargin(const GraspCellSpec& spec, double gravityMPerS2 = 9.81);

/// The slip of a held box that the rendering itself predicts (m): each hand carries m g / 2
/// by static friction, which the god-object renders as the stiffness k times the tangential
/// offset of the device point from its anchored proxy, so the box settles m g / (2 k) lower
/// relative to the hands than when it rested. [any thread]
double graspElasticSlipM(const GraspCellSpec& spec, double gravityMPerS2 = 9.81);

/// What one cell measured.
struct GraspCellResult {
    /// Slip and held over squeeze end..carry end, force error over lift end..carry end.
    GraspFigures grasp;
    double deepestPenetrationM = 0.0; ///< The body's deepest overlap with anything (m).
    double largestEnergyGainJ = 0.0;  ///< The body's largest energy rise with no work (J).
    double liftM = 0.0;               ///< The body's rise from its rest height at kCarryEnd (m).
    /// The squeeze the hands exert at the window's start (kSqueezeEnd): the mean of the two sent
    /// forces' components along the grasp axis, into the box (N).
    double squeezeFeltN = 0.0;
    /// When the slip first passed 1 mm (issue 37's bound for a held body), in session time
    /// (s; the lift starts at GraspTimes::kSqueezeEnd, 4.5 s); -1 when it never did.
    double slipOnsetS = -1.0;
    std::uint64_t dynamicsSteps = 0;   ///< Dynamics steps run.
    bool stable = false;               ///< The run report's verdict (devices and dynamics).
    std::uint64_t zeroedForMisses = 0; ///< Both hands' ticks zeroed for misses (0 stepped).
    std::vector<double> stepCpuNs;     ///< CPU time of every dynamics step (ns): a timing.
};

/// Runs one cell (about 7 s of simulated time, stepped). Throws std::invalid_argument for a
/// bad spec, std::runtime_error when a hand does not open. [control]
GraspCellResult runGraspCell(const GraspCellSpec& spec);

/// True when two results of the same spec agree in every field but the step's timing, bit for
/// bit: what step mode promises. [any thread]
bool sameGraspFigures(const GraspCellResult& a, const GraspCellResult& b);

} // namespace hapto::experiments
