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
// due in that time), and the result is the same every run.

#include "Bindings.h"

#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/index/DefaultIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/Session.h"
#include "hapto/runtime/World.h"

#include <cmath>
#include <memory>
#include <optional>
#include <string>

namespace hapto::python {
namespace {

/// Where a session's devices come from: JSON text (Python's list of dicts, as a device file),
/// a device file, or neither (the main job's two simulated hands).
DeviceFile deviceFileOf(const std::string& json, const std::string& path) {
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
    bool realtime = false; ///< Ask for SCHED_FIFO and pinning (the command's default is on).
};

class PySession {
public:
    PySession(const PyScene& scene, const SessionArgs& a) : mStepped(a.stepped) {
        DeviceFile file = deviceFileOf(a.devicesJson, a.devicesPath);
        checkDevices(file.devices, a);
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
        mRuntime = std::make_unique<Runtime>(*mWorld, std::move(devices), options);
        SessionOptions control;
        if (mStepped) {
            control.steppedClock = &mClock;
            control.controlPeriodNs = static_cast<std::uint64_t>(std::llround(1e9 / fastestHz));
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
    bool stepped() const { return mStepped; }

private:
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
        if (mSession->start() == 0) {
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
    std::unique_ptr<Session> mSession;
    bool mStepped = false, mStarted = false, mStopped = false, mInterrupted = false;
    RunReport mFinal;
};

} // namespace

void bindSession(py::module_& m) {
    py::class_<PySession>(m, "Session", "A session of devices over one shared world")
        .def(py::init([](const PyScene& scene, const std::string& devicesJson,
                         const std::string& devicesPath, bool stepped, const std::string& index,
                         std::uint64_t maxIndexMb, double rateHz, bool realtime) {
                 const SessionArgs a{devicesJson, devicesPath, stepped, index,
                                     maxIndexMb,  rateHz,      realtime};
                 py::gil_scoped_release release;
                 return std::make_unique<PySession>(scene, a);
             }),
             py::arg("scene"), py::arg("devices_json") = "", py::arg("devices_path") = "",
             py::arg("stepped") = false, py::arg("index") = "",
             py::arg("max_index_mb") = IndexSpec::kDefaultMaxMegabytes, py::arg("rate_hz") = 0.0,
             py::arg("realtime") = false)
        .def("run", &PySession::run, py::arg("seconds"))
        .def("step", &PySession::step, py::arg("ticks"))
        .def("report_json", &PySession::report)
        .def("stop", &PySession::stop)
        .def_property_readonly("time_s", &PySession::timeS)
        .def_property_readonly("stepped", &PySession::stepped);
}

} // namespace hapto::python
