#include "hapto/devices/ReplayDevice.h"

#include "hapto/core/Finite.h"

#include "hapto/devices/TraceReader.h"
#include "hapto/io/InputError.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace hapto {
namespace {

const ReplayConfig& replayOf(const DeviceConfig& config) {
    const auto* r = std::get_if<ReplayConfig>(&config.params);
    if (config.kind != DeviceKind::Replay || !r) {
        throw InputError("device '" + config.name +
                         "': a replay device needs kind \"replay\" (got \"" +
                         std::string(name(config.kind)) + "\")");
    }
    return *r;
}

} // namespace

ReplayDevice::ReplayDevice(const DeviceConfig& config)
    : mConfig(config), mReplay(replayOf(config)) {
    mSamples = TraceReader::load(mReplay.trace, &mHeader);
    if (mSamples.empty()) {
        throw InputError(mReplay.trace.string() +
                         ": the trace holds no samples; nothing to replay");
    }
}

DeviceCapabilities ReplayDevice::capabilities() const {
    DeviceCapabilities c;
    c.model = "replay of " + mReplay.trace.filename().string() + " (" + mHeader.kind + " '" +
              mHeader.name + "')";
    Aabb box = Aabb::empty();
    double maxForce = 0.0;
    for (const TraceSample& s : mSamples) {
        box.expand(s.positionM);
        maxForce = std::max(maxForce, glm::length(s.forceN));
    }
    c.workspace = box;
    c.maxForceN = mConfig.maxForceN > 0.0 ? mConfig.maxForceN : maxForce;
    c.nominalRateHz = mHeader.rateHz;
    std::uint32_t buttons = 0;
    for (const TraceSample& s : mSamples) {
        buttons |= s.buttons;
    }
    c.buttonCount = buttons == 0 ? 0 : 32 - std::countl_zero(buttons);
    return c;
}

DeviceStatus ReplayDevice::open() {
    mCursor = 0;
    mPlayed = 0;
    mReads = 0;
    mLoops = 0;
    mLastForceN = Vec3(0.0);
    mError.clear();
    mOpen = true;
    return DeviceStatus::Ok;
}

void ReplayDevice::close() {
    mLastForceN = Vec3(0.0);
    mOpen = false;
}

DeviceStatus ReplayDevice::read(DeviceState& state) noexcept {
    if (!mOpen) {
        return DeviceStatus::NotOpen;
    }
    const std::uint64_t first = mSamples.front().tick;
    const std::uint64_t last = mSamples.back().tick;
    if (mPlayed > last - first) {
        if (!mReplay.loop) {
            state.position = mSamples.back().positionM;
            state.hasVelocity = false;
            state.hasAngularVelocity = false;
            return DeviceStatus::Stalled;
        }
        mPlayed = 0;
        mCursor = 0;
        ++mLoops;
    }
    const std::uint64_t tick = first + mPlayed;
    while (mCursor + 1 < mSamples.size() && mSamples[mCursor + 1].tick <= tick) {
        ++mCursor;
    }
    ++mPlayed;
    ++mReads;
    const TraceSample& s = mSamples[mCursor];
    sampleToState(s, state);
    state.sequence = mReads;
    return s.status;
}

void useTraceSettings(std::span<DeviceConfig> configs, bool rates) {
    for (DeviceConfig& c : configs) {
        if (c.kind != DeviceKind::Replay) {
            continue;
        }
        const ReplayConfig& replay = replayOf(c);
        const std::filesystem::path& trace = replay.trace;
        const TraceHeader header = TraceReader(trace).header();
        if (header.hasConfiguration()) {
            if (!replay.ownTransform) {
                c.transform = header.transform;
            }
            if (!replay.ownToolTip) {
                c.toolTipM = header.toolTipM;
            }
            if (!replay.ownMaxForce) {
                c.maxForceN = header.maxForceN;
            }
        }
        if (!rates || replay.ownRate) {
            continue;
        }
        const double rateHz = header.rateHz;
        if (!(rateHz >= 100.0 && rateHz <= 100000.0)) {
            throw InputError(trace.string() + ": device '" + c.name + "' would replay at " +
                             std::to_string(rateHz) +
                             " Hz, the trace's rate, outside 100..100000 Hz; give the session "
                             "a rate (hapto run --rate)");
        }
        c.rateHz = rateHz;
    }
}

DeviceStatus ReplayDevice::write(const Vec3& forceN) noexcept {
    if (!mOpen) {
        return DeviceStatus::NotOpen;
    }
    if (!finite(forceN)) {
        mLastForceN = Vec3(0.0);
        return DeviceStatus::BadData;
    }
    mLastForceN = forceN;
    return DeviceStatus::Ok;
}

} // namespace hapto
