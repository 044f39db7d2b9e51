// Pure tests of the Falcon packet codec and the FTDI byte-stream reassembler.
#include "hapto/devices/FalconPacket.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

using namespace hapto::falcon;

namespace {

std::vector<Packet> collect(FalconStreamParser& parser, std::span<const std::uint8_t> transfer) {
    std::vector<Packet> out;
    parser.pushTransfer(transfer, [&](const Packet& p) { out.push_back(p); });
    return out;
}

std::vector<std::uint8_t> withStatus(std::vector<std::uint8_t> payload) {
    payload.insert(payload.begin(), {0x31, 0x60});
    return payload;
}

} // namespace

TEST_CASE("a command frame has '<', nibbles plus 0x41 least significant first, flags, '>'",
          "[codec]") {
    FalconCommand c;
    c.motor = {0x1234, -1, 0};
    c.homing = true;
    c.ledRed = true;
    const Packet p = encodeCommand(c);
    CHECK(p[0] == '<');
    CHECK(p[15] == '>');
    CHECK(p[1] == 0x41 + 0x4);
    CHECK(p[2] == 0x41 + 0x3);
    CHECK(p[3] == 0x41 + 0x2);
    CHECK(p[4] == 0x41 + 0x1);
    for (int i = 5; i <= 8; ++i) {
        CHECK(p[static_cast<std::size_t>(i)] == 0x41 + 0xF); // -1 = 0xFFFF
    }
    for (int i = 9; i <= 12; ++i) {
        CHECK(p[static_cast<std::size_t>(i)] == 0x41);
    }
    CHECK(p[13] == 0x41 + (1 | 8)); // homing + red LED
    CHECK(isValidFrame(p));
}

TEST_CASE("commands and readings survive an encode/decode round trip, extremes included",
          "[codec]") {
    for (std::int16_t w : {std::int16_t{0}, std::int16_t{1}, std::int16_t{-1}, std::int16_t{32767},
                           std::int16_t{-32768}, std::int16_t{0x0F0F}}) {
        FalconCommand c;
        c.motor = {w, static_cast<std::int16_t>(-w / 2), static_cast<std::int16_t>(w ^ 0x5555)};
        c.homing = (w & 1) != 0;
        c.ledGreen = true;
        c.ledBlue = (w & 2) != 0;
        const auto back = decodeCommand(encodeCommand(c));
        REQUIRE(back.has_value());
        CHECK(*back == c);

        FalconReading r;
        r.encoder = c.motor;
        r.buttons = static_cast<std::uint8_t>(w & 0xF);
        r.homedMask = static_cast<std::uint8_t>((w >> 4) & 0x7);
        const auto rb = decode(encodeReading(r));
        REQUIRE(rb.has_value());
        CHECK(*rb == r);
    }
    FalconReading homed;
    homed.homedMask = 7;
    CHECK(decode(encodeReading(homed))->allHomed());
}

TEST_CASE("decode rejects anything that is not exactly one well-formed frame", "[codec]") {
    const Packet good = encodeReading(FalconReading{{100, -200, 300}, 5, 3});
    CHECK(decode(good).has_value());
    CHECK_FALSE(decode(std::span<const std::uint8_t>()).has_value());
    CHECK_FALSE(decode(std::span<const std::uint8_t>(good.data(), 15)).has_value());
    std::vector<std::uint8_t> longer(good.begin(), good.end());
    longer.push_back('>');
    CHECK_FALSE(decode(longer).has_value());
    for (std::size_t i = 0; i < kPacketSize; ++i) {
        Packet bad = good;
        bad[i] = (i == 0 || i == 15) ? 'A' : '<';
        CHECK_FALSE(decode(bad).has_value());
    }
}

TEST_CASE("decode never crashes and only accepts frames that re-encode identically", "[codec]") {
    std::mt19937 rng(1234);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_int_distribution<int> len(0, 40);
    const Packet good = encodeReading(FalconReading{{7, 8, 9}, 1, 7});
    for (int trial = 0; trial < 20000; ++trial) {
        std::vector<std::uint8_t> data(static_cast<std::size_t>(len(rng)));
        for (auto& b : data) {
            b = static_cast<std::uint8_t>(byte(rng));
        }
        if (trial % 2 == 0 && data.size() == kPacketSize) {
            data.assign(good.begin(), good.end());
            data[static_cast<std::size_t>(trial) % kPacketSize] =
                static_cast<std::uint8_t>(byte(rng));
        }
        const auto r = decode(data);
        (void)decodeCommand(data);
        if (r) {
            REQUIRE(data.size() == kPacketSize);
            const Packet again = encodeReading(*r);
            CHECK(std::equal(again.begin(), again.end(), data.begin()));
        }
    }
}

