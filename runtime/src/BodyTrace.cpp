// The body trace (BodyTrace.h): its recorder, which drains the dynamics thread's ring into a
// temporary file renamed into place at close(), and its reader. Invariant: push() is the only
// member the dynamics thread calls, and it never blocks, allocates or throws.

#include "hapto/runtime/BodyTrace.h"

#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"

#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace hapto {

static_assert(std::endian::native == std::endian::little,
              "the body trace is written and read as little-endian bytes");

namespace {

constexpr char kMagic[8] = {'H', 'A', 'P', 'T', 'O', 'B', 'D', 'Y'};
constexpr std::size_t kFixedHeaderBytes = 32;

template <class T> void put(std::string& out, const T& v) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    out.append(bytes, sizeof(T));
}

template <class T> T get(const std::string& in, std::size_t at) {
    T v;
    std::memcpy(&v, in.data() + at, sizeof(T));
    return v;
}

void putVec(std::string& out, const Vec3& v) {
    put(out, v.x);
    put(out, v.y);
    put(out, v.z);
}

Vec3 getVec(const std::string& in, std::size_t at) {
    return Vec3(get<double>(in, at), get<double>(in, at + 8), get<double>(in, at + 16));
}

std::string encodeRecord(const BodyTraceSample& s) {
    std::string out;
    out.reserve(kBodyTraceRecordBytes);
    put(out, s.timeNs);
    put(out, s.body);
    put(out, std::uint32_t{0});
    putVec(out, s.centerOfMass);
    put(out, s.rotation.w);
    put(out, s.rotation.x);
    put(out, s.rotation.y);
    put(out, s.rotation.z);
    putVec(out, s.velocity);
    putVec(out, s.angularVelocity);
    return out;
}

BodyTraceSample decodeRecord(const std::string& in, std::size_t at) {
    BodyTraceSample s;
    s.timeNs = get<std::uint64_t>(in, at);
    s.body = get<std::uint32_t>(in, at + 8);
    s.centerOfMass = getVec(in, at + 16);
    s.rotation = Quat(get<double>(in, at + 40), get<double>(in, at + 48), get<double>(in, at + 56),
                      get<double>(in, at + 64));
    s.velocity = getVec(in, at + 72);
    s.angularVelocity = getVec(in, at + 96);
    return s;
}

bool finiteSample(const BodyTraceSample& s) {
    const double v[] = {
        s.centerOfMass.x,    s.centerOfMass.y,    s.centerOfMass.z,   s.rotation.w, s.rotation.x,
        s.rotation.y,        s.rotation.z,        s.velocity.x,       s.velocity.y, s.velocity.z,
        s.angularVelocity.x, s.angularVelocity.y, s.angularVelocity.z};
    for (double x : v) {
        if (!std::isfinite(x)) {
            return false;
        }
    }
    return true;
}

/// Checks the fixed header and returns the body count. Throws InputError.
std::uint32_t checkHeader(const std::string& bytes, const std::string& name) {
    if (bytes.size() < kFixedHeaderBytes || std::memcmp(bytes.data(), kMagic, 8) != 0) {
        throw InputError(name + ": not a hapto body trace (no HAPTOBDY header)");
    }
    const auto version = get<std::uint32_t>(bytes, 8);
    if (version != kBodyTraceVersion) {
        throw InputError(name + ": body trace version " + std::to_string(version) +
                         "; this build reads version " + std::to_string(kBodyTraceVersion));
    }
    const auto count = get<std::uint32_t>(bytes, 20);
    const auto headerBytes = get<std::uint32_t>(bytes, 12);
    if (headerBytes != kFixedHeaderBytes + 4ull * count || bytes.size() < headerBytes) {
        throw InputError(name + ": header size " + std::to_string(headerBytes) + " does not fit " +
                         std::to_string(count) + " bodies (or the file is cut short)");
    }
    if (get<std::uint32_t>(bytes, 16) != kBodyTraceRecordBytes) {
        throw InputError(name + ": record size " + std::to_string(get<std::uint32_t>(bytes, 16)) +
                         ", expected " + std::to_string(kBodyTraceRecordBytes));
    }
    return count;
}

} // namespace

