#include "hapto/devices/TraceReader.h"

#include "hapto/core/Finite.h"
#include "hapto/io/InputError.h"
#include "hapto/io/InputFile.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

namespace hapto {
namespace {

// Reads a NUL-padded ASCII field; false when it holds non-printable bytes or text after a NUL.
bool text(const char* field, std::size_t size, std::string& out) {
    out.clear();
    std::size_t i = 0;
    for (; i < size && field[i] != '\0'; ++i) {
        if (field[i] < 0x20 || field[i] > 0x7e) {
            return false;
        }
        out += field[i];
    }
    for (; i < size; ++i) {
        if (field[i] != '\0') {
            return false;
        }
    }
    return true;
}

} // namespace

void TraceReader::fail(std::uint64_t offset, const std::string& what) const {
    throw InputError(mPath.string() + ": byte " + std::to_string(offset) + ": " + what);
}

TraceReader::TraceReader(const std::filesystem::path& path) : mPath(path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
        throw InputError(path.string() + ": cannot read the trace (" +
                         (ec ? ec.message() : std::string("no such file")) + ")");
    }
    // A regular file of at most kMaxInputFileBytes (a FIFO, a pipe or /dev/zero is refused at
    // once); its size is taken from the open file, so it matches what is read.
    InputFile file(path, "trace");
    const std::uint64_t size = file.size();
    mFile = file.releaseToStdio();
    try {
        unsigned char bytes[kTraceHeaderBytes];
        std::size_t got = std::fread(bytes, 1, kTraceHeaderBytesV1, mFile);
        if (got >= 8 && std::memcmp(bytes, kTraceMagic.data(), 8) != 0) {
            fail(0, "not a hapto trace (the file does not start with \"HAPTOTRC\")");
        }
        if (got < kTraceHeaderBytesV1) {
            fail(got, "truncated: the header needs " + std::to_string(kTraceHeaderBytesV1) +
                          " bytes, the file has " + std::to_string(got));
        }
        const std::uint32_t version = decodeTraceHeader(bytes, false).version;
        if (version != kTraceVersion && version != kTraceVersion1) {
            fail(8, "trace format version " + std::to_string(version) + "; this build reads " +
                        std::to_string(kTraceVersion1) + " and " + std::to_string(kTraceVersion));
        }
        const bool v2 = version >= 2;
        mHeaderBytes = v2 ? kTraceHeaderBytes : kTraceHeaderBytesV1;
        mSampleBytes = v2 ? kTraceSampleBytes : kTraceSampleBytesV1;
        if (v2) {
            got += std::fread(bytes + got, 1, kTraceHeaderBytes - got, mFile);
            if (got < kTraceHeaderBytes) {
                fail(got, "truncated: a version 2 header needs " +
                              std::to_string(kTraceHeaderBytes) + " bytes, the file has " +
                              std::to_string(got));
            }
        }
        const TraceHeaderFields h = decodeTraceHeader(bytes, v2);
        if (h.headerBytes != mHeaderBytes) {
            fail(12, "header size " + std::to_string(h.headerBytes) + ", expected " +
                         std::to_string(mHeaderBytes) + " for version " + std::to_string(version));
        }
        if (h.sampleBytes != mSampleBytes) {
            fail(16, "sample size " + std::to_string(h.sampleBytes) + ", expected " +
                         std::to_string(mSampleBytes) + " for version " + std::to_string(version));
        }
        if ((h.flags & ~kTraceHeaderMarksMisses) != 0) {
            fail(20, "unknown flags " + std::to_string(h.flags) + " (expected 0 or " +
                         std::to_string(kTraceHeaderMarksMisses) + ")");
        }
        if (!(h.rateHz > 0.0 && h.rateHz <= 1e6)) {
            std::ostringstream s;
            s << "servo rate " << h.rateHz << " Hz is not in (0, 1e6]";
            fail(24, s.str());
        }
        if (!text(h.kind.data(), h.kind.size(), mHeader.kind)) {
            fail(48, "the kind field is not NUL-padded printable ASCII");
        }
        if (!text(h.name.data(), h.name.size(), mHeader.name)) {
            fail(64, "the name field is not NUL-padded printable ASCII");
        }
        if (v2) {
            checkConfiguration(h);
        }
        const std::uint64_t body = size - mHeaderBytes;
        mHeader.version = h.version;
        mHeader.rateHz = h.rateHz;
        mHeader.startUnixNs = h.startUnixNs;
        mHeader.marksMisses = (h.flags & kTraceHeaderMarksMisses) != 0;
        if (h.sampleCount == kTraceCountUnfinished) {
            mHeader.finished = false;
            mHeader.sampleCount = body / mSampleBytes;
        } else {
            mHeader.finished = true;
            mHeader.sampleCount = h.sampleCount;
            if (h.sampleCount > body / mSampleBytes) {
                // A corrupt count can be so large that the byte count would not fit 64 bits.
                const std::uint64_t kMaxCount =
                    (std::numeric_limits<std::uint64_t>::max() - mHeaderBytes) / mSampleBytes;
                const std::string need =
                    h.sampleCount <= kMaxCount
                        ? std::to_string(mHeaderBytes + h.sampleCount * mSampleBytes) + " bytes"
                        : "more bytes than a file can hold";
                fail(size, "truncated: the header announces " + std::to_string(h.sampleCount) +
                               " samples (" + need + ") but the file ends after " +
                               std::to_string(size) + " bytes");
            }
            if (body != h.sampleCount * mSampleBytes) {
                fail(mHeaderBytes + h.sampleCount * mSampleBytes,
                     std::to_string(body - h.sampleCount * mSampleBytes) +
                         " unexpected bytes after the last of " + std::to_string(h.sampleCount) +
                         " samples");
            }
        }
    } catch (...) {
        std::fclose(mFile);
        mFile = nullptr;
        throw;
    }
}

