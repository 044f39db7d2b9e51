#pragma once
// What the binding files of the _hapto extension share: the scene and index handles Python
// holds, the (N, 3) points conversion, and each file's bind function.
//
// Design note. Python never holds a bare C++ object: a scene is a shared_ptr<const Scene>
// (immutable once made, shared with the worlds and indices built over it), an index holds its
// scene too, so either outlives whatever Python drops first. Bad input from Python (a shape,
// a NaN, an option out of range) is an InputError like the command's, so it arrives as
// hapto.InputError (a ValueError) with the same kind of message.

#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/Scene.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

namespace hapto::python {

namespace py = pybind11;

/// A scene as Python holds it.
struct PyScene {
    std::shared_ptr<const Scene> scene; ///< Never null.
};

/// A built index as Python holds it, with the scene it was built over.
struct PyIndex {
    std::shared_ptr<const Scene> scene;        ///< The scene indexed.
    std::shared_ptr<const SpatialIndex> index; ///< Never null.
};

/// An (N, 3) array of finite doubles (m) as points; InputError naming `what` otherwise.
std::vector<Vec3>
pointsFrom(const py::array_t<double, py::array::c_style | py::array::forcecast>& points,
           const std::string& what);

/// A numpy array of `n` doubles, uint64s or uint32s to fill.
template <class T> py::array_t<T> column(std::size_t n) {
    return py::array_t<T>(static_cast<py::ssize_t>(n));
}

/// Scenes, generators and indices (Scenes.cpp).
void bindScenes(py::module_& m);
/// render() and read_trace() (Render.cpp).
void bindRender(py::module_& m);
/// Session (Session.cpp).
void bindSession(py::module_& m);
/// The experiments (Experiments.cpp).
void bindExperiments(py::module_& m);
/// The grasp experiment (GraspExperiment.cpp).
void bindGraspExperiment(py::module_& m);

} // namespace hapto::python
