// Scenes (files and the seeded generators) and spatial indices, for Python.

#include "Bindings.h"

#include "hapto/index/Cursor.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/io/InputError.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/SceneFile.h"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <optional>
#include <utility>

namespace hapto::python {
namespace {

PyScene share(Scene scene) {
    return {std::make_shared<const Scene>(std::move(scene))};
}

py::tuple bounds(const Aabb& b) {
    return py::make_tuple(py::make_tuple(b.min.x, b.min.y, b.min.z),
                          py::make_tuple(b.max.x, b.max.y, b.max.z));
}

/// `hapto query`'s answer as columns, one row per candidate: the point's number, the object's
/// id and, for a mesh triangle, its number in the mesh (-1: the whole object); per point
/// sorted by id, then triangle.
py::dict query(const PyIndex& self,
               const py::array_t<double, py::array::c_style | py::array::forcecast>& points) {
    const std::vector<Vec3> ps = pointsFrom(points, "points");
    const Scene& scene = *self.scene;
    std::vector<std::uint64_t> point;
    std::vector<std::pair<ObjectId, std::int64_t>> rows, ids;
    Cursor cursor(*self.index);
    for (std::size_t i = 0; i < ps.size(); ++i) {
        ids.clear();
        for (const std::uint32_t item : cursor.locate(ps[i]).candidates) {
            if (isTriangleItem(item)) {
                const TriangleRef t = scene.triangle(item);
                ids.emplace_back(scene.object(t.objectSlot).id, t.triangle);
            } else {
                ids.emplace_back(scene.object(item).id, -1);
            }
        }
        std::sort(ids.begin(), ids.end());
        rows.insert(rows.end(), ids.begin(), ids.end());
        point.insert(point.end(), ids.size(), i);
    }
    auto p = column<std::uint64_t>(rows.size());
    auto id = column<std::uint32_t>(rows.size());
    auto tri = column<std::int64_t>(rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
        p.mutable_at(k) = point[k];
        id.mutable_at(k) = rows[k].first;
        tri.mutable_at(k) = rows[k].second;
    }
    py::dict out;
    out["point"] = p;
    out["id"] = id;
    out["triangle"] = tri;
    return out;
}

void bindSceneClass(py::module_& m) {
    py::class_<PyScene>(m, "Scene", "A scene: objects in metres, y up (immutable)")
        .def("__len__", [](const PyScene& s) { return s.scene->size(); })
        .def_property_readonly(
            "bounds", [](const PyScene& s) { return bounds(s.scene->bounds()); },
            "The work volume ((min x, y, z), (max x, y, z)) in m")
        .def_property_readonly(
            "ids",
            [](const PyScene& s) {
                auto ids = column<std::uint32_t>(s.scene->size());
                for (std::uint32_t i = 0; i < s.scene->size(); ++i) {
                    ids.mutable_at(i) = s.scene->object(i).id;
                }
                return ids;
            },
            "The objects' ids, in slot order");
    m.def(
        "load_scene", [](const std::filesystem::path& path) { return share(loadSceneFile(path)); },
        py::arg("path"), "A scene file (JSON, format hapto-scene); InputError naming the place");
}

void bindGenerators(py::module_& m) {
    m.def(
        "lattice_scene",
        [](int perSide, double cubeSize, double gap) {
            return share(makeLatticeScene({perSide, cubeSize, gap}));
        },
        py::arg("per_side") = 3, py::arg("cube_size") = 0.05, py::arg("gap") = 0.01);
    m.def(
        "random_scene",
        [](std::size_t count, std::uint64_t seed, double workspace, double cubeSize, bool rotate,
           double keepClear) {
            return share(makeRandomScene({count, seed, workspace, cubeSize, rotate, keepClear}));
        },
        py::arg("count") = 200, py::arg("seed") = 1, py::arg("workspace") = 0.25,
        py::arg("cube_size") = 0.05, py::arg("rotate") = false, py::arg("keep_clear") = 0.0);
    m.def(
        "cluster_scene",
        [](std::size_t count, int clusters, std::uint64_t seed, double workspace, double cubeSize,
           double spread, bool rotate) {
            return share(
                makeClusterScene({count, clusters, seed, workspace, cubeSize, spread, rotate}));
        },
        py::arg("count") = 1000, py::arg("clusters") = 8, py::arg("seed") = 1,
        py::arg("workspace") = 0.25, py::arg("cube_size") = 0.005, py::arg("spread") = 0.01,
        py::arg("rotate") = false);
    m.def("grasp_scene", [] { return share(makeGraspScene()); });
    m.def(
        "dynamic_grasp_scene",
        [](const std::string& shape) {
            const std::optional<GraspObject> object = parseGraspObject(shape);
            if (!object) {
                throw InputError("shape '" + shape +
                                 "': expected the object to grasp: box, sphere or mesh");
            }
            return share(makeDynamicGraspScene(*object));
        },
        py::arg("shape") = "box",
        "The physical grasp demo's scene: a dynamic 100 g box, sphere or mesh on a floor");
    m.def("default_scene", [] { return share(makeDefaultScene()); });
}

void bindIndex(py::module_& m) {
    py::class_<PyIndex>(m, "Index", "A spatial index built over a scene (immutable)")
        .def_property_readonly("spec", [](const PyIndex& i) { return i.index->spec().toString(); })
        .def_property_readonly("scene", [](const PyIndex& i) { return PyScene{i.scene}; })
        .def_property_readonly("leaves", [](const PyIndex& i) { return i.index->stats().leaves; })
        .def_property_readonly("bytes", [](const PyIndex& i) { return i.index->stats().bytes; })
        .def("query", &query, py::arg("points"),
             "Candidates of each point of an (N, 3) array: columns point, id, triangle");
    m.def(
        "build_index",
        [](const PyScene& scene, const std::string& spec, std::uint64_t maxIndexMb) {
            const IndexSpec s = sessionIndexSpec(spec, *scene.scene, maxIndexMb);
            std::shared_ptr<const SpatialIndex> index;
            {
                py::gil_scoped_release release;
                index = buildIndex(*scene.scene, s);
            }
            return PyIndex{scene.scene, std::move(index)};
        },
        py::arg("scene"), py::arg("spec") = "",
        py::arg("max_index_mb") = IndexSpec::kDefaultMaxMegabytes,
        "Builds an index (spec text such as 'grid:5' or 'octree:2:0.005'; empty: the default)");
}

} // namespace

void bindScenes(py::module_& m) {
    bindSceneClass(m);
    bindGenerators(m);
    bindIndex(m);
}

} // namespace hapto::python