TEST_CASE("the unused top bit of the flag byte survives decode and re-encode", "[codec]") {
    // Found by fuzz_falcon_packet (corpus crash-flag-bit7-lost.bin): byte 14 'M' is nibble 0xC,
    // homed bits 2 and the unused flag bit 7; dropping bit 7 re-encoded the frame as 'E'.
    const std::string text = "<EGAAIDPCBHPAAM>";
    const std::vector<std::uint8_t> frame(text.begin(), text.end());
    const auto r = decode(frame);
    REQUIRE(r.has_value());
    CHECK(r->homedMask == 0x4);
    CHECK(r->flagBit7);
    CHECK_FALSE(r->allHomed());
    const Packet again = encodeReading(*r);
    CHECK(std::equal(again.begin(), again.end(), frame.begin()));
}

TEST_CASE("the reassembler strips the 2 FTDI status bytes and joins frames split over transfers",
          "[codec]") {
    FalconStreamParser parser;
    const Packet a = encodeReading(FalconReading{{1, 2, 3}, 0, 0});
    const Packet b = encodeReading(FalconReading{{-4, 5, -6}, 15, 7});
    // a in two pieces, then the end of... b whole, preceded by a status-only transfer.
    CHECK(collect(parser, withStatus({a.begin(), a.begin() + 9})).empty());
    CHECK(parser.pending() == 9);
    auto got = collect(parser, withStatus({a.begin() + 9, a.end()}));
    REQUIRE(got.size() == 1);
    CHECK(got[0] == a);
    CHECK(collect(parser, withStatus({})).empty());
    std::vector<std::uint8_t> both(a.begin(), a.end());
    both.insert(both.end(), b.begin(), b.end());
    got = collect(parser, withStatus(both));
    REQUIRE(got.size() == 2);
    CHECK(got[1] == b);
    CHECK(parser.stats().frames == 3);
    CHECK(parser.stats().garbageBytes == 0);
}

TEST_CASE("the reassembler skips garbage, false starts and malformed short transfers", "[codec]") {
    FalconStreamParser parser;
    const Packet a = encodeReading(FalconReading{{10, 20, 30}, 1, 0});
    std::vector<std::uint8_t> payload{0xFF, 'x', '<', 'A', 'B', 0x00, '>', '<'};
    payload.insert(payload.end(), a.begin(), a.end());
    payload.push_back('?');
    const std::uint8_t oneByte[1] = {0x31};
    CHECK(collect(parser, oneByte).empty());
    CHECK(parser.stats().shortTransfers == 1);
    const auto got = collect(parser, withStatus(payload));
    REQUIRE(got.size() == 1);
    CHECK(got[0] == a);
    CHECK(parser.stats().badFrames == 2);    // "<AB\0" and "<<"
    CHECK(parser.stats().garbageBytes == 9); // everything but the frame
}

TEST_CASE("every frame is recovered from a randomly chunked stream with garbage between frames",
          "[codec]") {
    std::mt19937 rng(42);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_int_distribution<int> chunk(0, 62);
    std::uniform_int_distribution<int> garbageLen(0, 14); // shorter than a frame
    std::vector<Packet> sent;
    std::vector<std::uint8_t> stream;
    for (int i = 0; i < 500; ++i) {
        const int g = garbageLen(rng);
        for (int k = 0; k < g; ++k) {
            stream.push_back(static_cast<std::uint8_t>(byte(rng)));
        }
        FalconReading r;
        r.encoder = {static_cast<std::int16_t>(byte(rng) * 100 - 12800),
                     static_cast<std::int16_t>(i), static_cast<std::int16_t>(-i)};
        r.buttons = static_cast<std::uint8_t>(i & 0xF);
        sent.push_back(encodeReading(r));
        stream.insert(stream.end(), sent.back().begin(), sent.back().end());
    }
    FalconStreamParser parser;
    std::vector<Packet> got;
    std::size_t at = 0;
    while (at < stream.size()) {
        const std::size_t n =
            std::min<std::size_t>(static_cast<std::size_t>(chunk(rng)), stream.size() - at);
        std::vector<std::uint8_t> t{0x31, 0x60};
        t.insert(t.end(), stream.begin() + static_cast<std::ptrdiff_t>(at),
                 stream.begin() + static_cast<std::ptrdiff_t>(at + n));
        parser.pushTransfer(t, [&](const Packet& p) { got.push_back(p); });
        at += n;
    }
    REQUIRE(got.size() == sent.size());
    CHECK(got == sent);
}
