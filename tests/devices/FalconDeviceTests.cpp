// FalconDevice's real libusb code against an emulated Falcon (umockdev). Run under
// umockdev-wrapper; CTest does that. Started by hand without it, these tests exit 77 (skip).
#include "FalconEmulator.h"
#include "TestSupport.h"

#include "hapto/devices/FalconDevice.h"
#include "hapto/devices/FalconKinematics.h"

#include <catch2/catch.hpp>

#include <umockdev.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

using namespace hapto;
using namespace hapto::falcon;
using hapto::test::FalconEmulator;
using hapto::test::FalconEmulatorOptions;
using hapto::test::FtdiRequest;
using hapto::test::ReplyMode;
using namespace std::chrono_literals;

#if defined(__SANITIZE_THREAD__)
/// ThreadSanitizer reports races inside the uninstrumented test harness (umockdev's worker
/// thread, GLib's slice allocator and mutex teardown, libudev's getrandom); none are in hapto.
extern "C" const char* __tsan_default_suppressions() {
    return "race:libumockdev.so\nrace:libglib-2.0.so\nrace:libgobject-2.0.so\nrace:libudev.so\n";
}
#endif

/// Opens `dev`, failing with its error message if that does not work.
#define REQUIRE_OPEN(dev)                                                                          \
    do {                                                                                           \
        const DeviceStatus openStatus = (dev).open();                                              \
        INFO("open: " << statusName(openStatus) << ": " << (dev).errorMessage());                  \
        REQUIRE(openStatus == DeviceStatus::Ok);                                                   \
    } while (false)

using hapto::test::eventually;

