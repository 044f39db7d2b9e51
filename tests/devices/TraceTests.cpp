#include "hapto/core/Random.h"
#include "hapto/devices/TraceReader.h"
#include "hapto/devices/TraceRecorder.h"
#include "hapto/io/InputError.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <bit>
#include <filesystem>
#include <thread>

using namespace hapto;

namespace {

TraceHeader header() {
    TraceHeader h;
    h.rateHz = 1000.0;
    h.kind = "sim";
    h.name = "left";
    h.startUnixNs = 1700000000123456789ull;
    h.transform.translation = Vec3(-0.02, 0.01, 0.3);
    h.transform.rotation = glm::angleAxis(0.7, glm::normalize(Vec3(1, 2, 3)));
    h.transform.scale = 1.5;
    h.toolTipM = Vec3(0.0, 0.0, -0.04);
    h.maxForceN = 3.3;
    return h;
}

std::vector<TraceSample> randomSamples(std::size_t n, std::uint64_t seed) {
    Random rng(seed);
    std::vector<TraceSample> out(n);
    std::uint64_t tick = 5;
    for (std::size_t i = 0; i < n; ++i) {
        TraceSample& s = out[i];
        tick += 1 + (rng.uniform() < 0.05 ? rng.below(3) : 0);
        s.tick = tick;
        s.timeNs = tick * 1000000ull + rng.below(1000);
        s.positionM = Vec3(rng.normal(), rng.normal(), rng.normal()) * 0.05;
        s.forceN = Vec3(rng.normal(), rng.normal(), rng.normal());
        s.computeNs = static_cast<std::uint32_t>(rng.below(1000000));
        s.ioNs = static_cast<std::uint32_t>(rng.below(100000));
        s.status = static_cast<DeviceStatus>(rng.below(6));
        s.buttons = static_cast<std::uint32_t>(rng.below(4));
        s.proxyM = s.positionM + Vec3(rng.normal(), rng.normal(), rng.normal()) * 0.001;
        s.hasVelocity = rng.uniform() < 0.5;
        if (s.hasVelocity) {
            s.velocityMps = Vec3(rng.normal(), rng.normal(), rng.normal());
        }
        s.hasOrientation = rng.uniform() < 0.5;
        if (s.hasOrientation) {
            s.orientation =
                glm::normalize(Quat{rng.normal(), rng.normal(), rng.normal(), rng.normal()});
        }
        s.hasAngularVelocity = rng.uniform() < 0.5;
        if (s.hasAngularVelocity) {
            s.angularVelocity = Vec3(rng.normal(), rng.normal(), rng.normal());
        }
        s.contactCount = static_cast<std::uint32_t>(rng.below(4));
        s.missedDeadline = rng.below(5) == 0;
    }
    return out;
}

void writeTrace(const std::filesystem::path& p, const std::vector<TraceSample>& samples) {
    TraceRecorder rec(p, header(), 64);
    for (const TraceSample& s : samples) {
        if (!rec.push(s)) {
            rec.drain();
            REQUIRE(rec.push(s));
        }
    }
    rec.close();
}

std::string errorReading(const std::filesystem::path& p) {
    try {
        TraceReader::load(p);
    } catch (const InputError& e) {
        return e.what();
    }
    return "(no error)";
}

void patch(const std::filesystem::path& p, std::size_t offset, const std::string& bytes) {
    std::string data = test::readFile(p);
    data.replace(offset, bytes.size(), bytes);
    test::writeFile(p, data);
}

} // namespace