void TraceReader::checkConfiguration(const TraceHeaderFields& h) {
    if (!finite(h.translation)) {
        fail(128, "the transform's translation is not finite");
    }
    const Quat q{h.rotation[0], h.rotation[1], h.rotation[2], h.rotation[3]};
    if (!std::isfinite(q.w) || !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) ||
        std::abs(glm::length(q) - 1.0) > 1e-6) {
        fail(152, "the transform's rotation is not a unit quaternion");
    }
    if (!(std::isfinite(h.scale) && h.scale > 0.0)) {
        fail(184, "the transform's scale is not a positive number");
    }
    if (!finite(h.toolTipM)) {
        fail(192, "the tool tip is not finite");
    }
    if (!(std::isfinite(h.maxForceN) && h.maxForceN >= 0.0)) {
        fail(216, "the force clamp is not a finite force >= 0 N");
    }
    for (std::size_t i = 0; i < h.reserved.size(); ++i) {
        if (h.reserved[i] != 0) {
            fail(224 + i, "reserved header bytes are not zero (corrupt header?)");
        }
    }
    mHeader.transform.translation = h.translation;
    mHeader.transform.rotation = q;
    mHeader.transform.scale = h.scale;
    mHeader.toolTipM = h.toolTipM;
    mHeader.maxForceN = h.maxForceN;
}

void TraceReader::checkVersion2(const TraceSample& s, const unsigned char* bytes,
                                std::uint64_t offset, const std::string& which) const {
    if (!finite(s.proxyM)) {
        fail(offset + 80, which + "proxy is not finite");
    }
    if (!finite(s.velocityMps)) {
        fail(offset + 104, which + "velocity is not finite");
    }
    const Quat& q = s.orientation;
    if (!std::isfinite(q.w) || !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z) ||
        std::abs(glm::length(q) - 1.0) > 1e-6) {
        fail(offset + 128, which + "orientation is not a unit quaternion");
    }
    if (!finite(s.angularVelocity)) {
        fail(offset + 160, which + "angular velocity is not finite");
    }
    if (s.contactCount > kTraceMaxContacts) {
        fail(offset + 184, which + "contact count " + std::to_string(s.contactCount) +
                               " is more than " + std::to_string(kTraceMaxContacts));
    }
    const std::uint32_t flags =
        static_cast<std::uint32_t>(bytes[188]) | static_cast<std::uint32_t>(bytes[189]) << 8 |
        static_cast<std::uint32_t>(bytes[190]) << 16 | static_cast<std::uint32_t>(bytes[191]) << 24;
    const std::uint32_t known = kTraceSampleHasVelocity | kTraceSampleHasOrientation |
                                kTraceSampleHasAngularVelocity |
                                (mHeader.marksMisses ? kTraceSampleMissedDeadline : 0u);
    if ((flags & ~known) != 0) {
        fail(offset + 188, which + "unknown sample flags " + std::to_string(flags));
    }
}

TraceReader::~TraceReader() {
    if (mFile) {
        std::fclose(mFile);
    }
}

bool TraceReader::next(TraceSample& out) {
    if (mIndex >= mHeader.sampleCount) {
        return false;
    }
    const std::uint64_t offset = mHeaderBytes + mIndex * mSampleBytes;
    unsigned char bytes[kTraceSampleBytes];
    if (std::fread(bytes, 1, mSampleBytes, mFile) != mSampleBytes) {
        fail(offset, "cannot read sample " + std::to_string(mIndex) + " (file changed?)");
    }
    const std::string which = "sample " + std::to_string(mIndex) + ": ";
    const TraceSample s = decodeTraceSample(bytes, mHeader.version);
    if (bytes[72] > static_cast<unsigned char>(DeviceStatus::Error)) {
        fail(offset + 72, which + "unknown device status " + std::to_string(bytes[72]));
    }
    if (bytes[73] != 0 || bytes[74] != 0 || bytes[75] != 0) {
        fail(offset + 73, which + "padding bytes are not zero (corrupt record?)");
    }
    if (!finite(s.positionM)) {
        fail(offset + 16, which + "position is not finite");
    }
    if (!finite(s.forceN)) {
        fail(offset + 40, which + "force is not finite");
    }
    if (mHeader.version >= 2) {
        checkVersion2(s, bytes, offset, which);
    }
    if (mHaveTick && s.tick <= mLastTick) {
        fail(offset, which + "tick " + std::to_string(s.tick) + " does not follow tick " +
                         std::to_string(mLastTick));
    }
    if (mHaveTick && s.timeNs < mLastTimeNs) {
        fail(offset + 8, which + "time goes backwards");
    }
    mHaveTick = true;
    mLastTick = s.tick;
    mLastTimeNs = s.timeNs;
    ++mIndex;
    out = s;
    return true;
}

std::vector<TraceSample> TraceReader::readAll() {
    std::vector<TraceSample> out;
    out.reserve(static_cast<std::size_t>(mHeader.sampleCount - mIndex));
    TraceSample s;
    while (next(s)) {
        out.push_back(s);
    }
    return out;
}

std::vector<TraceSample> TraceReader::load(const std::filesystem::path& path, TraceHeader* header) {
    TraceReader reader(path);
    if (header) {
        *header = reader.header();
    }
    return reader.readAll();
}

} // namespace hapto
