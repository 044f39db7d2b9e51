#pragma once
/// The body trace: the dynamic bodies' states step by step, as `hapto run --record DIR` writes
/// them to DIR/bodies.trace, and the reader `hapto trace export` and `hapto view --trace` use.
///
/// Design note. The dynamics thread push()es one sample per body per dynamics step into a
/// lock-free SPSC ring (core/SpscRing.h), as a device's servo feeds its TraceRecorder; the
/// control thread drains the ring into a temporary file beside the target, and close() renames
/// it into place (io/OutputFile.h), so a trace is either the previous one or a whole new one.
/// A full ring drops the sample and counts it: the dynamics thread never waits.
///
/// The file, little-endian throughout (this build runs on little-endian hosts only):
///
///   offset size  field
///        0    8  magic "HAPTOBDY"
///        8    4  u32 version (kBodyTraceVersion = 1)
///       12    4  u32 header size in bytes (32 + 4 * body count)
///       16    4  u32 sample record size in bytes (kBodyTraceRecordBytes = 120)
///       20    4  u32 body count N
///       24    8  f64 dynamics rate (Hz)
///       32  4 N  N x u32 the bodies' scene object ids, in body order
///
/// Then records of 120 bytes, step by step, within a step body by body (every step is
/// recorded; a step whose samples did not fit the ring is missing whole or in part):
///
///        0    8  u64 time since the session started (ns): the step's deadline
///        8    4  u32 body index (< N)
///       12    4  u32 zero
///       16   24  3 x f64 centre of mass, world (m)
///       40   32  4 x f64 rotation, unit quaternion (w, x, y, z)
///       72   24  3 x f64 velocity of the centre of mass (m/s)
///       96   24  3 x f64 angular velocity (rad/s)

#include "hapto/core/Geometry.h"
#include "hapto/core/SpscRing.h"
#include "hapto/scenes/SceneObject.h"

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace hapto {

class AtomicOutputFile;

/// The body trace's format version this build writes and reads.
inline constexpr std::uint32_t kBodyTraceVersion = 1;
/// Bytes per sample record.
inline constexpr std::uint32_t kBodyTraceRecordBytes = 120;
/// The body trace's file name inside a `--record` folder.
inline constexpr const char* kBodyTraceFileName = "bodies.trace";

/// One body's state at one dynamics step.
struct BodyTraceSample {
    std::uint64_t timeNs = 0;  ///< Since the session started (ns).
    std::uint32_t body = 0;    ///< Body index (in the trace's id list).
    Vec3 centerOfMass{0.0};    ///< World (m).
    Quat rotation{1, 0, 0, 0}; ///< Unit quaternion.
    Vec3 velocity{0.0};        ///< Of the centre of mass (m/s).
    Vec3 angularVelocity{0.0}; ///< (rad/s).
};

/// A whole body trace, read.
struct BodyTrace {
    double rateHz = 0;                    ///< Dynamics rate (Hz).
    std::vector<ObjectId> ids;            ///< Scene object id of each body.
    std::vector<BodyTraceSample> samples; ///< In file order.
};

/// Reads a body trace. Throws InputError naming the file and what is wrong (not a body trace,
/// another version, truncated, a body index out of range, a non-finite value). [control]
BodyTrace readBodyTrace(const std::filesystem::path& path);

/// True when `path` is a readable regular file beginning with the body trace's magic (a FIFO
/// or device is never opened: false). [control]
bool isBodyTrace(const std::filesystem::path& path);

/// The CSV export's header row, newline included: `time_s,id,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,
/// wy,wz`; time in s since the session started, id the scene object's, x,y,z its centre of
/// mass (m, world), the rotation, the velocity (m/s) and the angular velocity (rad/s). [any
/// thread]
std::string bodyTraceCsvHeader();
/// Appends one sample of `trace` as a CSV row (numbers that read back exactly). [any thread]
void appendBodyTraceCsvRow(const BodyTrace& trace, const BodyTraceSample& sample, std::string& out);

/// Writes DIR/bodies.trace from the dynamics thread's samples without ever making it wait.
/// One producer thread (the dynamics thread or the stepping thread) and one consumer.
class BodyTraceRecorder {
public:
    /// Creates the temporary beside `path` and writes the header. Throws InputError when the
    /// file cannot be created. [control]
    BodyTraceRecorder(const std::filesystem::path& path, std::span<const ObjectId> ids,
                      double rateHz, std::size_t capacitySamples = std::size_t{1} << 16);
    /// Abandons the recording unless close() was called. [control]
    ~BodyTraceRecorder();
    BodyTraceRecorder(const BodyTraceRecorder&) = delete;
    BodyTraceRecorder& operator=(const BodyTraceRecorder&) = delete;

    /// Queues a sample; false (and one more dropped()) when the ring is full or the recorder
    /// closed. Never blocks, allocates or throws. [dynamics]
    bool push(const BodyTraceSample& sample) noexcept;
    /// Writes every queued sample; returns how many. Throws std::runtime_error on a write
    /// failure. [control]
    std::size_t drain();
    /// Drains and renames the file into place; once the producer has stopped. Safe to call
    /// twice. Throws std::runtime_error when the file cannot be written. [control]
    void close();
    /// Drops the recording: the target is left as it was. [control]
    void abandon() noexcept;

    /// Samples dropped (ring full, or closed). [any thread]
    std::uint64_t dropped() const noexcept { return mDropped.load(std::memory_order_relaxed); }
    /// Samples written so far. [control]
    std::uint64_t written() const { return mWritten; }
    /// The trace file. [any thread]
    const std::filesystem::path& path() const { return mPath; }

private:
    std::filesystem::path mPath;
    std::unique_ptr<AtomicOutputFile> mFile;
    SpscRing<BodyTraceSample> mRing;
    std::vector<BodyTraceSample> mBatch;
    std::atomic<bool> mOpen{false};
    std::atomic<std::uint64_t> mDropped{0};
    std::uint64_t mWritten = 0;
};

} // namespace hapto