TEST_CASE("trace: write then read gives back every sample exactly") {
    test::TempDir dir;
    const auto samples = randomSamples(5000, 1);
    writeTrace(dir / "t.trace", samples);
    CHECK(std::filesystem::file_size(dir / "t.trace") ==
          kTraceHeaderBytes + samples.size() * kTraceSampleBytes);
    TraceHeader h;
    const auto back = TraceReader::load(dir / "t.trace", &h);
    CHECK(back == samples);
    CHECK(h.finished);
    CHECK(h.sampleCount == samples.size());
    CHECK(h.rateHz == 1000.0);
    CHECK(h.kind == "sim");
    CHECK(h.name == "left");
    CHECK(h.startUnixNs == 1700000000123456789ull);
    CHECK(h.version == kTraceVersion);
    CHECK(h.hasConfiguration());
    CHECK(h.transform.translation == header().transform.translation);
    CHECK(h.transform.rotation == header().transform.rotation);
    CHECK(h.transform.scale == 1.5);
    CHECK(h.toolTipM == Vec3(0.0, 0.0, -0.04));
    CHECK(h.maxForceN == 3.3);
    CHECK(h.marksMisses);
}

TEST_CASE("trace: a version 1 file still reads, its version 2 fields at their defaults") {
    // Written by the version 1 recorder (and kept as a fuzz corpus entry): three ticks of
    // "left" (sim) at 1 kHz.
    const std::filesystem::path v1 =
        std::filesystem::path(HAPTO_SOURCE_DIR) / "tools/fuzz/corpus/trace_file/three-ticks.trace";
    TraceHeader h;
    const auto samples = TraceReader::load(v1, &h);
    CHECK(h.version == 1);
    CHECK_FALSE(h.hasConfiguration());
    CHECK(h.name == "left");
    CHECK(h.kind == "sim");
    CHECK(h.rateHz == 1000.0);
    CHECK(h.transform.scale == 1.0);
    CHECK(h.toolTipM == Vec3(0.0));
    REQUIRE(samples.size() == 3);
    for (std::size_t k = 0; k < 3; ++k) {
        const TraceSample& s = samples[k];
        CHECK(s.tick == k);
        CHECK(s.timeNs == 1'000'000 * k);
        CHECK(s.positionM == Vec3(0.01 * static_cast<double>(k), 0.0, -0.02));
        CHECK(s.forceN == Vec3(0.0, 1.0, 0.0));
        CHECK(s.computeNs == 3000);
        CHECK(s.ioNs == 500);
        CHECK(s.buttons == 1);
        CHECK(s.proxyM == Vec3(0.0));
        CHECK_FALSE(s.hasVelocity);
        CHECK_FALSE(s.hasOrientation);
        CHECK(s.contactCount == 0);
    }
}

TEST_CASE("trace: the header layout is the documented one") {
    test::TempDir dir;
    writeTrace(dir / "t.trace", randomSamples(3, 2));
    const std::string bytes = test::readFile(dir / "t.trace");
    CHECK(bytes.substr(0, 8) == "HAPTOTRC");
    CHECK(bytes[8] == 2);  // version, little-endian
    CHECK(bytes[20] == 1); // flags: the samples mark missed deadlines
    CHECK(bytes[12] == 0); // header size 256
    CHECK(bytes[13] == 1);
    CHECK(bytes[16] == static_cast<char>(192));
    CHECK(bytes[32] == 3); // sample count
    CHECK(bytes.substr(48, 3) == "sim");
    CHECK(bytes.substr(64, 4) == "left");
    const auto f64 = [&](std::size_t at) {
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) {
            v |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[at + i])) << (8 * i);
        }
        return std::bit_cast<double>(v);
    };
    CHECK(f64(128) == -0.02); // translation
    CHECK(f64(152) == header().transform.rotation.w);
    CHECK(f64(176) == header().transform.rotation.z);
    CHECK(f64(184) == 1.5);   // scale
    CHECK(f64(208) == -0.04); // tool tip z
    CHECK(f64(216) == 3.3);   // force clamp
    CHECK(bytes.substr(224, 32) == std::string(32, '\0'));
    const std::vector<TraceSample> s = randomSamples(3, 2);
    const std::size_t s0 = kTraceHeaderBytes;
    CHECK(f64(s0 + 80) == s[0].proxyM.x);
    CHECK(f64(s0 + 128) == (s[0].hasOrientation ? s[0].orientation.w : 1.0));
    CHECK(static_cast<unsigned char>(bytes[s0 + 184]) == s[0].contactCount);
    CHECK(static_cast<unsigned char>(bytes[s0 + 188]) ==
          ((s[0].hasVelocity ? 1 : 0) | (s[0].hasOrientation ? 2 : 0) |
           (s[0].hasAngularVelocity ? 4 : 0) | (s[0].missedDeadline ? 8 : 0)));
}

