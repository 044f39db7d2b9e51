#pragma once
/// Plays a recorded trace back as a device (`"kind": "replay"`).

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/TraceFormat.h"

#include <span>
#include <string>
#include <vector>

namespace hapto {

/// A device whose positions come from a trace, one recorded tick per read(): the n-th read
/// after open() plays tick first + n (a tick missing from the trace, dropped while recording,
/// repeats the sample before it). Each read returns the recorded status and buttons, and from
/// a version 2 trace the recorded velocity, orientation and angular velocity with their flags
/// (a version 1 trace has none: the runtime then differentiates positions). At the end
/// it starts over when ReplayConfig::loop, else it keeps the last position and returns Stalled.
/// Written forces are kept next to the recorded ones, so a rerun of a session against another
/// index or renderer can compare them tick by tick. Its rate is the trace's.
class ReplayDevice final : public Device {
public:
    /// Loads and validates the whole trace (a servo thread never touches the file). Throws
    /// InputError for a bad trace or a configuration not of kind "replay". [control]
    explicit ReplayDevice(const DeviceConfig& config);

    std::string_view name() const override { return mConfig.name; }
    DeviceKind kind() const override { return DeviceKind::Replay; }
    /// Workspace: the recorded positions' bounds; max force: the configured one, else the
    /// largest recorded; rate: the trace's. [control]
    DeviceCapabilities capabilities() const override;
    /// Rewinds to the first sample. [control]
    DeviceStatus open() override;
    /// Stops; read/write then return NotOpen. [control]
    void close() override;
    /// Plays the next tick. [servo]
    DeviceStatus read(DeviceState& state) noexcept override;
    /// Keeps the force (N) for comparison; a non-finite one is refused with BadData. [servo]
    DeviceStatus write(const Vec3& forceN) noexcept override;
    /// The last failure. [control]
    std::string errorMessage() const override { return mError; }

    /// The trace's header. [any thread]
    const TraceHeader& traceHeader() const { return mHeader; }
    /// Every recorded sample. [any thread]
    std::span<const TraceSample> samples() const { return mSamples; }
    /// The sample the last read() played (the first one before any read). [servo]
    const TraceSample& currentSample() const { return mSamples[mCursor]; }
    /// The force last written (N, device frame). [servo]
    const Vec3& lastForceN() const { return mLastForceN; }
    /// Reads since open(), counting loops. [servo]
    std::uint64_t readCount() const { return mReads; }
    /// Times the trace started over (loop only). [servo]
    std::uint64_t loops() const { return mLoops; }

private:
    DeviceConfig mConfig;
    ReplayConfig mReplay;
    TraceHeader mHeader;
    std::vector<TraceSample> mSamples;
    std::size_t mCursor = 0;
    std::uint64_t mPlayed = 0; // ticks played in this pass
    std::uint64_t mReads = 0;
    std::uint64_t mLoops = 0;
    Vec3 mLastForceN{0.0};
    bool mOpen = false;
    std::string mError;
};

/// Gives every replay configuration what its trace recorded, unless the device gives its own:
/// from a version 2 trace the transform (unless `transform` was given), the tool tip (unless
/// `tool_tip` was) and the force clamp (unless `max_force_n` was), and when `rates` the rate
/// (unless `rate_hz` was), which is what a replay runs at unless the user sets a rate for the whole
/// session (`hapto run --rate`: then pass rates = false). So a replay of a recorded run against the
/// same scene and index touches the same points and writes the same forces, tick for tick. Other
/// kinds are left alone. Reads only the trace headers. Throws InputError for a trace that cannot be
/// read or a recorded rate outside 100..100000 Hz. [control]
void useTraceSettings(std::span<DeviceConfig> configs, bool rates = true);

} // namespace hapto
