#pragma once
/// Records a device's servo ticks to a trace file without ever making the servo thread wait.

#include "hapto/core/SpscRing.h"
#include "hapto/devices/TraceFormat.h"

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <vector>

namespace hapto {

/// Writes one trace file (TraceFormat.h). The servo thread push()es each tick into a lock-free
/// SPSC ring; a control thread calls drain() now and then (every 100 ms is plenty: the default
/// ring of 65 536 samples holds 65 s at 1 kHz) to write what is queued, and close() to finish
/// the file. When the ring is full, push() drops the sample and
/// counts it. One producer thread and one consumer thread at a time.
///
/// The samples go to a temporary file beside the trace (`<path>.tmp-XXXXXX`, created
/// exclusively, never through a symlink), which close() renames to `path` once the header is
/// final: a trace file is either the previous one or a finished new one, never half written.
class TraceRecorder {
public:
    /// Creates the temporary beside `path` and writes a header marked unfinished (`path`
    /// itself is left alone until close()); `capacitySamples` is rounded up to a power of two.
    /// Throws InputError when the file cannot be created (no such folder, not writable, `path`
    /// a folder). [control]
    TraceRecorder(const std::filesystem::path& path, const TraceHeader& header,
                  std::size_t capacitySamples = std::size_t{1} << 16);
    /// Closes (so the recording so far becomes `path`), swallowing errors (call close() to see
    /// them). [control]
    ~TraceRecorder();
    TraceRecorder(const TraceRecorder&) = delete;
    TraceRecorder& operator=(const TraceRecorder&) = delete;

    /// Queues a sample; false (and one more dropped()) when the ring is full. Never blocks,
    /// allocates or throws. [servo]
    bool push(const TraceSample& sample) noexcept;
    /// Writes every queued sample to the file; returns how many. Throws std::runtime_error on a
    /// write failure (disk full). [control]
    std::size_t drain();
    /// Drains, writes the final sample count into the header, closes the file and renames it to
    /// path() (on failure the temporary is removed and path() left as it was). Call it once
    /// the producer has stopped (a push racing with close() may be lost uncounted). Safe to call
    /// twice; after it, push() drops. Throws std::runtime_error on a write failure. [control]
    void close();

    /// Drops the recording: the temporary is removed and path() left as it was (a session
    /// that never started must not replace an older trace with an empty one). Safe after
    /// close() (then it does nothing). [control]
    void abandon() noexcept;

    /// Samples dropped because the ring was full (or the recorder closed). [any thread]
    std::uint64_t dropped() const noexcept { return mDropped.load(std::memory_order_relaxed); }
    /// Samples written to the file so far. [control]
    std::uint64_t written() const { return mWritten; }
    /// Ring capacity (samples). [any thread]
    std::size_t capacity() const { return mRing.capacity(); }
    /// The trace file (written at close()). [any thread]
    const std::filesystem::path& path() const { return mPath; }

private:
    std::filesystem::path mPath;
    std::filesystem::path mTemporary; // where the samples go until close()
    TraceHeader mHeader;
    SpscRing<TraceSample> mRing;
    std::FILE* mFile = nullptr;
    std::atomic<bool> mOpen{false};
    std::atomic<std::uint64_t> mDropped{0};
    std::uint64_t mWritten = 0;
    std::vector<TraceSample> mBatch;
    std::vector<unsigned char> mBytes;
};

} // namespace hapto
