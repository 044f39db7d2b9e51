#pragma once
/// The JSON the page reads once: the scene (/scene.json) and, offline, a recorded session
/// (/trace.json). The formats are written down in docs/DESIGN.md ("The view").

#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/TraceFormat.h"
#include "hapto/runtime/BodyTrace.h"
#include "hapto/scenes/Scene.h"

#include <string>
#include <vector>

namespace hapto {

/// Whether the page follows a live session or plays a recording.
enum class ViewMode : std::uint8_t { Live, Trace };

/// A device as the page names it.
struct ViewDevice {
    std::string name;  ///< "left", ...
    double rateHz = 0; ///< Servo rate (Hz).
};

/// At most this many mesh triangles per scene go to the page (about 10 MB of JSON); a mesh
/// beyond it is simplified to its share.
inline constexpr std::uint64_t kViewMaxMeshTriangles = 200'000;

/// The scene for the page: bounds, every object (centre, half extents, rotation (w, x, y, z))
/// and the devices and the mode. A mesh object also carries `triangleCount` and, as
/// `vertices` (flat x y z ..., m, in its own frame) and `triangles` (flat a b c ..., CCW from
/// outside, `trianglesShown` of them), either the whole mesh, while the scene's running total
/// in slot order stays within `maxMeshTriangles`, or, for the meshes past that, the mesh
/// simplified by meshoptimizer to an even share of what the cap leaves (the smaller meshes
/// first; listed in `meshes.simplified`). A mesh that cannot be simplified within its share
/// carries its `localBounds` (min, max) instead and is listed in `meshes.boxed`. Simplifying a
/// 10^6-triangle mesh takes about a second. [control]
std::string viewSceneJson(const Scene& scene, const std::vector<ViewDevice>& devices, ViewMode mode,
                          std::uint64_t maxMeshTriangles = kViewMaxMeshTriangles);

/// One recorded device for the offline player.
struct ViewTrace {
    TraceHeader header;               ///< Name and rate.
    WorkspaceTransform transform;     ///< Device frame into the world.
    std::vector<TraceSample> samples; ///< As recorded (device frame).
};

/// The recording as frames at `frameHz` (at most one per frame time per device, and its last
/// tick): time (s), device point, force and (version 2 traces) the god-object proxy in the
/// world frame, the objects whose solid holds the point (a god-object device point is inside
/// what it touches), and the load over the last second (p50, p99.9 of compute time over the
/// period) and the misses so far: the runtime's rule (a force written after the next deadline;
/// the deadlines move past the slots a late force overran) over deadlines rebuilt from the
/// recorded wake-ups, starting at the first tick's (ViewDocuments.cpp, MissCounter). A trace
/// records no cursor leaves or candidates; the frames carry none. With `bodies` (a
/// bodies.trace, BodyTrace.h), also each dynamic body's frames at `frameHz`: time (s), the
/// object's centre (from the recorded centre of mass and the scene object's
/// BodyProperties::centerOfMassLocal) and rotation, for the player to place it. [control]
std::string viewTraceJson(const Scene& scene, const std::vector<ViewTrace>& traces,
                          double frameHz = 60.0, const BodyTrace* bodies = nullptr);

} // namespace hapto
