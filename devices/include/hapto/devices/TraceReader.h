#pragma once
/// Reads and validates trace files (TraceFormat.h).

#include "hapto/devices/TraceFormat.h"

#include <cstdio>
#include <filesystem>
#include <vector>

namespace hapto {

/// Reads a trace file (version 1 or 2) sample by sample, checking everything: magic, version,
/// sizes, rate, the recorded configuration (version 2: finite transform, unit rotation,
/// positive scale, finite tool tip, zero reserved bytes), that the file holds exactly the
/// samples its header announces, and per sample a known status, finite position and force,
/// zero padding, strictly increasing ticks (version 2 also: finite proxy and velocity, a unit
/// orientation, at most kTraceMaxContacts contacts, known flags). Any problem is an
/// InputError naming the file and the byte offset. A trace whose recorder was never closed (a
/// crash) reads its whole records and ignores a partial last one. All [control].
class TraceReader {
public:
    /// Opens `path` and checks the header against the file size. Throws InputError, also for
    /// anything but a regular file (a FIFO, a pipe, a device) and for a file larger than
    /// kMaxInputFileBytes (hapto/io/InputFile.h). [control]
    explicit TraceReader(const std::filesystem::path& path);
    ~TraceReader();
    TraceReader(const TraceReader&) = delete;
    TraceReader& operator=(const TraceReader&) = delete;

    /// The header. [control]
    const TraceHeader& header() const { return mHeader; }
    /// Reads the next sample into `out`; false at the end. Throws InputError on a bad sample or
    /// a read failure. [control]
    bool next(TraceSample& out);
    /// Reads every remaining sample. Throws InputError. [control]
    std::vector<TraceSample> readAll();

    /// Loads a whole trace: header and samples. Throws InputError. [control]
    static std::vector<TraceSample> load(const std::filesystem::path& path,
                                         TraceHeader* header = nullptr);

private:
    [[noreturn]] void fail(std::uint64_t offset, const std::string& what) const;
    void checkConfiguration(const TraceHeaderFields& h);
    void checkVersion2(const TraceSample& s, const unsigned char* bytes, std::uint64_t offset,
                       const std::string& which) const;

    std::filesystem::path mPath;
    std::FILE* mFile = nullptr;
    TraceHeader mHeader;
    std::size_t mHeaderBytes = kTraceHeaderBytes;
    std::size_t mSampleBytes = kTraceSampleBytes;
    std::uint64_t mIndex = 0;
    bool mHaveTick = false;
    std::uint64_t mLastTick = 0;
    std::uint64_t mLastTimeNs = 0;
};

} // namespace hapto
