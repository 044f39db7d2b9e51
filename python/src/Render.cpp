// render() (a point path through the haptic tick, experiments::renderPath) and read_trace()
// (a trace file as the columns of `hapto trace export`: a device's, TraceColumns.h, or the
// dynamic bodies' bodies.trace, BodyTrace.h, told apart by its magic as the command does), for
// Python.

#include "Bindings.h"

#include "hapto/devices/TraceColumns.h"
#include "hapto/devices/TraceReader.h"
#include "hapto/experiments/RenderPath.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/runtime/World.h"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <optional>

namespace hapto::python {
namespace {

using Points = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// The rendered ticks as `hapto render`'s columns (renderPathColumns' order).
py::dict renderColumns(const std::vector<experiments::PathTick>& ticks) {
    const std::size_t n = ticks.size();
    const auto names = experiments::renderPathColumns();
    auto tick = column<std::uint64_t>(n);
    auto contacts = column<std::uint32_t>(n);
    std::vector<py::array_t<double>> xyz;
    for (int k = 0; k < 9; ++k) {
        xyz.push_back(column<double>(n));
    }
    for (std::size_t i = 0; i < n; ++i) {
        const experiments::PathTick& t = ticks[i];
        tick.mutable_at(i) = i;
        for (int a = 0; a < 3; ++a) {
            xyz[a].mutable_at(i) = t.pointM[a];
            xyz[3 + a].mutable_at(i) = t.proxyM[a];
            xyz[6 + a].mutable_at(i) = t.forceN[a];
        }
        contacts.mutable_at(i) = t.contacts;
    }
    py::dict out;
    out[py::str(names[0].data(), names[0].size())] = tick;
    for (int k = 0; k < 9; ++k) {
        out[py::str(names[1 + k].data(), names[1 + k].size())] = xyz[k];
    }
    out[py::str(names[10].data(), names[10].size())] = contacts;
    return out;
}

/// The snapshot to render over: a given index's (it must be over this scene) or a world built
/// with the spec text (empty: the default index), as `hapto render --index` does.
std::vector<experiments::PathTick> renderOver(const PyScene& scene, const std::vector<Vec3>& path,
                                              const py::object& index, double rateHz,
                                              std::uint64_t maxIndexMb) {
    if (!index.is_none() && py::isinstance<PyIndex>(index)) {
        const PyIndex& built = index.cast<const PyIndex&>();
        if (built.scene != scene.scene) {
            throw InputError("index: built over another scene; build_index(scene) first, or "
                             "pass index=None or a spec text");
        }
        WorldSnapshot snapshot;
        snapshot.version = 1;
        snapshot.scene = built.scene;
        snapshot.index = built.index;
        py::gil_scoped_release release;
        return experiments::renderPath(snapshot, path, rateHz);
    }
    const std::string text = index.is_none() ? std::string() : index.cast<std::string>();
    const IndexSpec spec = sessionIndexSpec(text, *scene.scene, maxIndexMb);
    py::gil_scoped_release release;
    const World world(scene.scene, spec);
    return experiments::renderPath(world.current(), path, rateHz);
}

py::dict render(const PyScene& scene, const Points& points, const py::object& index, double rateHz,
                std::uint64_t maxIndexMb) {
    if (!(std::isfinite(rateHz) && rateHz >= 100 && rateHz <= 100000)) {
        throw InputError("rate_hz " + std::to_string(rateHz) +
                         ": expected a tick rate from 100 to 100000 Hz");
    }
    const std::vector<Vec3> path = pointsFrom(points, "points");
    if (path.empty()) {
        throw InputError("points: no points; give one point x, y, z (m, world frame) per tick");
    }
    return renderColumns(renderOver(scene, path, index, rateHz, maxIndexMb));
}

/// A body trace's samples as the columns of `hapto trace export` for it (bodyTraceCsvHeader:
/// time_s,id,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz).
py::dict bodyTraceColumns(const BodyTrace& trace) {
    const std::size_t n = trace.samples.size();
    auto time = column<double>(n);
    auto id = column<std::uint32_t>(n);
    std::vector<py::array_t<double>> values;
    for (int k = 0; k < 13; ++k) {
        values.push_back(column<double>(n));
    }
    for (std::size_t i = 0; i < n; ++i) {
        const BodyTraceSample& s = trace.samples[i];
        time.mutable_at(i) = static_cast<double>(s.timeNs) * 1e-9; // as the export prints it
        id.mutable_at(i) = trace.ids.at(s.body);
        const double v[13] = {s.centerOfMass.x,   s.centerOfMass.y,    s.centerOfMass.z,
                              s.rotation.w,       s.rotation.x,        s.rotation.y,
                              s.rotation.z,       s.velocity.x,        s.velocity.y,
                              s.velocity.z,       s.angularVelocity.x, s.angularVelocity.y,
                              s.angularVelocity.z};
        for (int k = 0; k < 13; ++k) {
            values[k].mutable_at(i) = v[k];
        }
    }
    static const char* const kNames[13] = {"x",  "y",  "z",  "qw", "qx", "qy", "qz",
                                           "vx", "vy", "vz", "wx", "wy", "wz"};
    py::dict out;
    out["time_s"] = time;
    out["id"] = id;
    for (int k = 0; k < 13; ++k) {
        out[kNames[k]] = values[k];
    }
    return out;
}

/// A trace's samples as the columns of `hapto trace export` for its version (a body trace:
/// bodyTraceColumns).
py::dict readTrace(const std::filesystem::path& path) {
    if (isBodyTrace(path)) {
        BodyTrace trace;
        {
            py::gil_scoped_release release;
            trace = readBodyTrace(path);
        }
        return bodyTraceColumns(trace);
    }
    TraceHeader header;
    std::vector<TraceSample> samples;
    {
        py::gil_scoped_release release;
        samples = TraceReader::load(path, &header);
    }
    const std::size_t n = samples.size();
    py::dict out;
    for (const TraceColumn& c : traceColumns(header.version)) {
        const py::str name(c.name.data(), c.name.size());
        if (c.type == TraceColumnType::Real) {
            auto a = column<double>(n);
            for (std::size_t i = 0; i < n; ++i) {
                a.mutable_at(i) = c.real(samples[i]);
            }
            out[name] = a;
        } else if (c.type == TraceColumnType::Integer) {
            auto a = column<std::uint64_t>(n);
            for (std::size_t i = 0; i < n; ++i) {
                a.mutable_at(i) = c.integer(samples[i]);
            }
            out[name] = a;
        } else {
            py::list names;
            for (const TraceSample& s : samples) {
                const std::string_view text = statusName(s.status);
                names.append(py::str(text.data(), text.size()));
            }
            out[name] = py::module_::import("numpy").attr("array")(names, "str");
        }
    }
    return out;
}

/// What a trace says about itself (`hapto trace info`), as a dict; a body trace's: its
/// kind "bodies", dynamics rate, body ids and sample count.
py::dict traceHeader(const std::filesystem::path& path) {
    if (isBodyTrace(path)) {
        const BodyTrace trace = readBodyTrace(path);
        py::dict out;
        out["kind"] = "bodies";
        out["rate_hz"] = trace.rateHz;
        out["ids"] = py::cast(trace.ids);
        out["samples"] = trace.samples.size();
        return out;
    }
    const TraceReader reader(path);
    const TraceHeader& h = reader.header();
    py::dict out;
    out["version"] = h.version;
    out["name"] = h.name;
    out["kind"] = h.kind;
    out["rate_hz"] = h.rateHz;
    out["samples"] = h.sampleCount;
    out["finished"] = h.finished;
    out["start_unix_ns"] = h.startUnixNs;
    if (h.hasConfiguration()) {
        const WorkspaceTransform& t = h.transform;
        out["translation_m"] = py::make_tuple(t.translation.x, t.translation.y, t.translation.z);
        out["rotation"] = py::make_tuple(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
        out["scale"] = t.scale;
        out["tool_tip_m"] = py::make_tuple(h.toolTipM.x, h.toolTipM.y, h.toolTipM.z);
        out["max_force_n"] = h.maxForceN;
    }
    return out;
}

} // namespace

void bindRender(py::module_& m) {
    m.def("render", &render, py::arg("scene"), py::arg("points"), py::arg("index") = py::none(),
          py::arg("rate_hz") = 1000.0, py::arg("max_index_mb") = IndexSpec::kDefaultMaxMegabytes,
          "One device point along a path through the haptic tick: hapto render's columns");
    m.def("read_trace", &readTrace, py::arg("path"),
          "A trace file's samples as hapto trace export's columns");
    m.def("trace_header", &traceHeader, py::arg("path"), "A trace file's header");
}

} // namespace hapto::python
