#include "FalconFirmwareUpload.h"

#include "hapto/devices/FalconPacket.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace hapto::falcon {
namespace {
using Clock = std::chrono::steady_clock;
} // namespace

bool firmwareAnswers(FalconTransport& usb, std::chrono::milliseconds probe) {
    FalconCommand packet;
    packet.homing = true; // a homed Falcon stays homed only while every packet asks for it
    const Packet p = encodeCommand(packet);
    if (!usb.writeBytes(p.data(), p.size())) {
        return false;
    }
    FalconStreamParser replies;
    bool answered = false;
    const auto deadline = Clock::now() + probe;
    while (!answered && Clock::now() < deadline) {
        const auto bytes = usb.readBytes(kPacketSize, probe);
        replies.pushPayload(bytes, [&](const Packet&) { answered = true; });
        if (usb.lastUsbError() == LIBUSB_ERROR_NO_DEVICE) {
            break;
        }
    }
    return answered;
}

bool uploadFirmware(FalconTransport& usb, const std::filesystem::path& path,
                    std::chrono::milliseconds probe) {
    if (path.empty()) {
        return usb.fail("the Falcon has no firmware loaded (it is lost at power-off) and no "
                        "firmware file is configured: set \"firmware\" in the device's "
                        "configuration to your Falcon firmware image (see README, \"Novint "
                        "Falcon\")");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return usb.fail("cannot read the Falcon firmware file " + path.string() +
                        ": check the \"firmware\" path in the device configuration");
    }
    const std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    if (image.empty()) {
        return usb.fail("the Falcon firmware file " + path.string() + " is empty");
    }
    // 1. Bootloader line settings (setFirmwareMode: purge, latency 16 ms, 9600 baud, 8N1, no
    // flow control, RTS low, DTR low then high).
    if (!(usb.ftdi(kReqReset, kPurgeRx) && usb.ftdi(kReqReset, kPurgeTx) &&
          usb.ftdi(kReqLatency, 16) && usb.ftdi(kReqBaud, kBaudBootloader) &&
          usb.ftdi(kReqData, kData8N1) && usb.ftdi(kReqFlow, 0) && usb.ftdi(kReqModem, kRtsLow) &&
          usb.ftdi(kReqModem, kDtrLow) && usb.ftdi(kReqModem, kDtrHigh))) {
        return false;
    }
    // 2. Handshake: 0A 43 0D -> 0A 44 2C 0D (possibly after a 00).
    bool shook = false;
    for (int attempt = 0; attempt < kHandshakeAttempts && !shook; ++attempt) {
        const std::uint8_t hello[3] = {0x0A, 0x43, 0x0D};
        if (!usb.writeBytes(hello, sizeof hello)) {
            return false;
        }
        auto reply = usb.readBytes(4, probe);
        if (!reply.empty() && reply.front() == 0x00) {
            reply.erase(reply.begin());
            const auto more = usb.readBytes(4 - reply.size(), probe);
            reply.insert(reply.end(), more.begin(), more.end());
        }
        shook = reply == std::vector<std::uint8_t>{0x0A, 0x44, 0x2C, 0x0D};
        if (!shook && !(usb.ftdi(kReqReset, kPurgeRx) && usb.ftdi(kReqReset, kPurgeTx))) {
            return false;
        }
    }
    if (!shook) {
        return usb.fail("the Falcon's bootloader did not answer the firmware handshake (" +
                        std::to_string(kHandshakeAttempts) +
                        " tries): power-cycle the Falcon (unplug its power, not just USB) and "
                        "try again");
    }
    // 3. Upload mode.
    const std::uint8_t go = 0x41;
    if (!(usb.ftdi(kReqModem, kDtrLow) && usb.ftdi(kReqBaud, kBaudUpload) &&
          usb.writeBytes(&go, 1))) {
        return false;
    }
    if (usb.readBytes(1, usb.usbTimeout()) != std::vector<std::uint8_t>{go}) {
        return usb.fail("the Falcon's bootloader did not acknowledge the upload: power-cycle "
                        "the Falcon and try again");
    }
    // 4. The image, in chunks the bootloader echoes back (FalconFirmware::loadFirmware).
    for (std::size_t at = 0; at < image.size(); at += kMaxPayloadPerTransfer) {
        const std::size_t n = std::min(kMaxPayloadPerTransfer, image.size() - at);
        if (!usb.writeBytes(image.data() + at, n)) {
            return false;
        }
        const auto echo = usb.readBytes(n, usb.usbTimeout());
        if (echo.size() != n || !std::equal(echo.begin(), echo.end(), image.begin() + at)) {
            return usb.fail("firmware upload failed at byte " + std::to_string(at) + " of " +
                            path.string() + ": the Falcon echoed " + std::to_string(echo.size()) +
                            " bytes that do not match; power-cycle it and try again");
        }
    }
    // 5. Back to normal I/O.
    return usb.normalMode();
}

} // namespace hapto::falcon