TEST_CASE("trace: a trace from before the miss marks says so, and a mark in it is refused") {
    test::TempDir dir;
    std::vector<TraceSample> samples = randomSamples(3, 3);
    for (TraceSample& s : samples) {
        s.missedDeadline = false;
    }
    writeTrace(dir / "t.trace", samples);
    patch(dir / "t.trace", 20, std::string(1, '\0')); // header flags 0, as written before
    TraceHeader h;
    CHECK(TraceReader::load(dir / "t.trace", &h) == samples);
    CHECK_FALSE(h.marksMisses);
    patch(dir / "t.trace", kTraceHeaderBytes + 188, std::string(1, '\x08'));
    CHECK_THAT(errorReading(dir / "t.trace"), Catch::Contains("unknown sample flags 8"));
    patch(dir / "t.trace", 20, std::string(1, '\x02'));
    CHECK_THAT(errorReading(dir / "t.trace"), Catch::Contains("unknown flags 2"));
}

TEST_CASE("trace: an empty recording is valid") {
    test::TempDir dir;
    writeTrace(dir / "t.trace", {});
    TraceHeader h;
    CHECK(TraceReader::load(dir / "t.trace", &h).empty());
    CHECK(h.sampleCount == 0);
}

TEST_CASE("trace: truncated and corrupt files are refused with the byte offset") {
    test::TempDir dir;
    const auto p = dir / "t.trace";
    const auto samples = randomSamples(10, 3);
    const auto fresh = [&] { writeTrace(p, samples); };

    fresh();
    std::filesystem::resize_file(p, kTraceHeaderBytes + 9 * kTraceSampleBytes + 40);
    CHECK_THAT(errorReading(p), Catch::Contains("t.trace: byte 2024: truncated: the header "
                                                "announces 10 samples"));
    fresh();
    patch(p, 32, std::string("\xfe") + std::string(7, '\xff')); // 2^64 - 2 samples
    CHECK_THAT(errorReading(p), Catch::Contains("byte 2176: truncated: the header announces "
                                                "18446744073709551614 samples (more bytes than "
                                                "a file can hold)"));
    fresh();
    std::filesystem::resize_file(p, 50);
    CHECK_THAT(errorReading(p), Catch::Contains("byte 50: truncated: the header needs 128"));
    test::writeFile(p, "");
    CHECK_THAT(errorReading(p), Catch::Contains("byte 0: truncated"));
    test::writeFile(p, "{\"format\": \"hapto-scene\"} and then some more text to fill");
    CHECK_THAT(errorReading(p), Catch::Contains("byte 0: not a hapto trace"));
    fresh();
    patch(p, 8, std::string("\x03", 1));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 8: trace format version 3"));
    fresh();
    std::filesystem::resize_file(p, 200);
    CHECK_THAT(errorReading(p), Catch::Contains("byte 200: truncated: a version 2 header"));
    fresh();
    patch(p, 8, std::string("\x01", 1)); // a version 1 header on version 2 sizes
    CHECK_THAT(errorReading(p), Catch::Contains("byte 12: header size 256, expected 128"));
    fresh();
    patch(p, 152, std::string(8, '\0')); // rotation w = 0: not unit
    CHECK_THAT(errorReading(p), Catch::Contains("byte 152: the transform's rotation"));
    fresh();
    patch(p, 184, std::string(8, '\0')); // scale 0
    CHECK_THAT(errorReading(p), Catch::Contains("byte 184: the transform's scale"));
    fresh();
    patch(p, 200, std::string(8, '\xff')); // tool tip NaN
    CHECK_THAT(errorReading(p), Catch::Contains("byte 192: the tool tip is not finite"));
    fresh();
    patch(p, 230, std::string("\x01", 1));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 230: reserved header bytes"));
    fresh();
    patch(p, kTraceHeaderBytes + kTraceSampleBytes + 88, std::string(8, '\xff'));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 528: sample 1: proxy is not finite"));
    fresh();
    patch(p, kTraceHeaderBytes + kTraceSampleBytes + 128, std::string(8, '\0'));
    patch(p, kTraceHeaderBytes + kTraceSampleBytes + 136, std::string(24, '\0'));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 576: sample 1: orientation is not a unit"));
    fresh();
    patch(p, kTraceHeaderBytes + kTraceSampleBytes + 184, std::string("\x07", 1));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 632: sample 1: contact count 7"));
    fresh();
    patch(p, kTraceHeaderBytes + kTraceSampleBytes + 188, std::string("\x10", 1));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 636: sample 1: unknown sample flags 16"));
    fresh();
    patch(p, 16, std::string("\x40", 1));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 16: sample size 64"));
    fresh();
    patch(p, 24, std::string(8, '\xff')); // NaN rate
    CHECK_THAT(errorReading(p), Catch::Contains("byte 24: servo rate"));
    fresh();
    patch(p, 64, std::string("\x01", 1));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 64: the name field"));
    fresh();
    patch(p, kTraceHeaderBytes + 2 * kTraceSampleBytes + 72, std::string("\x09", 1));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 712: sample 2: unknown device status 9"));
    fresh();
    patch(p, kTraceHeaderBytes + 3 * kTraceSampleBytes + 16, std::string(8, '\xff'));
    CHECK_THAT(errorReading(p), Catch::Contains("byte 848: sample 3: position is not finite"));
    fresh();
    patch(p, kTraceHeaderBytes + 4 * kTraceSampleBytes, std::string(8, '\0'));
    CHECK_THAT(errorReading(p), Catch::Contains("sample 4: tick 0 does not follow"));
    fresh();
    test::writeFile(p, test::readFile(p) + "xyz");
    CHECK_THAT(errorReading(p), Catch::Contains("byte 2176: 3 unexpected bytes after the last"));
    CHECK_THAT(errorReading(dir / "none.trace"), Catch::Contains("none.trace: cannot read"));
}

