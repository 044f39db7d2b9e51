// The Falcon backend's parts on their own, against the emulated Falcon (umockdev): the USB/FTDI
// transport, the firmware probe and upload, the I/O thread and homing, each without
// FalconDevice around it. Run under umockdev-wrapper (CTest does); by hand without it, exit 77.
#include "FalconEmulator.h"
#include "TestSupport.h"

#include "falcon/FalconFirmwareUpload.h"
#include "falcon/FalconHoming.h"
#include "falcon/FalconIoThread.h"
#include "falcon/FalconTransport.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

using namespace hapto;
using namespace hapto::falcon;
using hapto::test::eventually;
using hapto::test::FalconEmulator;
using hapto::test::FalconEmulatorOptions;
using namespace std::chrono_literals;

namespace {

void requireEmulationHere() {
    if (FalconEmulator::inMockEnvironment()) {
        return;
    }
    if (std::getenv("HAPTO_FALCON_EMULATION_REQUIRED")) {
        FAIL("not running under umockdev-wrapper, but CTest requires the emulated Falcon");
    }
    std::fprintf(stderr, "skipped: the emulated-Falcon tests must run under umockdev-wrapper\n");
    std::exit(77);
}

IoSettings testSettings() {
    IoSettings s;
    s.timeouts.usb = 1000ms;
    s.timeouts.probe = 200ms;
    s.commandTimeoutNs = 10'000'000;
    return s;
}

} // namespace

TEST_CASE("falcon transport: opens the Falcon it is asked for, names what it found otherwise",
          "[emulated][threads]") {
    requireEmulationHere();
    FalconEmulator emu;
    std::string error;
    FalconTransport usb(error);
    FalconConfig wrong;
    wrong.serial = "NOTTHERE";
    CHECK(usb.open("left", wrong) == DeviceStatus::Disconnected);
    CHECK_FALSE(usb.isOpen());
    CHECK_THAT(error, Catch::Contains("device 'left'") && Catch::Contains("serial NOTTHERE") &&
                          Catch::Contains("FTHAPTO1"));
    FalconConfig right;
    right.serial = "FTHAPTO1";
    REQUIRE(usb.open("left", right) == DeviceStatus::Ok);
    CHECK(usb.isOpen());
    CHECK(emu.ftdiRequests().size() == 7); // reset and the normal-mode line settings
    usb.close();
    usb.close(); // safe twice
    CHECK_FALSE(usb.isOpen());
}

TEST_CASE("falcon firmware: the probe sees no firmware under the bootloader, the upload loads "
          "the image, then the probe answers",
          "[emulated][threads]") {
    requireEmulationHere();
    hapto::test::TempDir dir;
    std::string image;
    for (int i = 0; i < 300; ++i) {
        image.push_back(static_cast<char>((i * 53 + 7) & 0xFF));
    }
    hapto::test::writeFile(dir / "falcon.bin", image);
    FalconEmulatorOptions opt;
    opt.firmwareLoaded = false;
    FalconEmulator emu(opt);
    std::string error;
    FalconTransport usb(error);
    REQUIRE(usb.open("left", FalconConfig{}) == DeviceStatus::Ok);
    CHECK_FALSE(firmwareAnswers(usb, 200ms));
    CHECK_FALSE(uploadFirmware(usb, dir / "missing.bin", 200ms));
    CHECK_THAT(error, Catch::Contains("missing.bin"));
    REQUIRE(uploadFirmware(usb, dir / "falcon.bin", 200ms));
    const auto uploaded = emu.uploadedImage();
    CHECK(std::string(uploaded.begin(), uploaded.end()) == image);
    CHECK(firmwareAnswers(usb, 200ms));
    usb.close();
}

TEST_CASE("falcon I/O thread: zero motor words while homing or without a command, the last "
          "packet zero, every packet with the homing bit",
          "[emulated][threads]") {
    requireEmulationHere();
    FalconEmulator emu;
    std::string error;
    FalconTransport usb(error);
    REQUIRE(usb.open("left", FalconConfig{}) == DeviceStatus::Ok);
    FalconIoThread io;
    io.configure(testSettings());
    io.setHoming(true);
    io.start(usb);
    IoSample s{};
    REQUIRE(eventually([&] { return io.newestSample(s); }));
    CHECK(io.state() == IoState::Running);
    io.command(Vec3(1.0, 0.0, 0.0)); // held at zero: homing
    const std::size_t before = emu.commandCount();
    REQUIRE(eventually([&] { return emu.commandCount() > before + 20; }));
    io.setHoming(false);
    REQUIRE(eventually([&] {
        io.command(Vec3(1.0, 0.0, 0.0));
        const auto cmds = emu.commands();
        return !cmds.empty() && cmds.back().motor != MotorWords{0, 0, 0};
    }));
    io.stop();
    const auto cmds = emu.commands();
    REQUIRE(cmds.size() > before);
    for (std::size_t i = 0; i < before; ++i) {
        CHECK(cmds[i].motor == MotorWords{0, 0, 0});
    }
    for (const auto& c : cmds) {
        CHECK(c.homing);
    }
    CHECK(cmds.back().motor == MotorWords{0, 0, 0});
    CHECK(io.stats().samplesPublished > 0);
    usb.close();
}

TEST_CASE("falcon homing: done once all three flags are homed, a timeout says what to do",
          "[emulated][threads]") {
    requireEmulationHere();
    FalconEmulatorOptions opt;
    SECTION("homes") {
        opt.homeAfterPackets = 10;
    }
    SECTION("never homes") {
        opt.homeAfterPackets = -1;
    }
    FalconEmulator emu(opt);
    std::string error;
    FalconTransport usb(error);
    REQUIRE(usb.open("left", FalconConfig{}) == DeviceStatus::Ok);
    FalconIoThread io;
    io.configure(testSettings());
    io.start(usb);
    const bool homed = homeFalcon(io, "left", opt.homeAfterPackets < 0 ? 300ms : 10s, error);
    CHECK(homed == (opt.homeAfterPackets >= 0));
    if (homed) {
        CHECK(emu.homedMask() == 0x7);
    } else {
        CHECK_THAT(error, Catch::Contains("device 'left': homing timed out") &&
                              Catch::Contains("pull the grip all the way out"));
    }
    io.stop();
    usb.close();
}
