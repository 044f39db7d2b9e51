#include "hapto/devices/TraceFormat.h"

#include <algorithm>
#include <bit>
#include <cstring>

namespace hapto {
namespace {

void putU32(unsigned char* out, std::uint32_t v) {
    for (int i = 0; i < 4; ++i) {
        out[i] = static_cast<unsigned char>(v >> (8 * i));
    }
}
void putU64(unsigned char* out, std::uint64_t v) {
    for (int i = 0; i < 8; ++i) {
        out[i] = static_cast<unsigned char>(v >> (8 * i));
    }
}
void putF64(unsigned char* out, double v) {
    putU64(out, std::bit_cast<std::uint64_t>(v));
}
std::uint32_t getU32(const unsigned char* in) {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) {
        v |= static_cast<std::uint32_t>(in[i]) << (8 * i);
    }
    return v;
}
std::uint64_t getU64(const unsigned char* in) {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) {
        v |= static_cast<std::uint64_t>(in[i]) << (8 * i);
    }
    return v;
}
double getF64(const unsigned char* in) {
    return std::bit_cast<double>(getU64(in));
}

void putVec(unsigned char* out, const Vec3& v) {
    for (int i = 0; i < 3; ++i) {
        putF64(out + 8 * i, v[i]);
    }
}
Vec3 getVec(const unsigned char* in) {
    return Vec3(getF64(in), getF64(in + 8), getF64(in + 16));
}
void putQuat(unsigned char* out, const Quat& q) {
    putF64(out, q.w);
    putF64(out + 8, q.x);
    putF64(out + 16, q.y);
    putF64(out + 24, q.z);
}

void putText(unsigned char* out, const std::string& text, std::size_t field) {
    std::memset(out, 0, field);
    std::memcpy(out, text.data(), std::min(text.size(), field - 1));
}

} // namespace

void encodeTraceHeader(const TraceHeader& header, std::uint64_t sampleCount, unsigned char* out) {
    std::memset(out, 0, kTraceHeaderBytes);
    std::memcpy(out, kTraceMagic.data(), kTraceMagic.size());
    putU32(out + 8, kTraceVersion);
    putU32(out + 12, static_cast<std::uint32_t>(kTraceHeaderBytes));
    putU32(out + 16, static_cast<std::uint32_t>(kTraceSampleBytes));
    putU32(out + 20, kTraceHeaderMarksMisses);
    putF64(out + 24, header.rateHz);
    putU64(out + 32, sampleCount);
    putU64(out + 40, header.startUnixNs);
    putText(out + 48, header.kind, kTraceMaxKindBytes + 1);
    putText(out + 64, header.name, kTraceMaxNameBytes + 1);
    putVec(out + 128, header.transform.translation);
    putQuat(out + 152, header.transform.rotation);
    putF64(out + 184, header.transform.scale);
    putVec(out + 192, header.toolTipM);
    putF64(out + 216, header.maxForceN);
}

TraceHeaderFields decodeTraceHeader(const unsigned char* in, bool version2) {
    TraceHeaderFields h;
    std::memcpy(h.magic.data(), in, 8);
    h.version = getU32(in + 8);
    h.headerBytes = getU32(in + 12);
    h.sampleBytes = getU32(in + 16);
    h.flags = getU32(in + 20);
    h.rateHz = getF64(in + 24);
    h.sampleCount = getU64(in + 32);
    h.startUnixNs = getU64(in + 40);
    std::memcpy(h.kind.data(), in + 48, 16);
    std::memcpy(h.name.data(), in + 64, 64);
    if (version2) {
        h.translation = getVec(in + 128);
        for (int i = 0; i < 4; ++i) {
            h.rotation[static_cast<std::size_t>(i)] = getF64(in + 152 + 8 * i);
        }
        h.scale = getF64(in + 184);
        h.toolTipM = getVec(in + 192);
        h.maxForceN = getF64(in + 216);
        std::memcpy(h.reserved.data(), in + 224, h.reserved.size());
    }
    return h;
}

void encodeTraceSample(const TraceSample& s, unsigned char* out) noexcept {
    putU64(out, s.tick);
    putU64(out + 8, s.timeNs);
    for (int i = 0; i < 3; ++i) {
        putF64(out + 16 + 8 * i, s.positionM[i]);
        putF64(out + 40 + 8 * i, s.forceN[i]);
    }
    putU32(out + 64, s.computeNs);
    putU32(out + 68, s.ioNs);
    out[72] = static_cast<unsigned char>(s.status);
    out[73] = out[74] = out[75] = 0;
    putU32(out + 76, s.buttons);
    putVec(out + 80, s.proxyM);
    putVec(out + 104, s.hasVelocity ? s.velocityMps : Vec3(0.0));
    putQuat(out + 128, s.hasOrientation ? s.orientation : Quat{1, 0, 0, 0});
    putVec(out + 160, s.hasAngularVelocity ? s.angularVelocity : Vec3(0.0));
    putU32(out + 184, s.contactCount);
    putU32(out + 188, (s.hasVelocity ? kTraceSampleHasVelocity : 0u) |
                          (s.hasOrientation ? kTraceSampleHasOrientation : 0u) |
                          (s.hasAngularVelocity ? kTraceSampleHasAngularVelocity : 0u) |
                          (s.missedDeadline ? kTraceSampleMissedDeadline : 0u));
}

TraceSample decodeTraceSample(const unsigned char* in, std::uint32_t version) noexcept {
    TraceSample s;
    s.tick = getU64(in);
    s.timeNs = getU64(in + 8);
    for (int i = 0; i < 3; ++i) {
        s.positionM[i] = getF64(in + 16 + 8 * i);
        s.forceN[i] = getF64(in + 40 + 8 * i);
    }
    s.computeNs = getU32(in + 64);
    s.ioNs = getU32(in + 68);
    s.status = static_cast<DeviceStatus>(in[72]);
    s.buttons = getU32(in + 76);
    if (version >= 2) {
        s.proxyM = getVec(in + 80);
        s.velocityMps = getVec(in + 104);
        s.orientation =
            Quat{getF64(in + 128), getF64(in + 136), getF64(in + 144), getF64(in + 152)};
        s.angularVelocity = getVec(in + 160);
        s.contactCount = getU32(in + 184);
        const std::uint32_t flags = getU32(in + 188);
        s.hasVelocity = (flags & kTraceSampleHasVelocity) != 0;
        s.hasOrientation = (flags & kTraceSampleHasOrientation) != 0;
        s.hasAngularVelocity = (flags & kTraceSampleHasAngularVelocity) != 0;
        s.missedDeadline = (flags & kTraceSampleMissedDeadline) != 0;
    }
    return s;
}

void stateToSample(const DeviceState& state, TraceSample& sample) noexcept {
    sample.positionM = state.position;
    sample.velocityMps = state.velocity;
    sample.hasVelocity = state.hasVelocity;
    sample.orientation = state.orientation;
    sample.hasOrientation = state.hasOrientation;
    sample.angularVelocity = state.angularVelocity;
    sample.hasAngularVelocity = state.hasAngularVelocity;
    sample.buttons = state.buttons;
}

void sampleToState(const TraceSample& sample, DeviceState& state) noexcept {
    state.position = sample.positionM;
    state.velocity = sample.velocityMps;
    state.hasVelocity = sample.hasVelocity;
    state.orientation = sample.orientation;
    state.hasOrientation = sample.hasOrientation;
    state.angularVelocity = sample.angularVelocity;
    state.hasAngularVelocity = sample.hasAngularVelocity;
    state.buttons = sample.buttons;
}

} // namespace hapto
