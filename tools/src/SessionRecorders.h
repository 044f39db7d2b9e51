#pragma once
/// `--record DIR` for a session command (`hapto run`, `hapto demo grasp`): one trace per device,
/// `DIR/<name>.trace`, and `DIR/bodies.trace` for a runtime with dynamic bodies. One home, so
/// every command records alike and `hapto view --trace DIR` / `hapto trace export` read them.

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/TraceRecorder.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/runtime/DeviceFile.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/Session.h"

#include <memory>
#include <string>
#include <vector>

namespace hapto::cli {

/// The recorder of device `c` for --record `folder`: `<folder>/<name>.trace`, its header the
/// device's configuration and the wall-clock time now. [control]
std::unique_ptr<TraceRecorder> recorderFor(const DeviceConfig& c, const std::string& folder);

/// A session's recorders: each device's `<folder>/<name>.trace`, and `<folder>/bodies.trace`
/// when the runtime has dynamics.
struct Recorders {
    std::vector<std::unique_ptr<TraceRecorder>> devices; ///< One per device, in device order.
    std::unique_ptr<BodyTraceRecorder> bodies;           ///< Null without dynamics.

    /// The session's recorders in `options` (they are flushed by the session). [control]
    void addTo(SessionOptions& options) const;
};

/// The runtime's devices of `file` over `scene` (DeviceFactory's makeDevice, not opened), each
/// with its `<folder>/<name>.trace` in `recorders` when `folder` is not empty (the folder is
/// created). [control]
std::vector<RuntimeDevice> recordedDevices(const DeviceFile& file, const Scene& scene,
                                           const std::string& folder, Recorders& recorders);

/// `<folder>/bodies.trace` in `recorders` when `folder` is not empty and `runtime` has dynamic
/// bodies. [control]
void recordBodies(const Runtime& runtime, const std::string& folder, Recorders& recorders);

} // namespace hapto::cli
