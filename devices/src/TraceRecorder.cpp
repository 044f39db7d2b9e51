#include "hapto/devices/TraceRecorder.h"

#include "hapto/scenes/InputError.h"

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace hapto {
namespace {

constexpr std::size_t kBatch = 1024;

[[noreturn]] void writeFailed(const std::filesystem::path& path) {
    throw std::runtime_error(path.string() + ": writing the trace failed (" + std::strerror(errno) +
                             "; disk full?)");
}

} // namespace

TraceRecorder::TraceRecorder(const std::filesystem::path& path, const TraceHeader& header,
                             std::size_t capacitySamples)
    : mPath(path), mHeader(header), mRing(capacitySamples), mBatch(kBatch),
      mBytes(kBatch * kTraceSampleBytes) {
    mFile = std::fopen(path.c_str(), "wb");
    if (!mFile) {
        throw InputError(path.string() + ": cannot create the trace file (" + std::strerror(errno) +
                         "; does the folder exist and is it writable?)");
    }
    unsigned char bytes[kTraceHeaderBytes];
    encodeTraceHeader(mHeader, kTraceCountUnfinished, bytes);
    if (std::fwrite(bytes, 1, sizeof bytes, mFile) != sizeof bytes) {
        std::fclose(mFile);
        mFile = nullptr;
        writeFailed(path);
    }
    mOpen.store(true, std::memory_order_release);
}

TraceRecorder::~TraceRecorder() {
    try {
        close();
    } catch (const std::exception&) {
        // Reported by close() when the owner calls it; a destructor cannot.
    }
}

bool TraceRecorder::push(const TraceSample& sample) noexcept {
    if (!mOpen.load(std::memory_order_acquire) || !mRing.tryPush(sample)) {
        mDropped.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    return true;
}

std::size_t TraceRecorder::drain() {
    if (!mFile) {
        return 0;
    }
    std::size_t total = 0;
    for (;;) {
        const std::size_t n = mRing.popInto(mBatch);
        if (n == 0) {
            break;
        }
        for (std::size_t i = 0; i < n; ++i) {
            encodeTraceSample(mBatch[i], mBytes.data() + i * kTraceSampleBytes);
        }
        if (std::fwrite(mBytes.data(), kTraceSampleBytes, n, mFile) != n) {
            writeFailed(mPath);
        }
        total += n;
        mWritten += n;
    }
    return total;
}

void TraceRecorder::close() {
    if (!mFile) {
        return;
    }
    mOpen.store(false, std::memory_order_release);
    std::FILE* file = mFile;
    try {
        drain();
    } catch (...) {
        std::fclose(file);
        mFile = nullptr;
        throw;
    }
    mFile = nullptr;
    unsigned char bytes[kTraceHeaderBytes];
    encodeTraceHeader(mHeader, mWritten, bytes);
    const bool ok = std::fflush(file) == 0 && std::fseek(file, 0, SEEK_SET) == 0 &&
                    std::fwrite(bytes, 1, sizeof bytes, file) == sizeof bytes;
    if (std::fclose(file) != 0 || !ok) {
        writeFailed(mPath);
    }
}

} // namespace hapto
