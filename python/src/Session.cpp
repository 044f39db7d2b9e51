// hapto.Session: a Runtime driven by a hapto::Session over a shared world, from Python.
//
// Design note. The object owns, in this order, the step clock, the world, the runtime and the
// session, so they are destroyed the other way round: the session stops first (zero force on
// every device, then the report), and no device outlives the world it reads. The devices open
// at the first run() or step(). While the session runs, the GIL is released (other Python
// threads go on); once per control step the loop takes the GIL back only to look for a
// pending signal (Ctrl-C): a signal stops the session, leaving every device at zero force,
// and then raises in Python (KeyboardInterrupt). In step mode the control period is one
// period of the fastest device, so step(n) runs n of its ticks (each other device the ticks
// due in that time), and the result is the same every run; with no device (a scene with
// dynamic bodies, devices=[] as `hapto run --no-devices`) it is one dynamics period.
//
// Bodies. bodies() copies every dynamic body's latest published pose from the runtime's
// lock-free table (Runtime::bodyPoses) into numpy columns; the table holds the scene's poses
// only from the first run() or step() on (step 0 is published at start), so before that
// bodies() refuses. record=DIR writes DIR/bodies.trace with the library's BodyTraceRecorder,
// the call `hapto run --record` makes; the devices' traces are not written from Python: their
// header is made by tools/src/SessionRecorders.cpp (recorderFor), which the library lacks.

#include "Bindings.h"

