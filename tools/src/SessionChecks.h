#pragma once
/// The checks a session's arguments pass before any device starts (`hapto run`, `demo`,
/// `soak`): bad ones are refused with InputError (exit code 2) while nothing runs yet.

#include "hapto/devices/DeviceConfig.h"

#include <cstddef>
#include <span>
#include <string>

namespace hapto::cli {

/// What a session reads and writes, as given on the command line ("" = none or built in).
struct SessionPaths {
    std::string scene;   ///< --scene: the scene file.
    std::string devices; ///< --devices: the device configuration file.
    std::string report;  ///< --report: the JSON report to write.
    std::string record;  ///< --record: the folder the traces go to (<folder>/<name>.trace).
};

/// The most devices one `hapto run` drives: 1024. The World has no cap on readers; this one
/// guards against a generated device file gone wrong. Every device is a servo thread, and at
/// 1 kHz a device-tick costs about 13 us of CPU with the kernel's sleep and wake-up
/// (docs/results/many-devices.md; about 4 us in servo groups of 16), so 1024 devices on their
/// own threads already need about thirteen cores.
inline constexpr std::size_t kMaxSessionDevices = 1024;

/// Refuses more devices than kMaxSessionDevices, naming the limit and `source` (the device
/// file). [control]
void checkDeviceCount(std::size_t devices, const std::string& source);

/// Refuses a spin (us, before each deadline) that is not shorter than the servo period of
/// every device at its rate. [control]
void checkSpinAgainstRates(double spinUs, std::span<const DeviceConfig> configs);

/// Refuses outputs that cannot be written or would destroy an input: a --report that is not a
/// regular file (a folder, FIFO, socket or device), in a missing or read-only folder, or the
/// same file as the scene, the device file or a replay device's trace; a --record folder that
/// cannot be made or written, or whose `<name>.trace` is not a regular file, an input (a trace a
/// replay device of this session reads, the scene, the device file) or the report. Nothing is
/// created. [control]
void checkSessionFiles(const SessionPaths& paths, std::span<const DeviceConfig> configs);

/// `--stepped` runs only devices whose time the session gives them (runsOnStepClock:
/// simulated hands, replays); refuses any other (a Falcon or PHANToM keeps real time), naming
/// it. [control]
void checkSteppable(std::span<const DeviceConfig> configs);

/// With --record `folder` and dynamic bodies in the scene: refuses a `<folder>/bodies.trace`
/// (kBodyTraceFileName) that is a device's trace, an input, the report or not a regular file.
/// [control]
void checkBodyTraceFile(const SessionPaths& paths, std::span<const DeviceConfig> configs);

} // namespace hapto::cli
