// `hapto experiment grasp` for Python (experiments::runGrasp): two simulated hands grasp, lift
// and carry a dynamic box in step mode, swept one factor at a time. It writes its files (CSV,
// JSON, markdown, plots) into a folder as the command does; the hapto package reads the table
// back from grasp.json as columns. The GIL is released while it runs.
//
// Design note. The lists and `quick` follow the command: quick runs quickGraspArgs' smoke
// subset, and a list given explicitly (non-empty here) replaces the subset's or the default's,
// as an option given on the command line does. An empty list means "not given". Values a cell
// cannot run arrive as InputError from runGrasp (hapto.InputError in Python).

#include "Bindings.h"

#include "hapto/experiments/GraspExperiment.h"
#include "hapto/io/InputError.h"

#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <vector>

namespace hapto::python {
namespace {

/// The lists a caller may give; empty: not given.
struct GraspLists {
    std::vector<double> squeezesN, massesKg, stiffnessesNPerM, ratesHz;
};

int runGraspInto(const std::string& out, bool quick, const GraspLists& lists,
                 std::optional<int> repeats) {
    experiments::GraspArgs a;
    a.common.out = out;
    if (quick) {
        a = experiments::quickGraspArgs(a);
    }
    const auto keep = [](std::vector<double>& to, const std::vector<double>& given) {
        if (!given.empty()) {
            to = given;
        }
    };
    keep(a.squeezesN, lists.squeezesN);
    keep(a.massesKg, lists.massesKg);
    keep(a.stiffnessesNPerM, lists.stiffnessesNPerM);
    keep(a.ratesHz, lists.ratesHz);
    if (repeats && *repeats < 1) {
        throw InputError("repeats " + std::to_string(*repeats) +
                         ": expected at least 1 run per cell");
    }
    if (repeats) {
        a.common.repeats = *repeats;
    }
    py::gil_scoped_release release;
    return experiments::runGrasp(a);
}

} // namespace

void bindGraspExperiment(py::module_& m) {
    m.def(
        "run_grasp",
        [](const std::string& out, bool quick, const std::vector<double>& squeezes,
           const std::vector<double>& masses, const std::vector<double>& stiffnesses,
           const std::vector<double>& rates, std::optional<int> repeats) {
            return runGraspInto(out, quick, {squeezes, masses, stiffnesses, rates}, repeats);
        },
        py::arg("out"), py::arg("quick") = false, py::arg("squeezes_n") = std::vector<double>{},
        py::arg("masses_kg") = std::vector<double>{},
        py::arg("stiffnesses_n_per_m") = std::vector<double>{},
        py::arg("rates_hz") = std::vector<double>{}, py::arg("repeats") = py::none(),
        "hapto experiment grasp into the folder `out`; returns its exit code");
}

} // namespace hapto::python
