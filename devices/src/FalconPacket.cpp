#include "hapto/devices/FalconPacket.h"

namespace hapto::falcon {
namespace {

constexpr std::uint8_t kStart = '<';
constexpr std::uint8_t kEnd = '>';
constexpr std::uint8_t kNibbleBase = 0x41;
constexpr std::size_t kFlagByte = 13;
constexpr std::size_t kUnusedByteIndex = 14;

bool isNibbleByte(std::uint8_t b) {
    return b >= kNibbleBase && b < kNibbleBase + 16;
}

/// Whether byte `i` (1..14) of a frame may hold `b`: nibbles in 1-12, the 7-bit flag field plus
/// 0x41 in 13, anything in 14 (see the design note in FalconPacket.h).
bool isPayloadByte(std::size_t i, std::uint8_t b) {
    if (i == kFlagByte) {
        return b >= kNibbleBase && b <= kMaxReplyFlagByte;
    }
    return i == kUnusedByteIndex || isNibbleByte(b);
}

/// Writes a 16-bit word as four nibble bytes, least significant nibble first.
void putWord(Packet& p, std::size_t first, std::int16_t value) {
    const auto u = static_cast<std::uint16_t>(value);
    for (std::size_t i = 0; i < 4; ++i) {
        p[first + i] = static_cast<std::uint8_t>(kNibbleBase + ((u >> (4 * i)) & 0xF));
    }
}

std::int16_t getWord(std::span<const std::uint8_t> bytes, std::size_t first) {
    std::uint16_t u = 0;
    for (std::size_t i = 0; i < 4; ++i) {
        u = static_cast<std::uint16_t>(u | ((bytes[first + i] - kNibbleBase) & 0xF) << (4 * i));
    }
    return static_cast<std::int16_t>(u);
}

/// A frame of three words, a flag field (at most 7 bits) in byte 13 and `byte14`.
Packet frameWith(const std::array<std::int16_t, 3>& words, std::uint8_t flags,
                 std::uint8_t byte14) {
    Packet p{};
    p[0] = kStart;
    putWord(p, 1, words[0]);
    putWord(p, 5, words[1]);
    putWord(p, 9, words[2]);
    p[kFlagByte] = static_cast<std::uint8_t>(kNibbleBase + (flags & 0x7F));
    p[kUnusedByteIndex] = byte14;
    p[15] = kEnd;
    return p;
}

} // namespace

bool isValidFrame(std::span<const std::uint8_t> bytes) {
    if (bytes.size() != kPacketSize || bytes[0] != kStart || bytes[kPacketSize - 1] != kEnd) {
        return false;
    }
    for (std::size_t i = 1; i < kPacketSize - 1; ++i) {
        if (!isPayloadByte(i, bytes[i])) {
            return false;
        }
    }
    return true;
}

Packet encodeCommand(const FalconCommand& c) {
    const std::uint8_t flags = static_cast<std::uint8_t>((c.homing ? 1 : 0) | (c.ledGreen ? 2 : 0) |
                                                         (c.ledBlue ? 4 : 0) | (c.ledRed ? 8 : 0));
    return frameWith(c.motor, flags, kUnusedByte);
}

std::optional<FalconCommand> decodeCommand(std::span<const std::uint8_t> bytes) {
    // A host command carries only a nibble of flags and 'A' in byte 14 (libnifalcon
    // FalconFirmwareNovintSDK.cpp, formatInput).
    if (!isValidFrame(bytes) || !isNibbleByte(bytes[kFlagByte]) ||
        bytes[kUnusedByteIndex] != kUnusedByte) {
        return std::nullopt;
    }
    FalconCommand c;
    c.motor = {getWord(bytes, 1), getWord(bytes, 5), getWord(bytes, 9)};
    const unsigned flags = (bytes[kFlagByte] - kNibbleBase) & 0xFu;
    c.homing = (flags & 1u) != 0;
    c.ledGreen = (flags & 2u) != 0;
    c.ledBlue = (flags & 4u) != 0;
    c.ledRed = (flags & 8u) != 0;
    return c;
}

Packet encodeReading(const FalconReading& r) {
    const std::uint8_t flags =
        static_cast<std::uint8_t>((r.buttons & 0xF) | ((r.homedMask & 0x7) << 4));
    return frameWith(r.encoder, flags, r.byte14);
}

std::optional<FalconReading> decode(std::span<const std::uint8_t> bytes) {
    if (!isValidFrame(bytes)) {
        return std::nullopt;
    }
    FalconReading r;
    r.encoder = {getWord(bytes, 1), getWord(bytes, 5), getWord(bytes, 9)};
    // One 7-bit field: buttons in bits 0-3, homed per motor in bits 4-6 (libnifalcon
    // src/firmware/FalconFirmwareNovintSDK.cpp, formatOutput). Byte 14 is not read for meaning.
    const unsigned flags = (bytes[kFlagByte] - kNibbleBase) & 0x7Fu;
    r.buttons = static_cast<std::uint8_t>(flags & 0xFu);
    r.homedMask = static_cast<std::uint8_t>((flags >> 4) & 0x7u);
    r.byte14 = bytes[kUnusedByteIndex];
    return r;
}

bool FalconStreamParser::extract(Packet& frame) {
    std::size_t start = 0;
    bool found = false;
    while (start < mLength) {
        if (mBuffer[start] != kStart) {
            ++mStats.garbageBytes;
            ++start;
            continue;
        }
        // A '<': check as much of the frame as has arrived, rejecting early on a bad byte.
        const std::size_t have = mLength - start;
        const std::size_t check = have < kPacketSize ? have : kPacketSize;
        bool bad = false;
        for (std::size_t i = 1; i < check && !bad; ++i) {
            const std::uint8_t b = mBuffer[start + i];
            bad = (i == kPacketSize - 1) ? b != kEnd : !isPayloadByte(i, b);
        }
        if (bad) {
            ++mStats.badFrames;
            ++mStats.garbageBytes;
            ++start;
            continue;
        }
        if (have < kPacketSize) {
            break; // a valid prefix: wait for the rest
        }
        for (std::size_t i = 0; i < kPacketSize; ++i) {
            frame[i] = mBuffer[start + i];
        }
        start += kPacketSize;
        ++mStats.frames;
        found = true;
        break;
    }
    // Compact: move the unconsumed tail to the front.
    for (std::size_t i = start; i < mLength; ++i) {
        mBuffer[i - start] = mBuffer[i];
    }
    mLength -= start;
    return found;
}

} // namespace hapto::falcon
