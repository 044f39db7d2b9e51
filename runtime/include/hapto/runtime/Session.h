#pragma once
/// One session of a Runtime from start to report: the control loop every command, experiment
/// and application runs (start, supervise, stop on duration, request or end, zero force, close
/// the recordings, report).
///
/// Design note. A session's control thread does little of its own: it keeps the world up to
/// date (Runtime::maintain), lets the caller do its per-step work (a grasp controller, a view,
/// fault injection, windows of a soak), drains the trace recorders, and decides when to end.
/// The watchdog, closing and reopening devices run on the runtime's supervisor, never here.
/// Everything the caller adds (a terminal, a web view) is a ControlStep it passes in, so this
/// driver depends on nothing above the runtime, and a stop request is seen at the next control
/// step: the devices are zeroed (Runtime::stop) before any recording is closed or report
/// written. On the wall clock a control step waits for its period (sleep_until, a fixed rate:
/// a step that ran late is followed by the ones due at once); in step mode it runs the servo
/// ticks due in its period first (Runtime::runUntil), so the session's outcome is the same
/// every run however busy the machine is.

#include "hapto/runtime/ManualClock.h"
#include "hapto/runtime/Runtime.h"

#include <chrono>
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

namespace hapto {

class TraceRecorder;
class BodyTraceRecorder;

/// Why a session's control loop ended.
enum class SessionEnd : std::uint8_t {
    Duration,    ///< Its session time reached SessionOptions::durationS.
    Requested,   ///< SessionOptions::stopRequested said so (a signal, a user).
    Finished,    ///< The control step returned false (its work is done).
    NoneRunning, ///< No device is driven any more, nor will be (Runtime::anyRunning).
};

/// "duration", "requested", "finished", "none running". [any thread]
std::string_view sessionEndName(SessionEnd end);

/// True for the device kinds a session in step mode can drive: those whose time the session
/// gives them (simulated hands, replays, scripted test devices). A Falcon or PHANToM keeps real
/// time: stepped, it would be read as fast as the machine goes, not at its rate. [any thread]
bool runsOnStepClock(DeviceKind kind);

/// A caller's work in one control step, at session time `tS` (s, 0 at Session::start()),
/// after the world's upkeep: return false to end the session. [control]
using ControlStep = std::function<bool(double tS)>;

/// How a session runs.
struct SessionOptions {
    /// Session time at which the control loop ends (s); 0: no limit (until a request, the
    /// control step or the devices end it).
    double durationS = 0;
    /// One control step (ns): the world's upkeep, the caller's step and the recorders' drain
    /// run once per period.
    std::uint64_t controlPeriodNs = 5'000'000;
    /// Set: step mode on this clock (Runtime::startStepped; it must outlive the session).
    /// Null: the servo threads run on the wall clock and the control loop sleeps.
    ManualClock* steppedClock = nullptr;
    /// Asked before every control step; true ends the session (e.g. a stop signal came). It
    /// must not block. Empty: never.
    std::function<bool()> stopRequested;
    /// Recorders (the devices' RuntimeDevice::recorder, owned by the caller): drained every
    /// control step, closed after the devices are stopped, abandoned when no device opened.
    std::vector<TraceRecorder*> recorders;
    /// The dynamic bodies' recorder (Runtime::setBodyRecorder, owned by the caller): given to
    /// the runtime at start(), drained every control step, closed after the runtime stops.
    /// Null: none. Ignored (and abandoned) when the runtime has no dynamics.
    BodyTraceRecorder* bodyRecorder = nullptr;
};

/// Drives one Runtime through a session: start(), run(), stop(). Threading: [control], all of
/// it on the thread that made the runtime (in step mode, the servo ticks run there too).
class Session {
public:
    /// `runtime` (not yet started) must outlive the session. [control]
    Session(Runtime& runtime, SessionOptions options);
    /// Stops the session if stop() was not called (zero force, recordings closed). [control]
    ~Session();
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;

    /// Opens the devices and starts the servo threads and the dynamics thread, if any (or
    /// step mode on the options' clock); session time 0 is now. Returns how many devices
    /// opened; when none did, the devices' recorders are abandoned (an older trace of the same
    /// name stays). A session with dynamics and no device runs until its end like any: the
    /// dynamics counts as running (Runtime::anyRunning). [control]
    std::size_t start();
    /// The control loop, after start(): until the stop request, the end of every device, the
    /// control step's false or the duration, whichever comes first. Before each step the
    /// loop waits for (or, stepped, runs) one control period; a step then runs only at a
    /// session time before the duration. May be called again to go on. [control]
    SessionEnd run(const ControlStep& step = {});
    /// Commands zero force to every device and closes them (Runtime::stop), then closes the
    /// recorders, and returns the final report. Once; later calls return the same report.
    /// [control]
    const RunReport& stop();
    /// Session time now (s): since start(), on the wall clock or the step mode's. [control]
    double timeS() const;
    /// The runtime driven. [control]
    Runtime& runtime() { return mRuntime; }

private:
    double advance();
    bool stopRequested() const;

    Runtime& mRuntime;
    SessionOptions mOptions;
    bool mStarted = false, mStopped = false, mAbandoned = false;
    std::uint64_t mSteppedT0Ns = 0;
    std::chrono::steady_clock::time_point mWallT0{}, mNextStep{};
    RunReport mReport;
};

} // namespace hapto
