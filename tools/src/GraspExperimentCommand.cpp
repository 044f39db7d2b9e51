// `hapto experiment grasp`: its options, parsed into experiments::GraspArgs; the experiment
// itself is experiments::runGrasp (GraspExperiment.h). The sweep lists are read by
// parseSweepList (Stats.h), so they take the forms every experiment list takes.

#include "Commands.h"
#include "Options.h"

#include "hapto/experiments/GraspExperiment.h"
#include "hapto/experiments/Stats.h"
#include "hapto/experiments/Table.h"

#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace hapto::cli {
namespace {

using namespace hapto::experiments;

/// The grasp command's parsed text: the sweep lists, read after parsing.
struct GraspOptions {
    std::string squeezes, masses, stiffnesses, rates;
    CLI::Option *squeezesOpt = nullptr, *massesOpt = nullptr, *stiffnessesOpt = nullptr,
                *ratesOpt = nullptr, *repeats = nullptr;
};

CLI::Option* addList(CLI::App* cmd, std::string& text, const std::vector<double>& values,
                     const std::string& name, const std::string& help) {
    text = sweepListText(values);
    return cmd->add_option(name, text, help + "; a list: 1,2,4 or A:B:STEP")->capture_default_str();
}

std::vector<double> listOf(const std::string& text, const std::string& name, double min,
                           double max) {
    SweepListRule rule;
    rule.min = min;
    rule.max = max;
    rule.whole = false;
    rule.maxItems = 100;
    return parseSweepList(text, name, rule);
}

void addGraspOptions(CLI::App* cmd, GraspArgs& a, GraspOptions& o) {
    a.common.out = "out/grasp";
    a.common.repeats = 5; // [min, max] of 5 runs holds the step cost's median at 93.75 %
    cmd->add_option("--out", a.common.out,
                    "Folder for the CSV, JSON, markdown and plot files (created)")
        ->capture_default_str();
    cmd->add_flag("--quick", a.common.quick,
                  "A smoke test of seconds: the default cell and a 0.3 N squeeze (below the hold "
                  "limit), one run each; the report says it is the smoke subset");
    o.repeats = cmd->add_option("--repeats", a.common.repeats,
                                "Runs per cell: the physical figures are the same in every run "
                                "(checked); the step's CPU time is reported as the median over "
                                "the runs with its order-statistic interval; --quick: 1")
                    ->capture_default_str()
                    ->check(finiteRange(1, 99));
    o.squeezesOpt = addList(cmd, o.squeezes, a.squeezesN, "--squeezes",
                            "Squeeze forces, each hand (N, 0..20); --quick: 0.3,1.5");
    o.massesOpt =
        addList(cmd, o.masses, a.massesKg, "--masses", "Box masses (kg, 0.001..10); --quick: 0.05");
    o.stiffnessesOpt = addList(cmd, o.stiffnesses, a.stiffnessesNPerM, "--stiffnesses",
                               "Box surface stiffness as rendered (N/m, 10..1e5); --quick: 1000");
    o.ratesOpt = addList(cmd, o.rates, a.ratesHz, "--rates",
                         "Servo rates (Hz); periods must be whole ns and multiples of the "
                         "shorter of servo and dynamics period (500, 1000, 2000, 4000, 8000 "
                         "...); --quick: 1000");
}

} // namespace

void addGraspExperimentCommand(CLI::App* exp) {
    auto a = std::make_shared<GraspArgs>();
    auto o = std::make_shared<GraspOptions>();
    auto* cmd = exp->add_subcommand(
        "grasp",
        "Two simulated hands (the grasp scripts) squeeze, lift 5 cm and carry 10 cm a dynamic "
        "4 cm box on a floor, in step mode (deterministic). Per cell: slip of the box against "
        "the hands (max, final), deepest penetration, largest energy gain, |hands' vertical "
        "force - m g| / m g (median, worst), held or dropped against the analytic rule "
        "mu_s (F1 + F2) >= m g, and the dynamics step's CPU time (p50, p99.9; a timing). "
        "Swept one factor at a time around a default cell: squeeze force, mass, stiffness, "
        "servo rate");
    addGraspOptions(cmd, *a, *o);
    setExamples(cmd, {"hapto experiment grasp --quick",
                      "hapto experiment grasp --squeezes 0.4:0.5:0.02 --masses 0.05 --repeats 9"});
    cmd->callback([a, o] {
        a->squeezesN = listOf(o->squeezes, "--squeezes", 0.0, 20.0);
        a->massesKg = listOf(o->masses, "--masses", 0.001, 10.0);
        a->stiffnessesNPerM = listOf(o->stiffnesses, "--stiffnesses", 10.0, 1e5);
        a->ratesHz = listOf(o->rates, "--rates", 100.0, 100000.0);
        GraspArgs run = *a;
        if (a->common.quick) { // the smoke subset; options given explicitly still apply
            run = quickGraspArgs(*a);
            const auto keep = [](CLI::Option* opt, auto& to, const auto& from) {
                if (opt->count() > 0) {
                    to = from;
                }
            };
            keep(o->squeezesOpt, run.squeezesN, a->squeezesN);
            keep(o->massesOpt, run.massesKg, a->massesKg);
            keep(o->stiffnessesOpt, run.stiffnessesNPerM, a->stiffnessesNPerM);
            keep(o->ratesOpt, run.ratesHz, a->ratesHz);
            keep(o->repeats, run.common.repeats, a->common.repeats);
        }
        const int rc = runGrasp(run);
        if (rc != 0) {
            std::exit(rc);
        }
    });
}

} // namespace hapto::cli
