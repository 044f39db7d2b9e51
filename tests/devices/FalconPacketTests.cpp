// Pure tests of the Falcon packet codec and the FTDI byte-stream reassembler.
#include "hapto/devices/FalconPacket.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
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
    CHECK(p[14] == 'A');            // the public code sends 'A' in byte 14
    CHECK(isValidFrame(p));
}

TEST_CASE("a homed Falcon's reply, byte 13 above 'P', is one 7-bit field: buttons and homed flags",
          "[codec]") {
    // Byte 13 minus 0x41 masked to 0x7F: grip buttons in bits 0-3, homed per motor in bits 4-6
    // (libnifalcon FalconFirmwareNovintSDK.cpp formatOutput; FalconFirmwareNovintSDK.h). Frames
    // written by hand from those notes, not by our encoder.
    const auto frame = [](std::uint8_t byte13, std::uint8_t byte14) {
        std::string text = "<AAAAAAAAAAAA";
        text.push_back(static_cast<char>(byte13));
        text.push_back(static_cast<char>(byte14));
        text.push_back('>');
        return std::vector<std::uint8_t>(text.begin(), text.end());
    };
    struct Case {
        std::uint8_t byte13;
        std::uint8_t buttons;
        std::uint8_t homed;
    };
    for (const Case c :
         {Case{0x41, 0x0, 0x0}, Case{0x50, 0xF, 0x0}, Case{0x51, 0x0, 0x1}, Case{0x61, 0x0, 0x2},
          Case{0x81, 0x0, 0x4}, Case{0xB1, 0x0, 0x7}, Case{0xB6, 0x5, 0x7}, Case{0xC0, 0xF, 0x7}}) {
        INFO("byte 13 = " << int(c.byte13));
        const auto bytes = frame(c.byte13, 'A');
        CHECK(isValidFrame(bytes));
        const auto r = decode(bytes);
        REQUIRE(r.has_value());
        CHECK(r->buttons == c.buttons);
        CHECK(r->homedMask == c.homed);
        CHECK(r->allHomed() == (c.homed == 0x7));
        CHECK(r->encoder == std::array<std::int16_t, 3>{0, 0, 0});
    }
    // Outside 0x41..0xC0 it is not a frame.
    for (const std::uint8_t bad : {std::uint8_t{0x40}, std::uint8_t{0xC1}, std::uint8_t{0xFF},
                                   std::uint8_t{'<'}, std::uint8_t{'>'}}) {
        CHECK_FALSE(decode(frame(bad, 'A')).has_value());
    }
}

TEST_CASE("a reply's byte 14 carries no information: any value is accepted and ignored",
          "[codec]") {
    // The public code never reads byte 14 of a reply; "<HNGPOKOPFPOPAA>" is its sample string.
    const std::string sample = "<HNGPOKOPFPOPAA>";
    const std::vector<std::uint8_t> base(sample.begin(), sample.end());
    const auto ref = decode(base);
    REQUIRE(ref.has_value());
    for (const std::uint8_t b14 : {std::uint8_t{'A'}, std::uint8_t{'P'}, std::uint8_t{0x00},
                                   std::uint8_t{0xC0}, std::uint8_t{0xFF}, std::uint8_t{'<'}}) {
        std::vector<std::uint8_t> bytes = base;
        bytes[14] = b14;
        const auto r = decode(bytes);
        REQUIRE(r.has_value());
        CHECK(r->encoder == ref->encoder);
        CHECK(r->buttons == ref->buttons);
        CHECK(r->homedMask == ref->homedMask);
        const Packet again = encodeReading(*r); // still re-encodes to its own bytes
        CHECK(std::equal(again.begin(), again.end(), bytes.begin()));
    }
}

TEST_CASE("encoder words are nibbles plus 0x41, least significant first, two's complement",
          "[codec]") {
    // libnifalcon FalconFirmwareNovintSDK.h, "Motor Value Extraction Example": bytes 0x4A 0x46
    // 0x4B 0x50 are nibbles 9, 5, A, F, least significant first: 0xFA59, which as int16 is -1447
    // (the header prints its magnitude, 1447).
    const std::string text = "<JFKPAAAAPPPPAA>";
    const auto r = decode(std::vector<std::uint8_t>(text.begin(), text.end()));
    REQUIRE(r.has_value());
    CHECK(r->encoder[0] == -1447);
    CHECK(r->encoder[1] == 0);
    CHECK(r->encoder[2] == -1);
}

TEST_CASE("a command frame needs a nibble in byte 13 and 'A' in byte 14", "[codec]") {
    FalconCommand c;
    c.motor = {100, -100, 4096};
    c.homing = true;
    Packet p = encodeCommand(c);
    REQUIRE(decodeCommand(p).has_value());
    p[13] = 0xB1; // a reply's flag field, not a command's
    CHECK_FALSE(decodeCommand(p).has_value());
    p = encodeCommand(c);
    p[14] = 'B';
    CHECK_FALSE(decodeCommand(p).has_value());
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
        if (i == 14) {
            continue; // byte 14 may hold anything (see the byte 14 test)
        }
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

TEST_CASE("the fuzzer's flag-byte frame is read by the corrected layout", "[codec]") {
    // Found by fuzz_falcon_packet (corpus crash-flag-bit7-lost.bin) when we read homed flags from
    // byte 14 (as homed bit 2 and a flag bit 7). Byte 13 is 'A': no button, no motor homed;
    // byte 14 'M' means nothing.
    const std::string text = "<EGAAIDPCBHPAAM>";
    const std::vector<std::uint8_t> frame(text.begin(), text.end());
    const auto r = decode(frame);
    REQUIRE(r.has_value());
    CHECK(r->encoder[0] == static_cast<std::int16_t>(0x0064)); // E G A A: 4, 6, 0, 0
    CHECK(r->buttons == 0x0);
    CHECK(r->homedMask == 0x0);
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
