#pragma once
/// The Novint Falcon's 16-byte I/O packets and the byte-stream reassembler that finds them.
//
// Design note. The Falcon firmware talks in 16-byte frames: '<', 14 payload bytes, '>'. Bytes
// 1-12 carry three int16 words as 4-bit nibbles plus 0x41 ('A'..'P'), least significant nibble
// first: motor commands from the host, encoder counts from the device. Byte 13 is a flag field
// plus 0x41, not a nibble: the host sends homing (bit 0) and the LEDs (bits 1-3); the device
// answers with ONE 7-bit field, grip buttons in bits 0-3 and a "homed" flag per motor in bits
// 4-6, so a reply's byte 13 ranges over 0x41..0xC0 and a homed Falcon sends values above 'P'
// (libnifalcon src/firmware/FalconFirmwareNovintSDK.cpp, formatOutput: homing status is
// ((byte13 - 0x41) >> 4) & 7, grip info (byte13 - 0x41) & 0xF; its header
// FalconFirmwareNovintSDK.h, "Buttons and Homing Control Report": 0x10/0x20/0x40 = motor homed).
// Byte 14 carries no known information: the public code sends 'A' there and never reads it on
// replies, so a reply's byte 14 is accepted whatever it holds and kept only so that a decoded
// frame re-encodes to its own bytes. Over USB the FTDI bridge prefixes every IN transfer with
// two modem-status bytes and may split or merge frames arbitrarily, so the reassembler strips
// those two bytes and scans the remaining stream for valid frames, skipping garbage byte by byte.
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
    bool homing = false;   ///< Homing mode bit (bit 0 of byte 13); must stay set in every packet
                           ///< for the Falcon to stay homed (libnifalcon
                           ///< include/falcon/core/FalconFirmware.h, "Homing Mode").
    bool ledGreen = false; ///< Green LED (bit 1).
    bool ledBlue = false;  ///< Blue LED (bit 2).
    bool ledRed = false;   ///< Red LED (bit 3).

    /// Field-wise equality. [any thread]
    bool operator==(const FalconCommand&) const = default;
};

/// What the host sends in byte 14, and a reading's byte 14 by default: 'A'.
inline constexpr std::uint8_t kUnusedByte = 0x41;
/// The largest byte 13 of a reply: 0x41 plus the 7-bit flag field 0x7F.
inline constexpr std::uint8_t kMaxReplyFlagByte = 0x41 + 0x7F;

/// Device-to-host reading: three encoder counts, grip buttons and homed flags.
struct FalconReading {
    std::array<std::int16_t, 3> encoder{}; ///< Encoder counts per motor.
    std::uint8_t buttons = 0;              ///< Grip buttons, bits 0-3.
    std::uint8_t homedMask = 0;            ///< Bit i set once motor i is homed, bits 0-2.
    std::uint8_t byte14 = kUnusedByte;     ///< Byte 14 as received: no known meaning, never read by
                                           ///< the driver; kept so a frame re-encodes to its bytes.

    /// True when all three motors report homed. [any thread]
    bool allHomed() const { return homedMask == 0x7; }
    /// Field-wise equality. [any thread]
    bool operator==(const FalconReading&) const = default;
};

/// Encodes a host command into a frame. [any thread]
Packet encodeCommand(const FalconCommand& command);
/// Decodes a host command frame; nullopt unless `bytes` is exactly one valid reply frame whose
/// byte 13 is a nibble byte ('A'..'P') and whose byte 14 is 'A'. [any thread]
std::optional<FalconCommand> decodeCommand(std::span<const std::uint8_t> bytes);
/// Encodes a device reading into a frame (used by tests and the fuzz target). [any thread]
Packet encodeReading(const FalconReading& reading);
/// Decodes a device reading; nullopt unless `bytes` is exactly one valid frame. Never reads
/// outside `bytes`, whatever it holds. [any thread]
std::optional<FalconReading> decode(std::span<const std::uint8_t> bytes);
/// True when `bytes` is exactly one well-formed frame: '<', bytes 1-12 in 'A'..'P', byte 13 in
/// 0x41..0xC0, byte 14 anything, '>'. [any thread]
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