#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/Session.h"
#include "hapto/runtime/World.h"

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace hapto::python {
namespace {

/// Where a session's devices come from: JSON text (Python's list of dicts, as a device file),
/// a device file, none (`noDevices`), or neither (the main job's two simulated hands).
DeviceFile deviceFileOf(const std::string& json, const std::string& path, bool noDevices) {
    if (noDevices) {
        return DeviceFile{{}, {}};
    }
    if (!json.empty()) {
        return parseDeviceFile(json, "devices");
    }
    if (!path.empty()) {
        return loadDeviceFile(path);
    }
    return DeviceFile{defaultDeviceConfigs(), {}};
}

/// The session's settings from Python.
struct SessionArgs {
    std::string devicesJson; ///< A device file's text; empty: devicesPath or the default.
    std::string devicesPath; ///< A device file; empty: the default hands.
    bool stepped = false;    ///< Step mode.
    std::string index;       ///< Index spec text; empty: the default.
    std::uint64_t maxIndexMb = IndexSpec::kDefaultMaxMegabytes; ///< Index memory limit (MB).
    double rateHz = 0;                                          ///< > 0: every device's rate.
    bool realtime = false;  ///< Ask for SCHED_FIFO and pinning (the command's default is on).
    bool noDevices = false; ///< No device: only the dynamics runs (`hapto run --no-devices`).
    std::string record;     ///< Non-empty: write <record>/bodies.trace.
};

/// The bodies' latest poses as numpy columns, one row per body in body order; time_s counts from
/// `startNs` (the runtime's clock at the start).
py::dict bodyColumns(const BodyPoseTable& table, std::span<const ObjectId> ids,
                     std::uint64_t startNs) {
    const std::size_t n = table.size();
    auto id = column<std::uint32_t>(n);
    auto step = column<std::uint64_t>(n);
    auto time = column<double>(n);
    auto sleeping = column<bool>(n);
    py::array_t<double> center({n, std::size_t{3}}), com({n, std::size_t{3}}),
        rotation({n, std::size_t{4}}), velocity({n, std::size_t{3}}), angular({n, std::size_t{3}});
    for (std::size_t i = 0; i < n; ++i) {
        const BodyPose p = table.read(i);
        id.mutable_at(i) = ids[i];
        step.mutable_at(i) = p.step;
        time.mutable_at(i) = static_cast<double>(p.timeNs - startNs) * 1e-9; // as the trace
        sleeping.mutable_at(i) = p.sleeping;
        for (int k = 0; k < 3; ++k) {
            center.mutable_at(i, k) = p.center[k];
            com.mutable_at(i, k) = p.centerOfMass[k];
            velocity.mutable_at(i, k) = p.velocity[k];
            angular.mutable_at(i, k) = p.angularVelocity[k];
        }
        const double q[4] = {p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z};
        for (int k = 0; k < 4; ++k) {
            rotation.mutable_at(i, k) = q[k];
        }
    }
    py::dict out;
    out["id"] = id;
    out["center"] = center;
    out["rotation"] = rotation;
    out["center_of_mass"] = com;
    out["velocity"] = velocity;
    out["angular_velocity"] = angular;
    out["sleeping"] = sleeping;
    out["time_s"] = time;
    out["step"] = step;
    return out;
}

class PySession {
public:
    PySession(const PyScene& scene, const SessionArgs& a) : mStepped(a.stepped) {
        DeviceFile file = deviceFileOf(a.devicesJson, a.devicesPath, a.noDevices);
        checkDevices(file.devices, a);
        checkAgainstScene(*scene.scene, a);
        mWorld = std::make_unique<World>(scene.scene,
                                         sessionIndexSpec(a.index, *scene.scene, a.maxIndexMb));
        if (mStepped) {
            mWorld->useClock(mClock);
        }
        double fastestHz = 0;
        std::vector<RuntimeDevice> devices;
        for (std::size_t i = 0; i < file.devices.size(); ++i) {
            const DeviceConfig& c = file.devices[i];
            fastestHz = std::max(fastestHz, c.rateHz);
            devices.push_back({makeDevice(c, *scene.scene), c, nullptr, file.renderingOf(i)});
        }
        RuntimeOptions options;
        options.realtime = a.realtime;
        mDevices = devices.size();
        mRuntime = std::make_unique<Runtime>(*mWorld, std::move(devices), options);
        SessionOptions control;
        if (mStepped) {
            control.steppedClock = &mClock;
            const double hz = fastestHz > 0 ? fastestHz : mRuntime->dynamicsRateHz();
            control.controlPeriodNs = static_cast<std::uint64_t>(std::llround(1e9 / hz));
        }
        if (!a.record.empty() && mRuntime->hasDynamics()) {
            std::filesystem::create_directories(a.record);
            mBodyRecorder = std::make_unique<BodyTraceRecorder>(
                std::filesystem::path(a.record) / kBodyTraceFileName, mRuntime->bodyIds(),
                mRuntime->dynamicsRateHz());
            control.bodyRecorder = mBodyRecorder.get();
        }
        control.stopRequested = [this] { return signalPending(); };
        mSession = std::make_unique<Session>(*mRuntime, std::move(control));
    }

    /// Runs for `seconds` of session time; returns why it ended.
    std::string run(double seconds) {
        if (!(std::isfinite(seconds) && seconds > 0)) {
            throw InputError("seconds " + std::to_string(seconds) +
                             ": expected a positive, finite session time (s)");
        }
        return drive([this, seconds](std::uint64_t) {
            const double end = mSession->timeS() + seconds;
            return ControlStep([end](double tS) { return tS < end; });
        });
    }

    /// Runs `ticks` ticks of the fastest device (step mode only); returns why it ended.
    std::string step(std::int64_t ticks) {
        if (!mStepped) {
            throw InputError("step: only a session made with stepped=True steps; use "
                             "run(seconds) on the wall clock");
        }
        if (ticks <= 0) {
            throw InputError("ticks " + std::to_string(ticks) + ": expected a positive count");
        }
        return drive([ticks](std::uint64_t) {
            auto done = std::make_shared<std::int64_t>(0);
            return ControlStep([ticks, done](double) { return ++*done < ticks; });
        });
    }

    /// The run report as `hapto run --report` writes it (final after stop()).
    std::string report() const { return reportToJson(mStopped ? mFinal : mRuntime->report()); }

    /// Zero force on every device, devices closed; returns the final report.
    std::string stop() {
        if (!mStopped) {
            py::gil_scoped_release release;
            mFinal = mStarted ? mSession->stop() : mRuntime->report();
            mStopped = true;
        }
        return reportToJson(mFinal);
    }

    double timeS() const { return mStarted ? mSession->timeS() : 0.0; }

    /// Every dynamic body's latest pose, as numpy columns (body order: the scene's slots).
    py::dict bodies() const {
        const BodyPoseTable* table = mRuntime->bodyPoses();
        if (table == nullptr) {
            throw InputError("bodies: the scene has no dynamic body (an object with "
                             "\"dynamic\": true)");
        }
        if (!mStarted) {
            throw InputError("bodies: the session has not started; run() or step() it first "
                             "(the bodies' poses are published from its start)");
        }
        return bodyColumns(*table, mRuntime->bodyIds(), mStartNs);
    }
    bool stepped() const { return mStepped; }

private:
    /// No device needs a dynamic body to run; record=DIR writes only the bodies' trace.
    static void checkAgainstScene(const Scene& scene, const SessionArgs& a) {
        if (a.noDevices && !scene.hasDynamicBodies()) {
            throw InputError("devices=[]: the scene has no dynamic body (an object with "
                             "\"dynamic\": true), so nothing would run; give a scene with one, "
                             "or devices");
        }
        if (!a.record.empty() && !scene.hasDynamicBodies()) {
            throw InputError("record " + a.record +
                             ": the scene has no dynamic body; from Python, record writes "
                             "only the bodies' trace (use `hapto run --record` for the "
                             "devices' traces)");
        }
    }

    static void checkDevices(std::vector<DeviceConfig>& configs, const SessionArgs& a) {
        if (a.rateHz > 0) {
            for (DeviceConfig& c : configs) {
                c.rateHz = a.rateHz;
            }
        }
        useTraceSettings(configs, !(a.rateHz > 0));
        for (const DeviceConfig& c : configs) {
            if (a.stepped && !runsOnStepClock(c.kind)) {
                throw InputError("stepped: device '" + c.name + "' is a " +
                                 std::string(name(c.kind)) +
                                 "; only simulated hands (sim) and replays run on the step clock");
            }
        }
    }

    /// Starts the devices at the first call, then runs the session with the GIL released.
    template <class MakeStep> std::string drive(MakeStep makeStep) {
        if (mStopped) {
            throw InputError("the session was stopped; make a new Session");
        }
        SessionEnd end;
        {
            py::gil_scoped_release release;
            start();
            end = mSession->run(makeStep(0));
        }
        if (mInterrupted) {
            stop(); // zero force before Python sees the signal
            throw py::error_already_set();
        }
        return std::string(sessionEndName(end));
    }

    void start() {
        if (mStarted) {
            return;
        }
        mStarted = true;
        // The runtime's clock at its start, which the bodies' pose times count from: exact in
        // step mode (the clock stands still until the first step), within the devices'
        // opening time (microseconds) on the wall clock.
        mStartNs = mStepped ? mClock.nowNs() : rt::nowNs();
        // No device to open (devices=[]) is not a failure: the dynamics runs alone.
        if (mSession->start() == 0 && mDevices > 0) {
            std::string why = "no device could be opened:";
            for (const DeviceReport& d : mRuntime->report().devices) {
                why += " " + d.name + ": " + d.fault + ";";
            }
            mFinal = mSession->stop();
            mStopped = true;
            throw std::runtime_error(why);
        }
    }

    /// Called by the control loop without the GIL: true once Python has a signal pending.
    bool signalPending() {
        if (!mInterrupted) {
            py::gil_scoped_acquire acquire;
            mInterrupted = PyErr_CheckSignals() != 0;
        }
        return mInterrupted;
    }

    ManualClock mClock;
    std::unique_ptr<World> mWorld;
    std::unique_ptr<Runtime> mRuntime;
    std::unique_ptr<BodyTraceRecorder> mBodyRecorder; // outlives the session that drains it
    std::unique_ptr<Session> mSession;
    std::size_t mDevices = 0;
    std::uint64_t mStartNs = 0; // the runtime's clock at start() (ns)
    bool mStepped = false, mStarted = false, mStopped = false, mInterrupted = false;
    RunReport mFinal;
};

} // namespace

void bindSession(py::module_& m) {
    py::class_<PySession>(m, "Session", "A session of devices over one shared world")
        .def(py::init([](const PyScene& scene, const std::string& devicesJson,
                         const std::string& devicesPath, bool stepped, const std::string& index,
                         std::uint64_t maxIndexMb, double rateHz, bool realtime, bool noDevices,
                         const std::string& record) {
                 const SessionArgs a{devicesJson, devicesPath, stepped,   index, maxIndexMb,
                                     rateHz,      realtime,    noDevices, record};
                 py::gil_scoped_release release;
                 return std::make_unique<PySession>(scene, a);
             }),
             py::arg("scene"), py::arg("devices_json") = "", py::arg("devices_path") = "",
             py::arg("stepped") = false, py::arg("index") = "",
             py::arg("max_index_mb") = IndexSpec::kDefaultMaxMegabytes, py::arg("rate_hz") = 0.0,
             py::arg("realtime") = false, py::arg("no_devices") = false, py::arg("record") = "")
        .def("run", &PySession::run, py::arg("seconds"))
        .def("step", &PySession::step, py::arg("ticks"))
        .def("report_json", &PySession::report)
        .def("stop", &PySession::stop)
        .def("bodies", &PySession::bodies)
        .def_property_readonly("time_s", &PySession::timeS)
        .def_property_readonly("stepped", &PySession::stepped);
}

} // namespace hapto::python
