#pragma once
/// The binary trace file: one device's servo ticks, as `hapto run --record` writes them.
///
/// Little-endian throughout, fixed sizes, no padding ambiguity (every field is encoded byte by
/// byte). Header, 128 bytes:
///
///   offset size  field
///        0    8  magic "HAPTOTRC"
///        8    4  u32 version (kTraceVersion = 1)
///       12    4  u32 header size in bytes (128)
///       16    4  u32 sample record size in bytes (80)
///       20    4  u32 flags (0; reserved)
///       24    8  f64 servo rate (Hz)
///       32    8  u64 sample count; kTraceCountUnfinished until the recorder is closed
///       40    8  u64 start of the recording, Unix time (ns); 0 = unknown
///       48   16  kind, NUL-padded ASCII ("sim", "falcon", ...)
///       64   64  device name, NUL-padded ASCII (at most 63 bytes)
///
/// Then `sample count` records of 80 bytes:
///
///        0    8  u64 tick index (strictly increasing; gaps are ticks not recorded)
///        8    8  u64 time since the session started (ns)
///       16   24  3 x f64 position, device frame (m)
///       40   24  3 x f64 force written, device frame (N)
///       64    4  u32 compute time: wake-up to force written (ns)
///       68    4  u32 device I/O time: read + write (ns)
///       72    1  u8 DeviceStatus of the tick's read
///       73    3  zero
///       76    4  u32 buttons
///
/// 1 kHz for an hour is 288 MB.

#include "hapto/devices/Device.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace hapto {

/// The trace format version this build reads and writes.
inline constexpr std::uint32_t kTraceVersion = 1;
/// The file's first 8 bytes.
inline constexpr std::array<char, 8> kTraceMagic = {'H', 'A', 'P', 'T', 'O', 'T', 'R', 'C'};
/// Header size (bytes).
inline constexpr std::size_t kTraceHeaderBytes = 128;
/// Size of one sample record (bytes).
inline constexpr std::size_t kTraceSampleBytes = 80;
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

    bool operator==(const TraceSample&) const = default;
};

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
};

/// The header's fields as stored, before any validation (TraceReader checks them).
struct TraceHeaderFields {
    std::array<char, 8> magic{};   ///< Should be kTraceMagic.
    std::uint32_t version = 0;     ///< Should be kTraceVersion.
    std::uint32_t headerBytes = 0; ///< Should be kTraceHeaderBytes.
    std::uint32_t sampleBytes = 0; ///< Should be kTraceSampleBytes.
    std::uint32_t flags = 0;       ///< Should be 0.
    double rateHz = 0.0;           ///< Servo rate (Hz).
    std::uint64_t sampleCount = 0; ///< Or kTraceCountUnfinished.
    std::uint64_t startUnixNs = 0; ///< Recording start (ns, Unix time).
    std::array<char, 16> kind{};   ///< NUL-padded.
    std::array<char, 64> name{};   ///< NUL-padded.
};

/// Decodes the 128 header bytes (no validation). [any thread]
TraceHeaderFields decodeTraceHeader(const unsigned char* in);
/// Encodes a header into its 128 bytes; names longer than the field are cut. [any thread]
void encodeTraceHeader(const TraceHeader& header, std::uint64_t sampleCount, unsigned char* out);
/// Encodes a sample into its 80 bytes; allocates nothing. [servo]
void encodeTraceSample(const TraceSample& sample, unsigned char* out) noexcept;
/// Decodes a sample from its 80 bytes (no validation). [any thread]
TraceSample decodeTraceSample(const unsigned char* in) noexcept;

} // namespace hapto
