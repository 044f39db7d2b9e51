// The _hapto extension module: the version, the error type, and each part's bindings.
//
// Errors: hapto's InputError (bad input: a file, an argument, a value) becomes
// hapto.InputError, a subclass of ValueError, carrying the message the `hapto` command prints
// after "hapto: "; any other std::exception becomes RuntimeError (pybind11's rule), the
// message the command prints after "hapto: error: ".

#include "Bindings.h"

#include "hapto/Version.h"
#include "hapto/io/InputError.h"

namespace hapto::python {

std::vector<Vec3>
pointsFrom(const py::array_t<double, py::array::c_style | py::array::forcecast>& points,
           const std::string& what) {
    if (points.ndim() != 2 || points.shape(1) != 3) {
        std::string shape;
        for (py::ssize_t d = 0; d < points.ndim(); ++d) {
            shape += (d ? ", " : "") + std::to_string(points.shape(d));
        }
        throw InputError(what + ": expected an (N, 3) array of points x, y, z (m), got shape (" +
                         shape + ")");
    }
    const auto p = points.unchecked<2>();
    std::vector<Vec3> out(static_cast<std::size_t>(p.shape(0)));
    for (py::ssize_t i = 0; i < p.shape(0); ++i) {
        out[static_cast<std::size_t>(i)] = Vec3(p(i, 0), p(i, 1), p(i, 2));
        if (!std::isfinite(p(i, 0)) || !std::isfinite(p(i, 1)) || !std::isfinite(p(i, 2))) {
            throw InputError(what + "[" + std::to_string(i) +
                             "]: expected three finite numbers x, y, z in metres");
        }
    }
    return out;
}

} // namespace hapto::python

PYBIND11_MODULE(_hapto, m) {
    namespace hp = hapto::python;
    m.doc() = "hapto's library from Python (use the hapto package, not this module)";
    m.attr("__version__") = hapto::kVersion;
    pybind11::register_exception<hapto::InputError>(m, "InputError", PyExc_ValueError);
    hp::bindScenes(m);
    hp::bindRender(m);
    hp::bindSession(m);
    hp::bindExperiments(m);
    hp::bindGraspExperiment(m);
}