TEST_CASE("trace: a recording that was never closed reads its whole records") {
    test::TempDir dir;
    const auto p = dir / "t.trace";
    const auto samples = randomSamples(10, 4);
    writeTrace(p, samples);
    patch(p, 32, std::string(8, '\xff'));
    std::filesystem::resize_file(p, kTraceHeaderBytes + 7 * kTraceSampleBytes + 13);
    TraceHeader h;
    const auto back = TraceReader::load(p, &h);
    CHECK_FALSE(h.finished);
    CHECK(back == std::vector<TraceSample>(samples.begin(), samples.begin() + 7));
}

TEST_CASE("trace recorder: a full ring drops and counts instead of blocking") {
    test::TempDir dir;
    TraceRecorder rec(dir / "t.trace", header(), 8);
    CHECK(rec.capacity() == 8);
    const auto samples = randomSamples(20, 5);
    int accepted = 0;
    for (const TraceSample& s : samples) {
        accepted += rec.push(s);
    }
    CHECK(accepted == 8);
    CHECK(rec.dropped() == 12);
    CHECK(rec.drain() == 8);
    CHECK(rec.push(samples[19]));
    rec.close();
    CHECK(rec.written() == 9);
    CHECK_FALSE(rec.push(samples[0])); // closed: dropped
    CHECK(rec.dropped() == 13);
    const auto back = TraceReader::load(dir / "t.trace");
    REQUIRE(back.size() == 9);
    CHECK(back[8] == samples[19]);
}