BodyTrace readBodyTrace(const std::filesystem::path& path) {
    const std::string name = path.string();
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        throw InputError(name + ": cannot open the body trace");
    }
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::uint32_t count = checkHeader(bytes, name);
    BodyTrace trace;
    trace.rateHz = get<double>(bytes, 24);
    for (std::uint32_t i = 0; i < count; ++i) {
        trace.ids.push_back(get<std::uint32_t>(bytes, kFixedHeaderBytes + 4 * i));
    }
    const std::size_t start = kFixedHeaderBytes + 4ull * count;
    if ((bytes.size() - start) % kBodyTraceRecordBytes != 0) {
        throw InputError(name + ": " + std::to_string(bytes.size() - start) +
                         " bytes of records is not a whole number of " +
                         std::to_string(kBodyTraceRecordBytes) + "-byte records (cut short?)");
    }
    for (std::size_t at = start; at < bytes.size(); at += kBodyTraceRecordBytes) {
        const BodyTraceSample s = decodeRecord(bytes, at);
        const std::size_t k = (at - start) / kBodyTraceRecordBytes;
        if (s.body >= count) {
            throw InputError(name + ": record " + std::to_string(k) + " names body " +
                             std::to_string(s.body) + " of " + std::to_string(count));
        }
        if (!finiteSample(s)) {
            throw InputError(name + ": record " + std::to_string(k) + " holds a non-finite value");
        }
        trace.samples.push_back(s);
    }
    return trace;
}

bool isBodyTrace(const std::filesystem::path& path) {
    // Only a regular file is opened: a FIFO or a device would block the open or the read
    // (the device trace reader then refuses it with its message).
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        return false;
    }
    std::ifstream in(path, std::ios::binary);
    char magic[8] = {};
    return in.read(magic, sizeof magic) && std::memcmp(magic, kMagic, sizeof magic) == 0;
}

std::string bodyTraceCsvHeader() {
    return "time_s,id,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz\n";
}

void appendBodyTraceCsvRow(const BodyTrace& trace, const BodyTraceSample& s, std::string& out) {
    const auto append = [&out](auto v) {
        char buf[32];
        const auto res = std::to_chars(buf, buf + sizeof buf, v); // shortest exact form
        out.append(buf, res.ptr);
    };
    append(static_cast<double>(s.timeNs) * 1e-9);
    out += ',';
    append(trace.ids.at(s.body));
    const double v[] = {
        s.centerOfMass.x,    s.centerOfMass.y,    s.centerOfMass.z,   s.rotation.w, s.rotation.x,
        s.rotation.y,        s.rotation.z,        s.velocity.x,       s.velocity.y, s.velocity.z,
        s.angularVelocity.x, s.angularVelocity.y, s.angularVelocity.z};
    for (double x : v) {
        out += ',';
        append(x);
    }
    out += '\n';
}

BodyTraceRecorder::BodyTraceRecorder(const std::filesystem::path& path,
                                     std::span<const ObjectId> ids, double rateHz,
                                     std::size_t capacitySamples)
    : mPath(path), mFile(std::make_unique<AtomicOutputFile>(path)), mRing(capacitySamples) {
    mBatch.resize(std::min<std::size_t>(mRing.capacity(), 4096));
    std::string header(kMagic, 8);
    put(header, kBodyTraceVersion);
    put(header, static_cast<std::uint32_t>(kFixedHeaderBytes + 4 * ids.size()));
    put(header, kBodyTraceRecordBytes);
    put(header, static_cast<std::uint32_t>(ids.size()));
    put(header, rateHz);
    for (ObjectId id : ids) {
        put(header, static_cast<std::uint32_t>(id));
    }
    mFile->stream().write(header.data(), static_cast<std::streamsize>(header.size()));
    mOpen.store(true, std::memory_order_release);
}

BodyTraceRecorder::~BodyTraceRecorder() {
    abandon();
}

bool BodyTraceRecorder::push(const BodyTraceSample& sample) noexcept {
    if (!mOpen.load(std::memory_order_acquire) || !mRing.tryPush(sample)) {
        mDropped.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    return true;
}

std::size_t BodyTraceRecorder::drain() {
    if (!mFile) {
        return 0;
    }
    std::size_t total = 0;
    for (;;) {
        const std::size_t n = mRing.popInto(std::span<BodyTraceSample>(mBatch));
        if (n == 0) {
            break;
        }
        std::string bytes;
        bytes.reserve(n * kBodyTraceRecordBytes);
        for (std::size_t i = 0; i < n; ++i) {
            bytes += encodeRecord(mBatch[i]);
        }
        mFile->stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        if (!mFile->stream()) {
            throw std::runtime_error(mPath.string() + ": cannot write the body trace");
        }
        total += n;
    }
    mWritten += total;
    return total;
}

void BodyTraceRecorder::close() {
    if (!mFile) {
        return;
    }
    drain();
    mOpen.store(false, std::memory_order_release);
    mFile->commit();
    mFile.reset();
}

void BodyTraceRecorder::abandon() noexcept {
    mOpen.store(false, std::memory_order_release);
    mFile.reset(); // removes the temporary; the target stays as it was
}

} // namespace hapto
