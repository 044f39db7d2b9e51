#include "hapto/devices/TraceRecorder.h"

#include "hapto/io/InputError.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <random>
#include <stdexcept>
#include <unistd.h>

namespace hapto {
namespace {

constexpr std::size_t kBatch = 1024;

[[noreturn]] void writeFailed(const std::filesystem::path& path) {
    throw std::runtime_error(path.string() + ": writing the trace failed (" + std::strerror(errno) +
                             "; disk full?)");
}

/// Creates a new file `<path>.tmp-XXXXXX` beside `path`: exclusively and never through a
/// symlink (O_EXCL | O_NOFOLLOW), so an existing file or link is neither followed nor truncated.
std::FILE* createTemporary(const std::filesystem::path& path, std::filesystem::path& temporary) {
    std::random_device random;
    const char* digits = "0123456789abcdefghijklmnopqrstuvwxyz";
    int fd = -1;
    for (int attempt = 0; attempt < 100 && fd < 0; ++attempt) {
        std::string suffix = ".tmp-";
        for (int i = 0; i < 6; ++i) {
            suffix += digits[random() % 36];
        }
        temporary = path;
        temporary += suffix;
        fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
        if (fd < 0 && errno != EEXIST) {
            break;
        }
    }
    if (fd < 0) {
        return nullptr;
    }
    std::FILE* file = ::fdopen(fd, "wb");
    if (!file) {
        const int error = errno;
        ::close(fd);
        ::unlink(temporary.c_str());
        errno = error;
    }
    return file;
}

} // namespace

TraceRecorder::TraceRecorder(const std::filesystem::path& path, const TraceHeader& header,
                             std::size_t capacitySamples)
    : mPath(path), mHeader(header), mRing(capacitySamples), mBatch(kBatch),
      mBytes(kBatch * kTraceSampleBytes) {
    if (std::filesystem::is_directory(path)) {
        throw InputError(path.string() + ": cannot create the trace file: a folder has its name");
    }
    mFile = createTemporary(path, mTemporary);
    if (!mFile) {
        throw InputError(path.string() + ": cannot create the trace file (" + std::strerror(errno) +
                         "; does the folder exist and is it writable?)");
    }
    unsigned char bytes[kTraceHeaderBytes];
    encodeTraceHeader(mHeader, kTraceCountUnfinished, bytes);
    if (std::fwrite(bytes, 1, sizeof bytes, mFile) != sizeof bytes) {
        std::fclose(mFile);
        mFile = nullptr;
        ::unlink(mTemporary.c_str());
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

void TraceRecorder::abandon() noexcept {
    if (!mFile) {
        return;
    }
    mOpen.store(false, std::memory_order_release);
    std::fclose(mFile);
    mFile = nullptr;
    ::unlink(mTemporary.c_str());
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
        ::unlink(mTemporary.c_str());
        throw;
    }
    mFile = nullptr;
    unsigned char bytes[kTraceHeaderBytes];
    encodeTraceHeader(mHeader, mWritten, bytes);
    bool ok = std::fflush(file) == 0 && std::fseek(file, 0, SEEK_SET) == 0 &&
              std::fwrite(bytes, 1, sizeof bytes, file) == sizeof bytes && std::fflush(file) == 0 &&
              ::fsync(::fileno(file)) == 0;
    int error = errno;
    if (std::fclose(file) != 0 && ok) {
        ok = false;
        error = errno;
    }
    // The finished file takes the trace's name only now, replacing (not following) whatever
    // had it; a failure leaves that as it was.
    if (ok && ::rename(mTemporary.c_str(), mPath.c_str()) != 0) {
        ok = false;
        error = errno;
    }
    if (!ok) {
        ::unlink(mTemporary.c_str());
        errno = error;
        writeFailed(mPath);
    }
}

} // namespace hapto
