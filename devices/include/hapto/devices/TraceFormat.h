#pragma once
/// The binary trace file: one device's servo ticks, as `hapto run --record` writes them.
///
/// Little-endian throughout, fixed sizes, no padding ambiguity (every field is encoded byte by
/// byte). This build writes version 2 and reads versions 1 and 2. Header, 256 bytes (version
/// 1: the first 128 only):
///
///   offset size  field
///        0    8  magic "HAPTOTRC"
///        8    4  u32 version (kTraceVersion = 2; 1 in older files)
///       12    4  u32 header size in bytes (256; 128 in version 1)
///       16    4  u32 sample record size in bytes (192; 80 in version 1)
///       20    4  u32 flags: bit 0 the samples mark missed deadlines (sample flag bit 3); the
///                other bits zero (files from before the mark have 0)
///       24    8  f64 servo rate (Hz)
///       32    8  u64 sample count; kTraceCountUnfinished until the recorder is closed
///       40    8  u64 start of the recording, Unix time (ns); 0 = unknown
///       48   16  kind, NUL-padded ASCII ("sim", "falcon", ...)
///       64   64  device name, NUL-padded ASCII (at most 63 bytes)
///   version 2 only, the device configuration the run used:
///      128   24  3 x f64 transform translation (m): where the device origin sits in the world
///      152   32  4 x f64 transform rotation, unit quaternion (w, x, y, z)
///      184    8  f64 transform scale (world m per device m, > 0)
///      192   24  3 x f64 tool tip (m, stylus frame; 0 = the gimbal centre)
///      216    8  f64 force clamp, the device's `max_force_n` (N, >= 0; 0 = the default)
///      224   32  zero (reserved)
///
/// Then `sample count` records of 192 bytes (version 1: the first 80 only):
///
///        0    8  u64 tick index (strictly increasing; gaps are ticks not recorded)
///        8    8  u64 time since the session started (ns)
///       16   24  3 x f64 position read (gimbal centre), device frame (m)
///       40   24  3 x f64 force written, device frame (N)
///       64    4  u32 compute time: wake-up to force written (ns)
///       68    4  u32 device I/O time: read + write (ns)
///       72    1  u8 DeviceStatus of the tick's read
///       73    3  zero
///       76    4  u32 buttons
///   version 2 only:
///       80   24  3 x f64 proxy, device frame (m) (the god object of the contact point)
///      104   24  3 x f64 velocity read, device frame (m/s); zero unless flag bit 0
///      128   32  4 x f64 stylus orientation, unit quaternion (w, x, y, z), device frame;
///                (1, 0, 0, 0) unless flag bit 1
///      160   24  3 x f64 stylus angular velocity, device frame (rad/s); zero unless flag bit 2
///      184    4  u32 contact count (0..3)
///      188    4  u32 flags: bit 0 the device gave a velocity, bit 1 an orientation, bit 2 an
///                angular velocity, bit 3 the tick missed its deadline (its force was written
///                after the next deadline: the runtime counted a miss); the other bits zero
///
/// 1 kHz for an hour is 691 MB (288 MB in version 1).

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace hapto {

/// The trace format version this build writes (it reads kTraceVersion1 too).
inline constexpr std::uint32_t kTraceVersion = 2;
/// The first version, still read: no device configuration, no proxy, velocity, orientation
/// or contact count.
inline constexpr std::uint32_t kTraceVersion1 = 1;
/// The file's first 8 bytes.
inline constexpr std::array<char, 8> kTraceMagic = {'H', 'A', 'P', 'T', 'O', 'T', 'R', 'C'};
/// Header size (bytes).
inline constexpr std::size_t kTraceHeaderBytes = 256;
/// Size of one sample record (bytes).
inline constexpr std::size_t kTraceSampleBytes = 192;
/// Header size of a version 1 trace (bytes).
inline constexpr std::size_t kTraceHeaderBytesV1 = 128;
/// Sample record size of a version 1 trace (bytes).
inline constexpr std::size_t kTraceSampleBytesV1 = 80;
/// The most contacts a sample records (the renderer's GodObjectRenderer::kMaxContacts).
inline constexpr std::uint32_t kTraceMaxContacts = 3;
/// Sample flag: the velocity field is the device's.
inline constexpr std::uint32_t kTraceSampleHasVelocity = 1u << 0;
/// Sample flag: the orientation field is the device's.
inline constexpr std::uint32_t kTraceSampleHasOrientation = 1u << 1;
/// Sample flag: the angular velocity field is the device's.
inline constexpr std::uint32_t kTraceSampleHasAngularVelocity = 1u << 2;
/// Sample flag: the tick missed its deadline (meaningful when the header has
/// kTraceHeaderMarksMisses).
inline constexpr std::uint32_t kTraceSampleMissedDeadline = 1u << 3;
/// Header flag: every sample says whether its tick missed its deadline
/// (kTraceSampleMissedDeadline). Traces written before the mark existed have it clear; a reader
/// then knows only the wake-ups.
inline constexpr std::uint32_t kTraceHeaderMarksMisses = 1u << 0;
/// The sample count of a trace whose recorder was never closed (a crash).
inline constexpr std::uint64_t kTraceCountUnfinished = ~std::uint64_t{0};
/// Longest device name a trace holds (bytes).
inline constexpr std::size_t kTraceMaxNameBytes = 63;
/// Longest kind a trace holds (bytes).
inline constexpr std::size_t kTraceMaxKindBytes = 15;

/// One servo tick, as recorded.
struct TraceSample {
    std::uint64_t tick = 0;                 ///< Tick index since the session started.
    std::uint64_t timeNs = 0;               ///< Wake-up time since the session started (ns).
    Vec3 positionM{0.0};                    ///< Position read, device frame (m).
    Vec3 forceN{0.0};                       ///< Force written, device frame (N).
    std::uint32_t computeNs = 0;            ///< Wake-up to force written (ns).
    std::uint32_t ioNs = 0;                 ///< Time in device read + write (ns).
    DeviceStatus status = DeviceStatus::Ok; ///< The read's status.
    std::uint32_t buttons = 0;              ///< Buttons read.
    // Version 2 only (a version 1 sample reads them as their defaults).
    Vec3 proxyM{0.0};                ///< God-object proxy, device frame (m).
    Vec3 velocityMps{0.0};           ///< Velocity read, device frame (m/s), if hasVelocity.
    Quat orientation{1, 0, 0, 0};    ///< Stylus orientation, device frame, if hasOrientation.
    Vec3 angularVelocity{0.0};       ///< Stylus angular velocity, device frame (rad/s), if
                                     ///< hasAngularVelocity.
    std::uint32_t contactCount = 0;  ///< Constraints the renderer held (0..3).
    bool hasVelocity = false;        ///< The device gave the velocity.
    bool hasOrientation = false;     ///< The device gave the orientation.
    bool hasAngularVelocity = false; ///< The device gave the angular velocity.
    bool missedDeadline = false;     ///< The tick's force came after its deadline (a miss).

    /// Field by field, exactly (a replayed tick equals the recorded one bit for bit).
    bool operator==(const TraceSample&) const = default;
};

/// A reading's motion into a sample: position, velocity, orientation and angular velocity (each
/// with its flag) and buttons; the rest of the sample is the recorder's. [any thread]
void stateToSample(const DeviceState& state, TraceSample& sample) noexcept;
/// A sample's motion as a reading (the same fields; sequence and gimbal angles untouched).
/// [any thread]
void sampleToState(const TraceSample& sample, DeviceState& state) noexcept;

/// What a trace says about itself.
struct TraceHeader {
    std::uint32_t version = kTraceVersion; ///< Format version.
    double rateHz = 1000.0;                ///< Servo rate (Hz).
    std::uint64_t sampleCount = 0;         ///< Samples in the file (for an unfinished file:
                                           ///< the whole records present).
    bool finished = true;                  ///< False when the recorder was never closed.
    std::uint64_t startUnixNs = 0;         ///< Recording start, Unix time (ns); 0 = unknown.
    std::string kind;                      ///< Device kind ("sim", ...).
    std::string name;                      ///< Device name ("left", ...).
    bool marksMisses = true;               ///< Samples carry missedDeadline (false in traces
                                           ///< written before the mark; this build writes it).
    // Version 2 only: the configuration the run used (a version 1 trace reads the defaults).
    WorkspaceTransform transform; ///< Device frame into the world.
    Vec3 toolTipM{0.0};           ///< Tool tip in the stylus frame (m).
    double maxForceN = 0.0;       ///< The force clamp (N); 0 = the runtime's default.

    /// True when the trace says which transform and tool tip it was recorded with. [any thread]
    bool hasConfiguration() const { return version >= 2; }
};

/// The header's fields as stored, before any validation (TraceReader checks them).
struct TraceHeaderFields {
    std::array<char, 8> magic{};   ///< Should be kTraceMagic.
    std::uint32_t version = 0;     ///< Should be kTraceVersion.
    std::uint32_t headerBytes = 0; ///< Should be kTraceHeaderBytes.
    std::uint32_t sampleBytes = 0; ///< Should be kTraceSampleBytes.
    std::uint32_t flags = 0;       ///< Only kTraceHeaderMarksMisses may be set.
    double rateHz = 0.0;           ///< Servo rate (Hz).
    std::uint64_t sampleCount = 0; ///< Or kTraceCountUnfinished.
    std::uint64_t startUnixNs = 0; ///< Recording start (ns, Unix time).
    std::array<char, 16> kind{};   ///< NUL-padded.
    std::array<char, 64> name{};   ///< NUL-padded.
    // Version 2 only.
    Vec3 translation{0.0};                    ///< Transform translation (m).
    std::array<double, 4> rotation{};         ///< Transform rotation (w, x, y, z).
    double scale = 0.0;                       ///< Transform scale.
    Vec3 toolTipM{0.0};                       ///< Tool tip (m).
    double maxForceN = 0.0;                   ///< Force clamp (N).
    std::array<unsigned char, 32> reserved{}; ///< Should be zero.
};

/// Decodes the first 128 header bytes, and when `version2` the 128 after them (no validation).
/// [any thread]
TraceHeaderFields decodeTraceHeader(const unsigned char* in, bool version2);
/// Encodes a version 2 header into its kTraceHeaderBytes (header.version is not read: this
/// build writes kTraceVersion); names longer than the field are cut. [any thread]
void encodeTraceHeader(const TraceHeader& header, std::uint64_t sampleCount, unsigned char* out);
/// Encodes a sample into its kTraceSampleBytes (version 2); allocates nothing. [servo]
void encodeTraceSample(const TraceSample& sample, unsigned char* out) noexcept;
/// Decodes a sample of the given version from its 80 (version 1) or 192 bytes (no
/// validation). [any thread]
TraceSample decodeTraceSample(const unsigned char* in, std::uint32_t version) noexcept;

} // namespace hapto
