// The experiments, for Python: each runs as `hapto experiment <name>` does, writing its files
// (CSV, JSON, markdown, plots) into a folder; the hapto package reads the tables back as
// columns. The GIL is released while an experiment runs.

#include "Bindings.h"

#include "hapto/experiments/Experiments.h"

#include <pybind11/stl.h>

namespace hapto::python {
namespace {

experiments::CommonArgs common(const std::string& out, bool quick, double durationS, int repeats,
                               bool realtime) {
    experiments::CommonArgs c;
    c.out = out;
    c.quick = quick;
    c.durationS = durationS;
    c.repeats = repeats;
    c.realtime = realtime;
    return c;
}

int runDevices(const std::string& out, int maxDevices, const std::vector<double>& ratesHz,
               const std::string& scene, const std::string& index, const std::string& script,
               const std::vector<std::size_t>& cursorObjects, std::size_t walkSteps, bool cursor,
               bool quick, double durationS, int repeats, bool realtime,
               const std::vector<int>& counts) {
    experiments::DevicesArgs a;
    a.common = common(out, quick, durationS, repeats, realtime);
    a.maxDevices = maxDevices;
    a.deviceCounts = counts;
    a.ratesHz = ratesHz;
    a.scene = scene;
    a.index = index.empty() ? a.index : index;
    a.script = script;
    a.cursorObjects = cursorObjects;
    a.walkSteps = walkSteps;
    a.cursor = cursor;
    py::gil_scoped_release release;
    return experiments::runDevices(a);
}

} // namespace

void bindExperiments(py::module_& m) {
    const experiments::DevicesArgs d;
    m.def("run_devices", &runDevices, py::arg("out"), py::arg("max_devices") = d.maxDevices,
          py::arg("rates_hz") = d.ratesHz, py::arg("scene") = "", py::arg("index") = "",
          py::arg("script") = d.script, py::arg("cursor_objects") = d.cursorObjects,
          py::arg("walk_steps") = d.walkSteps, py::arg("cursor") = d.cursor,
          py::arg("quick") = false, py::arg("duration_s") = d.common.durationS,
          py::arg("repeats") = d.common.repeats, py::arg("realtime") = d.common.realtime,
          py::arg("counts") = d.deviceCounts,
          "hapto experiment scaling into the folder `out`; returns its exit code");
}

} // namespace hapto::python