TEST_CASE("trace recorder: a servo thread and a draining thread lose nothing uncounted",
          "[threads]") {
    test::TempDir dir;
    constexpr std::uint64_t kTicks = 200000;
    std::atomic<bool> done{false};
    std::uint64_t pushed = 0;
    {
        TraceRecorder rec(dir / "t.trace", header(), 256);
        std::thread servo([&] {
            TraceSample s;
            for (std::uint64_t t = 0; t < kTicks; ++t) {
                s.tick = t;
                s.timeNs = t * 1000;
                s.positionM = Vec3(static_cast<double>(t), 0, 0);
                pushed += rec.push(s);
            }
            done = true;
        });
        while (!done) {
            rec.drain();
            std::this_thread::yield();
        }
        servo.join();
        rec.close();
        CHECK(rec.written() == pushed);
        CHECK(pushed + rec.dropped() == kTicks);
    }
    const auto back = TraceReader::load(dir / "t.trace"); // checks ticks strictly increase
    REQUIRE(back.size() == pushed);
    for (const TraceSample& s : back) {
        REQUIRE(s.positionM.x == static_cast<double>(s.tick));
    }
}

namespace {} // namespace

TEST_CASE("trace recorder: the trace appears whole at close, until then the old file stays") {
    test::TempDir dir;
    const auto p = dir / "t.trace";
    const auto first = randomSamples(5, 6);
    writeTrace(p, first);
    const std::string before = test::readFile(p);
    {
        TraceRecorder rec(p, header(), 64);
        for (const TraceSample& s : randomSamples(7, 7)) {
            REQUIRE(rec.push(s));
        }
        rec.drain();
        CHECK(test::readFile(p) == before); // the new samples go elsewhere until close()
        CHECK(test::namesIn(dir.path()).size() == 2);
        rec.close();
    }
    CHECK(TraceReader::load(p) == randomSamples(7, 7));
    CHECK(test::namesIn(dir.path()) == std::vector<std::string>{"t.trace"}); // no temporary left
}

TEST_CASE("trace recorder: an abandoned recording leaves the old trace and no temporary") {
    test::TempDir dir;
    const auto p = dir / "t.trace";
    writeTrace(p, randomSamples(5, 6));
    const std::string before = test::readFile(p);
    {
        TraceRecorder rec(p, header(), 64);
        REQUIRE(rec.push(randomSamples(1, 9).front()));
        rec.abandon();
        CHECK_FALSE(rec.push(randomSamples(1, 9).front())); // closed: it drops
    } // the destructor, after abandon(), commits nothing
    CHECK(test::readFile(p) == before);
    CHECK(test::namesIn(dir.path()) == std::vector<std::string>{"t.trace"});
}

TEST_CASE("trace recorder: a symlink at the trace's name is replaced, never followed") {
    test::TempDir dir;
    test::writeFile(dir / "victim.txt", "keep me");
    std::filesystem::create_symlink(dir / "victim.txt", dir / "t.trace");
    writeTrace(dir / "t.trace", randomSamples(3, 8));
    CHECK(test::readFile(dir / "victim.txt") == "keep me");
    CHECK(std::filesystem::is_regular_file(std::filesystem::symlink_status(dir / "t.trace")));
    CHECK(TraceReader::load(dir / "t.trace") == randomSamples(3, 8));
    CHECK(test::namesIn(dir.path()) == std::vector<std::string>{"t.trace", "victim.txt"});
}

TEST_CASE("trace recorder: a folder or a missing folder is refused and nothing is left") {
    test::TempDir dir;
    std::filesystem::create_directory(dir / "t.trace");
    CHECK_THROWS_WITH(TraceRecorder(dir / "t.trace", header()), Catch::Contains("t.trace"));
    CHECK_THROWS_AS(TraceRecorder(dir / "missing" / "t.trace", header()), InputError);
    CHECK(test::namesIn(dir.path()) == std::vector<std::string>{"t.trace"});
    CHECK(std::filesystem::is_empty(dir / "t.trace"));
}