namespace {

/// Skips (exit 77) unless umockdev's preload is active; under CTest the environment variable
/// HAPTO_FALCON_EMULATION_REQUIRED turns a missing wrapper into a failure, never a skip.
void requireEmulation() {
    if (FalconEmulator::inMockEnvironment()) {
        return;
    }
    if (std::getenv("HAPTO_FALCON_EMULATION_REQUIRED")) {
        FAIL("not running under umockdev-wrapper, but CTest requires the emulated Falcon");
    }
    std::fprintf(stderr, "skipped: the emulated-Falcon tests must run under umockdev-wrapper\n");
    std::exit(77);
}

/// Test timeouts: short where a test waits for a failure, generous where it is only a guard.
FalconTimeouts testTimeouts() {
    FalconTimeouts t;
    t.usb = 1000ms;
    t.probe = 200ms;
    t.homing = 10s;
    t.stale = 50ms;
    return t;
}

/// A command clock the test steps by hand (ns).
std::atomic<std::int64_t> gTestNowNs{1'000'000'000};
std::int64_t testClock() {
    return gTestNowNs.load();
}

/// No homing wait, and the longest command timeout allowed (10 ms), so that the servo threads
/// of these tests, which sleep 1 ms between writes on a loaded machine, keep their force.
FalconConfig noHoming() {
    FalconConfig c;
    c.home = false;
    c.commandTimeoutMs = 10.0;
    return c;
}

/// Encoder counts that put the tip near `mech` (mechanism frame, m), and the exact position
/// those counts mean.
struct Pose {
    std::array<std::int16_t, 3> encoders;
    Vec3 mechPosition{0.0};
    Angles angles;
};

Pose poseNear(const Vec3& mech) {
    const FalconKinematics k;
    const auto a = k.inverse(mech);
    REQUIRE(a);
    Pose pose;
    for (std::size_t i = 0; i < 3; ++i) {
        pose.encoders[i] = FalconKinematics::angleToEncoder((*a)[i]);
    }
    pose.angles = FalconKinematics::encodersToAngles(pose.encoders);
    const auto p = k.forward(pose.angles, mech);
    REQUIRE(p);
    pose.mechPosition = *p;
    REQUIRE(glm::length(pose.mechPosition - mech) < 1e-3);
    return pose;
}

MotorWords expectedWords(const Pose& pose, const Vec3& forceN) {
    const FalconKinematics k;
    const auto j = k.jacobian(pose.mechPosition, pose.angles);
    REQUIRE(j);
    return FalconKinematics::torqueToMotorWords(FalconKinematics::forceToTorque(*j, forceN));
}

bool wordsClose(const MotorWords& a, const MotorWords& b) {
    for (std::size_t i = 0; i < 3; ++i) {
        if (std::abs(a[i] - b[i]) > 1) {
            return false;
        }
    }
    return true;
}

/// Reads until the device reports Ok with a sample, or the guard expires.
bool readOk(FalconDevice& dev, DeviceState& s) {
    return eventually([&] { return dev.read(s) == DeviceStatus::Ok; });
}

const Vec3 kOrigin(0.0, 0.0, kWorkspaceOriginZ);

} // namespace

TEST_CASE("set-up with firmware running sends the FTDI requests in order, no upload",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    FalconDevice dev("left", noHoming(), 5.0);
    dev.setTimeouts(testTimeouts());
    DeviceState before;
    CHECK(dev.read(before) == DeviceStatus::NotOpen);
    REQUIRE_OPEN(dev);
    CHECK(dev.firmwareWasLoaded());
    dev.close();
    const std::vector<FtdiRequest> expected{
        {0, 0, 0},      // reset
        {9, 1, 0},      // latency 1 ms
        {3, 0x0002, 0}, // 1.5 Mbaud
        {4, 0x0008, 0}, // 8N1
        {2, 0, 0},      // no flow control
        {0, 1, 0},      // purge RX
        {0, 2, 0},      // purge TX
    };
    CHECK(emu.ftdiRequests() == expected);
    CHECK(emu.uploadedImage().empty());
    CHECK(emu.unknownIoctls().empty());
}

TEST_CASE("firmware is uploaded from the user's file with the handshake and echo check",
          "[emulated][threads]") {
    requireEmulation();
    hapto::test::TempDir dir;
    std::string image;
    for (int i = 0; i < 1000; ++i) { // not a multiple of 62: the last chunk is short
        image.push_back(static_cast<char>((i * 37 + 11) & 0xFF));
    }
    hapto::test::writeFile(dir / "falcon.bin", image);

    FalconEmulatorOptions opt;
    opt.firmwareLoaded = false;
    SECTION("handshake reply with a leading 0x00") {
        opt.handshakeLeadingZero = true;
    }
    SECTION("handshake reply without it") {
        opt.handshakeLeadingZero = false;
    }
    FalconEmulator emu(opt);
    FalconConfig cfg = noHoming();
    cfg.firmware = dir / "falcon.bin";
    FalconDevice dev("left", cfg, 5.0);
    dev.setTimeouts(testTimeouts());
    REQUIRE_OPEN(dev);
    CHECK_FALSE(dev.firmwareWasLoaded());
    CHECK(emu.firmwareRunning());
    const auto uploaded = emu.uploadedImage();
    CHECK(std::string(uploaded.begin(), uploaded.end()) == image);

    // The bootloader sequence appears in order after the first set-up.
    const std::vector<FtdiRequest> boot{
        {0, 1, 0},      {0, 2, 0},      {9, 16, 0},     {3, 0x4138, 0}, {4, 0x0008, 0}, {2, 0, 0},
        {1, 0x0200, 0}, {1, 0x0100, 0}, {1, 0x0101, 0}, {1, 0x0100, 0}, {3, 0x0015, 0}, {9, 1, 0},
        {3, 0x0002, 0}, {4, 0x0008, 0}, {2, 0, 0},      {0, 1, 0},      {0, 2, 0}};
    const auto seen = emu.ftdiRequests();
    std::size_t at = 0;
    for (const auto& r : seen) {
        if (at < boot.size() && r == boot[at]) {
            ++at;
        }
    }
    CHECK(at == boot.size());

    // And the device then runs: a sample arrives.
    DeviceState s;
    CHECK(readOk(dev, s));
    dev.close();
}

TEST_CASE("a firmware upload whose echo does not match fails with the byte position",
          "[emulated][threads]") {
    requireEmulation();
    hapto::test::TempDir dir;
    hapto::test::writeFile(dir / "falcon.bin", std::string(300, '\x42'));
    FalconEmulatorOptions opt;
    opt.firmwareLoaded = false;
    opt.corruptEchoAt = 130; // in the third 62-byte chunk, which starts at byte 124
    FalconEmulator emu(opt);
    FalconConfig cfg = noHoming();
    cfg.firmware = dir / "falcon.bin";
    FalconDevice dev("left", cfg, 5.0);
    dev.setTimeouts(testTimeouts());
    CHECK(dev.open() == DeviceStatus::Error);
    CHECK_THAT(dev.errorMessage(), Catch::Contains("firmware upload failed at byte 124"));
}

TEST_CASE("without firmware and without a firmware file, open says what to do",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulatorOptions opt;
    opt.firmwareLoaded = false;
    FalconEmulator emu(opt);
    SECTION("no file configured") {
        FalconDevice dev("left", noHoming(), 5.0);
        dev.setTimeouts(testTimeouts());
        CHECK(dev.open() == DeviceStatus::Error);
        CHECK_THAT(dev.errorMessage(),
                   Catch::Contains("no firmware loaded") && Catch::Contains("\"firmware\""));
    }
    SECTION("a file that does not exist") {
        FalconConfig cfg = noHoming();
        cfg.firmware = "/nonexistent/falcon-firmware.bin";
        FalconDevice dev("left", cfg, 5.0);
        dev.setTimeouts(testTimeouts());
        CHECK(dev.open() == DeviceStatus::Error);
        CHECK_THAT(dev.errorMessage(), Catch::Contains("/nonexistent/falcon-firmware.bin"));
    }
    CHECK_FALSE(emu.firmwareRunning());
}

TEST_CASE("homing: every packet asks for homing mode, open waits for all three homed flags, and "
          "the Falcon stays homed while it runs and after close",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulatorOptions opt;
    opt.homeAfterPackets = 20;
    FalconEmulator emu(opt);
    const Pose a = poseNear(Vec3(0.0, 0.01, 0.13));
    emu.setEncoders(a.encoders);
    FalconDevice dev("left", FalconConfig{}, 5.0);
    dev.setTimeouts(testTimeouts());
    REQUIRE_OPEN(dev); // only possible if the homed replies (byte 13 above 'P') were accepted
    const std::size_t atOpen = emu.commandCount();
    CHECK(emu.homedMask() == 0x7);
    CHECK(emu.lastReply()[13] > 'P'); // what a homed Falcon sends: 0x41 + (7 << 4) + buttons

    // Run with force for a while: every command still asks for homing, so it stays homed.
    std::atomic<bool> stop{false};
    std::thread servo([&] {
        while (!stop.load()) {
            DeviceState s;
            (void)dev.read(s);
            (void)dev.write(Vec3(0.5, 0.0, 0.0));
            std::this_thread::sleep_for(1ms);
        }
    });
    CHECK(eventually([&] { return emu.commandCount() > atOpen + 100; }));
    CHECK(emu.homedMask() == 0x7);
    stop = true;
    servo.join();
    dev.close();

    const auto cmds = emu.commands();
    REQUIRE(cmds.size() > atOpen);
    std::size_t homingCount = 0;
    for (std::size_t i = 0; i < cmds.size(); ++i) {
        INFO("command " << i);
        CHECK(cmds[i].homing); // the probe, homing, running and the last zero packet alike
        homingCount += cmds[i].homing ? 1 : 0;
        if (i < atOpen) {
            CHECK(cmds[i].motor == MotorWords{0, 0, 0}); // no force before homed
        }
    }
    CHECK(homingCount >= 20);
    CHECK(cmds.back().motor == MotorWords{0, 0, 0});
    CHECK(emu.homedMask() == 0x7); // close's zero packet asked for homing too
    CHECK(emu.badCommandFrames() == 0);
}

TEST_CASE("homing times out with a message telling the user what to do", "[emulated][threads]") {
    requireEmulation();
    FalconEmulatorOptions opt;
    opt.homeAfterPackets = -1;
    FalconEmulator emu(opt);
    FalconDevice dev("left", FalconConfig{}, 5.0);
    FalconTimeouts t = testTimeouts();
    t.homing = 300ms;
    dev.setTimeouts(t);
    CHECK(dev.open() == DeviceStatus::Error);
    CHECK_THAT(dev.errorMessage(), Catch::Contains("homing timed out") &&
                                       Catch::Contains("pull the grip all the way out"));
    const auto cmds = emu.commands();
    REQUIRE_FALSE(cmds.empty());
    CHECK(cmds.back().motor == MotorWords{0, 0, 0});
    CHECK(cmds.back().homing);
}

TEST_CASE("a second of I/O gives known positions and known motor words, zero at close",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    const Pose a = poseNear(Vec3(0.010, -0.015, 0.140));
    const Pose b = poseNear(Vec3(-0.020, 0.005, 0.125));
    emu.setEncoders(a.encoders);
    emu.setButtons(0x5);
    FalconDevice dev("right", noHoming(), 5.0);
    dev.setTimeouts(testTimeouts());
    REQUIRE_OPEN(dev);

    const Vec3 force(1.0, -0.5, 2.0);
    std::atomic<bool> stop{false};
    std::atomic<int> okReads{0}, okAtA{0}, okAtB{0}, okElsewhere{0};
    std::atomic<std::uint32_t> buttons{0};
    std::thread servo([&] {
        std::uint64_t lastSeq = 0;
        bool monotonic = true;
        while (!stop.load()) {
            DeviceState s;
            if (dev.read(s) == DeviceStatus::Ok) {
                ++okReads;
                monotonic = monotonic && s.sequence >= lastSeq;
                lastSeq = s.sequence;
                buttons = s.buttons;
                if (glm::length(s.position - (a.mechPosition - kOrigin)) < 1e-9) {
                    ++okAtA;
                } else if (glm::length(s.position - (b.mechPosition - kOrigin)) < 1e-9) {
                    ++okAtB;
                } else {
                    ++okElsewhere;
                }
            }
            dev.write(force);
            std::this_thread::sleep_for(1ms);
        }
        CHECK(monotonic);
    });

    const MotorWords wordsA = expectedWords(a, force);
    const MotorWords wordsB = expectedWords(b, force);
    REQUIRE(wordsA != MotorWords{0, 0, 0});
    CHECK(eventually([&] {
        const auto c = emu.commands();
        return !c.empty() && wordsClose(c.back().motor, wordsA);
    }));
    std::this_thread::sleep_for(500ms);
    emu.setEncoders(b.encoders);
    CHECK(eventually([&] { return okAtB.load() > 0; }));
    CHECK(eventually([&] {
        const auto c = emu.commands();
        return !c.empty() && wordsClose(c.back().motor, wordsB);
    }));
    std::this_thread::sleep_for(500ms);
    stop = true;
    servo.join();
    dev.close();

    CHECK(okAtA.load() > 0);
    CHECK(okAtB.load() > 0);
    CHECK(okElsewhere.load() == 0);
    CHECK(buttons.load() == 0x5);
    const auto cmds = emu.commands();
    REQUIRE(cmds.size() > 2);
    CHECK(cmds.back().motor == MotorWords{0, 0, 0}); // close() sent zero force last
    // "home": false only skips the wait: every packet still keeps the Falcon homed.
    CHECK(std::all_of(cmds.begin(), cmds.end(), [](const FalconCommand& c) { return c.homing; }));
    CHECK(emu.badCommandFrames() == 0);
    const FalconIoStats st = dev.ioStats();
    CHECK(st.framesDecoded > 0);
    CHECK(st.badFrames == 0);
    CHECK(st.garbageBytes == 0);
    CHECK(st.kinematicsFailures == 0);
    DeviceState s;
    CHECK(dev.read(s) == DeviceStatus::NotOpen);
    CHECK(dev.write(force) == DeviceStatus::NotOpen);
}

TEST_CASE("forces are clamped to the max force and non-finite forces become zero",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    const Pose a = poseNear(Vec3(0.0, 0.0, 0.130));
    emu.setEncoders(a.encoders);
    FalconDevice dev("left", noHoming(), 2.0);
    dev.setTimeouts(testTimeouts());
    REQUIRE_OPEN(dev);
    DeviceState s;
    REQUIRE(readOk(dev, s));
    const MotorWords clamped = expectedWords(a, Vec3(0.0, 0.0, 2.0));
    CHECK(eventually([&] {
        dev.write(Vec3(0.0, 0.0, 50.0));
        const auto c = emu.commands();
        return !c.empty() && wordsClose(c.back().motor, clamped);
    }));
    CHECK(eventually([&] {
        dev.write(Vec3(std::nan(""), 1.0, 1.0));
        const auto c = emu.commands();
        return !c.empty() && c.back().motor == MotorWords{0, 0, 0};
    }));
    dev.close();
}

TEST_CASE("motor words over the configured limit are scaled together: the force keeps its "
          "direction and the largest word equals the limit",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    const Pose a = poseNear(Vec3(0.01, -0.01, 0.13));
    emu.setEncoders(a.encoders);
    FalconConfig cfg = noHoming();
    cfg.motorWordLimit = 700;
    FalconDevice dev("left", cfg, 20.0);
    dev.setTimeouts(testTimeouts());
    REQUIRE_OPEN(dev);
    DeviceState s;
    REQUIRE(readOk(dev, s));

    const Vec3 force(3.0, -2.0, 6.0); // N, under the 20 N clamp
    const FalconKinematics k;
    const auto j = k.jacobian(a.mechPosition, a.angles);
    REQUIRE(j);
    const Vec3 raw = -FalconKinematics::forceToTorque(*j, force) * kMotorWordPerNm; // unlimited
    const double largest = std::max({std::abs(raw.x), std::abs(raw.y), std::abs(raw.z)});
    REQUIRE(largest > 700.0); // the test is only meaningful if the limit bites
    // Scaled together: raw * (700 / largest), rounded; a clamp per word would differ.
    MotorWords got{};
    CHECK(eventually([&] {
        dev.write(force);
        const auto c = emu.commands();
        if (c.empty() || c.back().motor == MotorWords{0, 0, 0}) {
            return false;
        }
        got = c.back().motor;
        return true;
    }));
    INFO("words " << got[0] << ", " << got[1] << ", " << got[2]);
    int biggest = 0;
    for (int i = 0; i < 3; ++i) {
        const auto w = got[static_cast<std::size_t>(i)];
        CHECK(std::abs(w - raw[i] * 700.0 / largest) <= 1.0);
        biggest = std::max(biggest, std::abs(int{w}));
    }
    CHECK(biggest == 700);
    dev.close();
}

TEST_CASE("a Falcon whose servo stops writing is commanded zero once the newest command is "
          "older than the command timeout (stepped clock)",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    const Pose a = poseNear(Vec3(0.0, 0.0, 0.130));
    emu.setEncoders(a.encoders);
    FalconConfig cfg = noHoming();
    cfg.commandTimeoutMs = 4.0;
    FalconDevice dev("left", cfg, 5.0);
    dev.setTimeouts(testTimeouts());
    const std::int64_t t0 = 5'000'000'000;
    gTestNowNs = t0;
    dev.setCommandClock(&testClock);
    REQUIRE_OPEN(dev);
    DeviceState s;
    REQUIRE(readOk(dev, s));

    const Vec3 force(1.0, -0.5, 2.0);
    const MotorWords words = expectedWords(a, force);
    REQUIRE(words != MotorWords{0, 0, 0});
    REQUIRE(dev.write(force) == DeviceStatus::Ok); // stamped t0; then the servo stalls
    // Exactly as old as the timeout: still applied, packet after packet.
    gTestNowNs = t0 + 4'000'000;
    REQUIRE(eventually([&] {
        const auto c = emu.commands();
        return !c.empty() && wordsClose(c.back().motor, words);
    }));
    const std::size_t young = emu.commandCount();
    REQUIRE(eventually([&] { return emu.commandCount() >= young + 50; }));
    auto cmds = emu.commands();
    for (std::size_t i = young; i < cmds.size(); ++i) {
        INFO("command " << i);
        CHECK(wordsClose(cmds[i].motor, words));
    }
    // One nanosecond older: zero from the next packet on (one may already be on its way).
    gTestNowNs = t0 + 4'000'001;
    const std::size_t old = emu.commandCount();
    REQUIRE(eventually([&] { return emu.commandCount() >= old + 50; }));
    cmds = emu.commands();
    std::size_t firstZero = old;
    while (firstZero < cmds.size() && cmds[firstZero].motor != MotorWords{0, 0, 0}) {
        ++firstZero;
    }
    CHECK(firstZero <= old + 1);
    for (std::size_t i = firstZero; i < cmds.size(); ++i) {
        INFO("command " << i);
        CHECK(cmds[i].motor == MotorWords{0, 0, 0});
    }
    // A fresh write brings the force back.
    REQUIRE(dev.write(force) == DeviceStatus::Ok);
    CHECK(eventually([&] {
        const auto c = emu.commands();
        return !c.empty() && wordsClose(c.back().motor, words);
    }));
    dev.close();
    gTestNowNs = 1'000'000'000;
}

TEST_CASE("a Falcon whose servo thread stops is commanded zero (steady clock)",
          "[emulated][realtime]") {
    requireEmulation();
    FalconEmulator emu;
    const Pose a = poseNear(Vec3(0.0, 0.0, 0.130));
    emu.setEncoders(a.encoders);
    FalconConfig cfg = noHoming();
    cfg.commandTimeoutMs = 2.0;
    FalconDevice dev("left", cfg, 5.0);
    dev.setTimeouts(testTimeouts());
    REQUIRE_OPEN(dev);
    std::atomic<bool> stop{false};
    std::thread servo([&] {
        while (!stop.load()) {
            (void)dev.write(Vec3(1.0, -0.5, 2.0));
            std::this_thread::sleep_for(200us);
        }
    });
    const bool forced = eventually([&] {
        const auto c = emu.commands();
        return !c.empty() && c.back().motor != MotorWords{0, 0, 0};
    });
    stop = true;
    servo.join(); // the servo thread is gone; the I/O thread keeps sending packets
    REQUIRE(forced);
    // Only the eventual zero is asserted (a loaded machine may take long to get there), and
    // that it stays zero for the next 50 packets.
    std::size_t zeroAt = 0;
    REQUIRE(eventually([&] {
        const auto c = emu.commands();
        zeroAt = c.size();
        return !c.empty() && c.back().motor == MotorWords{0, 0, 0};
    }));
    REQUIRE(eventually([&] { return emu.commandCount() >= zeroAt + 50; }));
    const auto cmds = emu.commands();
    for (std::size_t i = zeroAt; i < cmds.size(); ++i) {
        CHECK(cmds[i].motor == MotorWords{0, 0, 0});
    }
    dev.close();
}

TEST_CASE("garbage and short packets are counted and skipped, and only garbage is BadData",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    const Pose a = poseNear(Vec3(0.005, 0.010, 0.135));
    emu.setEncoders(a.encoders);
    emu.setReplyMode(ReplyMode::Fragmented);
    FalconDevice dev("left", noHoming(), 5.0);
    dev.setTimeouts(testTimeouts());
    REQUIRE_OPEN(dev);

    DeviceState s;
    REQUIRE(readOk(dev, s));
    CHECK(glm::length(s.position - (a.mechPosition - kOrigin)) < 1e-9);
    REQUIRE(eventually([&] { return dev.ioStats().shortTransfers > 3; }));
    const FalconIoStats st = dev.ioStats();
    CHECK(st.garbageBytes > 0);
    CHECK(st.badFrames > 0);
    CHECK(st.framesDecoded > 0);

    SECTION("nothing valid: BadData, then valid again: Ok") {
        emu.setReplyMode(ReplyMode::Garbage);
        CHECK(eventually([&] { return dev.read(s) == DeviceStatus::BadData; }));
        emu.setReplyMode(ReplyMode::Normal);
        CHECK(eventually([&] { return dev.read(s) == DeviceStatus::Ok; }));
    }
    SECTION("silence: Stalled, then answers again: Ok") {
        emu.setReplyMode(ReplyMode::Normal);
        REQUIRE(readOk(dev, s));
        emu.setReplyMode(ReplyMode::Silent);
        CHECK(eventually([&] { return dev.read(s) == DeviceStatus::Stalled; }));
        emu.setReplyMode(ReplyMode::Normal);
        CHECK(eventually([&] { return dev.read(s) == DeviceStatus::Ok; }));
    }
    dev.close();
}

TEST_CASE("unplugged mid-run, the servo sees Disconnected and close does not hang",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    const Pose a = poseNear(Vec3(0.0, 0.01, 0.14));
    emu.setEncoders(a.encoders);
    FalconDevice dev("left", noHoming(), 5.0);
    dev.setTimeouts(testTimeouts());
    REQUIRE_OPEN(dev);

    std::atomic<bool> stop{false};
    std::atomic<DeviceStatus> lastRead{DeviceStatus::NotOpen};
    std::atomic<DeviceStatus> lastWrite{DeviceStatus::NotOpen};
    std::thread servo([&] {
        while (!stop.load()) {
            DeviceState s;
            lastRead = dev.read(s);
            lastWrite = dev.write(Vec3(0.5, 0.0, 0.0));
            std::this_thread::sleep_for(1ms);
        }
    });
    REQUIRE(eventually([&] { return lastRead.load() == DeviceStatus::Ok; }));
    REQUIRE(eventually([&] {
        const auto c = emu.commands();
        return !c.empty() && c.back().motor != MotorWords{0, 0, 0};
    }));
    emu.unplug();
    CHECK(eventually([&] { return lastRead.load() == DeviceStatus::Disconnected; }));
    CHECK(eventually([&] { return lastWrite.load() == DeviceStatus::Disconnected; }));
    const std::size_t sentBeforeClose = emu.commandCount();
    stop = true;
    servo.join();
    dev.close(); // must return: nothing can be sent any more
    CHECK(emu.commandCount() == sentBeforeClose);
    CHECK_THAT(dev.errorMessage(), Catch::Contains("unplugged"));
    DeviceState s;
    CHECK(dev.read(s) == DeviceStatus::NotOpen);
    dev.close(); // twice is fine
}

TEST_CASE("unplugged and plugged back in, the same device opens again and drives the motors",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    const Pose a = poseNear(Vec3(0.0, 0.01, 0.14));
    emu.setEncoders(a.encoders);
    FalconDevice dev("left", noHoming(), 5.0);
    dev.setTimeouts(testTimeouts());
    // Reads and writes 0.5 N every millisecond until `seen` holds, then stops. The force must be
    // looked for while it is written: 10 ms after the last write the I/O thread sends zero.
    const auto driveUntil = [&](const auto& seen) {
        std::atomic<bool> stop{false};
        std::atomic<DeviceStatus> last{DeviceStatus::NotOpen};
        std::thread servo([&] {
            while (!stop.load()) {
                DeviceState s;
                last = dev.read(s);
                (void)dev.write(Vec3(0.5, 0.0, 0.0));
                std::this_thread::sleep_for(1ms);
            }
        });
        const bool held = eventually([&] { return seen(last.load()); });
        stop = true;
        servo.join();
        return held;
    };
    const auto reaches = [](DeviceStatus until) {
        return [until](DeviceStatus last) { return last == until; };
    };
    REQUIRE_OPEN(dev);
    REQUIRE(driveUntil(reaches(DeviceStatus::Ok)));
    emu.unplug();
    REQUIRE(driveUntil(reaches(DeviceStatus::Disconnected)));
    dev.close();
    CHECK(dev.open() != DeviceStatus::Ok); // still away: open says so, and does not hang
    dev.close();

    emu.replug();
    const std::size_t sentBefore = emu.commandCount();
    REQUIRE_OPEN(dev);
    CHECK(driveUntil([&](DeviceStatus last) {
        const auto c = emu.commands();
        return last == DeviceStatus::Ok && c.size() > sentBefore &&
               c.back().motor != MotorWords{0, 0, 0};
    }));
    DeviceState s;
    REQUIRE(dev.read(s) == DeviceStatus::Ok);
    CHECK(glm::length(s.position - (a.mechPosition - kOrigin)) < 1e-9); // the same pose
    dev.close();
    CHECK(emu.commands().back().motor == MotorWords{0, 0, 0}); // zero at close
}

TEST_CASE("devices are picked by serial or bus/address, and listed for `hapto devices`",
          "[emulated][threads]") {
    requireEmulation();
    FalconEmulator emu;
    std::string why;
    const auto found = listFalcons(why);
    REQUIRE(found.size() == 1);
    CHECK(found[0].bus == 1);
    CHECK(found[0].address == 2);
    CHECK(found[0].serial == "FTHAPTO1");
    CHECK(why.empty());

    SECTION("a serial that is not there") {
        FalconConfig cfg = noHoming();
        cfg.serial = "NOPE";
        FalconDevice dev("left", cfg, 5.0);
        dev.setTimeouts(testTimeouts());
        CHECK(dev.open() == DeviceStatus::Disconnected);
        CHECK_THAT(dev.errorMessage(),
                   Catch::Contains("serial NOPE") && Catch::Contains("serial FTHAPTO1"));
    }
    SECTION("the right serial on the right bus and address") {
        FalconConfig cfg = noHoming();
        cfg.serial = "FTHAPTO1";
        cfg.bus = 1;
        cfg.address = 2;
        FalconDevice dev("left", cfg, 5.0);
        dev.setTimeouts(testTimeouts());
        REQUIRE_OPEN(dev);
        dev.close();
    }
    SECTION("another address") {
        FalconConfig cfg = noHoming();
        cfg.address = 9;
        FalconDevice dev("left", cfg, 5.0);
        dev.setTimeouts(testTimeouts());
        CHECK(dev.open() == DeviceStatus::Disconnected);
        CHECK_THAT(dev.errorMessage(), Catch::Contains("bus 1 address 2"));
    }
}

TEST_CASE("with no Falcon on the bus, discovery says so", "[emulated][threads]") {
    requireEmulation();
    UMockdevTestbed* tb = umockdev_testbed_new(); // an empty bus
    std::string why;
    CHECK(listFalcons(why).empty());
    CHECK(why == "no 0403:cb48 device on the USB bus");
    FalconDevice dev("left", noHoming(), 5.0);
    CHECK(dev.open() == DeviceStatus::Disconnected);
    CHECK_THAT(dev.errorMessage(), Catch::Contains("no Novint Falcon (USB 0403:cb48) found") &&
                                       Catch::Contains("plugged in"));
    g_object_unref(tb);
}
