#pragma once
/// The `hapto` command's subcommands: each file adds its own to the app.

#include "hapto/scenes/Scene.h"

#include <CLI/CLI.hpp>

#include <span>
#include <string>
#include <vector>

namespace hapto::experiments {
struct PlotSpec;
}

namespace hapto::cli {

/// `hapto scene ...`: generators and scene information. [control]
void addSceneCommands(CLI::App& app);

/// `hapto query` and `hapto index-stats`: build a spatial index, query it, describe it.
/// [control]
void addIndexCommands(CLI::App& app);

/// `hapto trace export|info|plot`: trace files as CSV, what they hold, and plots. [control]
void addTraceCommands(CLI::App& app);

/// `hapto report plot`: a `hapto run --report` JSON file drawn per device. [control]
void addReportCommands(CLI::App& app);

/// Where a plot command writes: the plot, OUT.png or OUT.svg, and optionally its gnuplot script.
struct PlotOutputs {
    std::string out;
    std::string script; ///< Empty: not kept.

    /// Refuses, before any work, a plot not ending in .png or .svg or not writable, a script
    /// that is the plot or not writable, and either being one of `inputs` (each called
    /// `inputName` in the message). Throws InputError. [control]
    void check(std::span<const std::string> inputs, const std::string& inputName) const;
    /// Draws `spec` there with gnuplot (atomically) and says so on standard error. [control]
    void draw(const experiments::PlotSpec& spec) const;
};

/// Adds the required `-o,--output OUT.png|OUT.svg` and `--script F` to a plot command.
/// [control]
void addPlotOutputOptions(CLI::App* cmd, PlotOutputs& outputs);

/// `hapto bench query` and `hapto bench tick`: per-query cost of indices and the servo tick's
/// stages along a hand-speed walk. [control]
void addBenchCommands(CLI::App& app);

/// `hapto demo grasp`: the scripted two-handed grasp. [control]
void addDemoCommands(CLI::App& app);

/// `hapto devices`: hardware found, or why none. [control]
void addDeviceCommands(CLI::App& app);

/// `hapto run`: a multi-device session with load report. [control]
void addRunCommands(CLI::App& app);

/// `hapto experiment paper1|paper2|devices`: the paper's experiments and load scaling,
/// written as CSV, JSON, markdown and plots. [control]
void addExperimentCommands(CLI::App& app);

/// `hapto experiment grasp` under `exp` (GraspExperimentCommand.cpp): two simulated hands grasp
/// a dynamic box in step mode; slip, penetration, energy, force error and step cost. [control]
void addGraspExperimentCommand(CLI::App* exp);

/// `hapto soak`: a long run with world updates and injected faults; drift, memory, misses.
/// [control]
void addSoakCommands(CLI::App& app);

/// `hapto render`: one device point along a path through the haptic tick, as CSV. [control]
void addRenderCommands(CLI::App& app);

/// `hapto view`: the 3-D view over a recorded session, in the browser. [control]
void addViewCommands(CLI::App& app);

/// Loads `path`, or the embedded default scene when it is empty. Throws InputError. [control]
Scene loadSceneOrDefault(const std::string& path);

/// Reads `x,y,z` lines (m), with an optional `x,y,z` header line; blank lines are skipped.
/// Only a regular file of at most kMaxInputFileBytes is read (InputFile, which names it as
/// `what`); a bad line is InputError naming path:line. [control]
std::vector<Vec3> readPoints(const std::string& path, const std::string& what);

} // namespace hapto::cli
