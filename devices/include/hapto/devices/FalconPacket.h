#pragma once
/// The Novint Falcon's 16-byte I/O packets and the byte-stream reassembler that finds them.
//
// Design note. The Falcon firmware talks in 16-byte frames: '<', 14 nibble bytes (each a 4-bit
// value plus 0x41, so 'A'..'P'), '>'. The host sends three int16 motor words and a flag nibble
// (homing, LEDs); the device answers with three int16 encoder counts and a flag byte (grip
// buttons, per-motor "homed"). Over USB the FTDI bridge prefixes every IN transfer with two
// modem-status bytes and may split or merge frames arbitrarily, so the reassembler strips those
// two bytes and scans the remaining stream for valid frames, skipping garbage byte by byte.
// The device's flag byte has 8 bits but a frame byte carries one nibble, so it is read like the
// words, least significant nibble first: byte 13 holds the buttons (bits 0-3), byte 14 the homed
// flags (bits 4-6); its top bit (flag bit 7) has no known meaning and is carried through as is.
// Host commands put their flag nibble in byte 13 and 'A' (0) in byte 14.
// (Our reading of the protocol notes; to be confirmed on hardware.)
// Invariant: every function here is pure or works on a fixed-size buffer; nothing allocates,
// throws or reads outside the span it is given, whatever the input (these are fuzz targets).
// Cost: O(bytes) per call, a few nanoseconds per byte.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace hapto::falcon {

/// Bytes in one I/O frame, either direction.
inline constexpr std::size_t kPacketSize = 16;
/// Payload bytes an FTDI IN transfer can carry after its 2 modem-status bytes.
inline constexpr std::size_t kMaxPayloadPerTransfer = 62;
/// The FTDI modem-status bytes at the start of every IN transfer.
inline constexpr std::size_t kFtdiStatusBytes = 2;

/// One raw frame on the wire.
using Packet = std::array<std::uint8_t, kPacketSize>;

/// Host-to-device command: three motor words and the flag nibble.
struct FalconCommand {
    std::array<std::int16_t, 3> motor{}; ///< Motor command words (dimensionless, -torque * 1e4).
    bool homing = false;                 ///< Homing mode bit (bit 0 of byte 13).
    bool ledGreen = false;               ///< Green LED (bit 1).
    bool ledBlue = false;                ///< Blue LED (bit 2).
    bool ledRed = false;                 ///< Red LED (bit 3).

    /// Field-wise equality. [any thread]
    bool operator==(const FalconCommand&) const = default;
};

/// Device-to-host reading: three encoder counts, grip buttons and homed flags.
struct FalconReading {
    std::array<std::int16_t, 3> encoder{}; ///< Encoder counts per motor.
    std::uint8_t buttons = 0;              ///< Grip buttons, bits 0-3.
    std::uint8_t homedMask = 0;            ///< Bit i set once motor i is homed, bits 0-2.
    bool flagBit7 = false; ///< Bit 7 of the flag byte (top bit of byte 14), unused as far as we
                           ///< know; kept so that a decoded frame re-encodes to its own bytes.

    /// True when all three motors report homed. [any thread]
    bool allHomed() const { return homedMask == 0x7; }
    /// Field-wise equality. [any thread]
    bool operator==(const FalconReading&) const = default;
};

/// Encodes a host command into a frame. [any thread]
Packet encodeCommand(const FalconCommand& command);
/// Decodes a host command frame; nullopt unless `bytes` is exactly one valid frame. [any thread]
std::optional<FalconCommand> decodeCommand(std::span<const std::uint8_t> bytes);
/// Encodes a device reading into a frame (used by emulators and tests). [any thread]
Packet encodeReading(const FalconReading& reading);
/// Decodes a device reading; nullopt unless `bytes` is exactly one valid frame. Never reads
/// outside `bytes`, whatever it holds. [any thread]
std::optional<FalconReading> decode(std::span<const std::uint8_t> bytes);
/// True when `bytes` is exactly one well-formed frame ('<', 14 bytes in 'A'..'P', '>'). [any
/// thread]
bool isValidFrame(std::span<const std::uint8_t> bytes);

/// Counters kept by the reassembler (monotonic).
struct FalconStreamStats {
    std::uint64_t frames = 0;         ///< Valid frames found.
    std::uint64_t garbageBytes = 0;   ///< Bytes skipped because they start no valid frame.
    std::uint64_t badFrames = 0;      ///< '<'...16 bytes that were not a valid frame.
    std::uint64_t shortTransfers = 0; ///< IN transfers shorter than the 2 status bytes.
    std::uint64_t transfers = 0;      ///< IN transfers seen.
};

/// Reassembles frames from FTDI IN transfers: strips the 2 status bytes of each transfer,
/// buffers partial frames across transfers, skips garbage. Fixed capacity; never allocates.
/// One thread at a time.
class FalconStreamParser {
public:
    /// Feeds one whole IN transfer (status bytes included); calls onFrame(const Packet&) for
    /// every valid frame completed by it, in order. [servo]
    template <class OnFrame>
    void pushTransfer(std::span<const std::uint8_t> transfer, OnFrame&& onFrame) {
        ++mStats.transfers;
        if (transfer.size() < kFtdiStatusBytes) {
            ++mStats.shortTransfers;
            return;
        }
        pushPayload(transfer.subspan(kFtdiStatusBytes), onFrame);
    }

    /// Feeds payload bytes (no status bytes), any length; calls onFrame(const Packet&) for every
    /// valid frame completed. [servo]
    template <class OnFrame>
    void pushPayload(std::span<const std::uint8_t> payload, OnFrame&& onFrame) {
        while (!payload.empty()) {
            const std::size_t room = mBuffer.size() - mLength;
            const std::size_t n = payload.size() < room ? payload.size() : room;
            for (std::size_t i = 0; i < n; ++i) {
                mBuffer[mLength + i] = payload[i];
            }
            mLength += n;
            payload = payload.subspan(n);
            Packet frame;
            while (extract(frame)) {
                onFrame(static_cast<const Packet&>(frame));
            }
        }
    }

    /// Drops any partial frame (after a purge or reconnect). [servo]
    void reset() { mLength = 0; }
    /// Counters since construction. [servo]
    const FalconStreamStats& stats() const { return mStats; }
    /// Bytes buffered waiting for the rest of a frame. [servo]
    std::size_t pending() const { return mLength; }

private:
    /// Takes the next valid frame from the buffer if one is complete; compacts the buffer.
    bool extract(Packet& frame);

    std::array<std::uint8_t, 2 * kPacketSize + kMaxPayloadPerTransfer> mBuffer{};
    std::size_t mLength = 0;
    FalconStreamStats mStats;
};

} // namespace hapto::falcon
