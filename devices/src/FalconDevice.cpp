#include "hapto/devices/FalconDevice.h"

#include "hapto/core/Clock.h"
#include "hapto/core/Finite.h"
#include "hapto/core/Mailbox.h"

#include "hapto/devices/FalconKinematics.h"
#include "hapto/devices/FalconPacket.h"

#include <libusb.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <thread>
#include <type_traits>

namespace hapto {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

constexpr std::uint16_t kVendorId = 0x0403;
constexpr std::uint16_t kProductId = 0xCB48;
constexpr unsigned char kEndpointOut = 0x02;
constexpr unsigned char kEndpointIn = 0x81;
constexpr int kInterface = 0;
constexpr int kTransferSize = 64;
constexpr double kDefaultMaxForceN = 8.9; // the Falcon's rated peak force

// FTDI vendor requests (bmRequestType 0x40, wIndex 0).
constexpr std::uint8_t kFtdiOut = 0x40;
constexpr std::uint8_t kReqReset = 0, kReqModem = 1, kReqFlow = 2, kReqBaud = 3, kReqData = 4,
                       kReqLatency = 9;
constexpr std::uint16_t kResetSio = 0, kPurgeRx = 1, kPurgeTx = 2;
constexpr std::uint16_t kDtrLow = 0x0100, kDtrHigh = 0x0101, kRtsLow = 0x0200;
constexpr std::uint16_t kData8N1 = 0x0008;
constexpr std::uint16_t kBaudBootloader = 0x4138; // 9600 baud
constexpr std::uint16_t kBaudUpload = 0x0015;
constexpr std::uint16_t kBaudNormal = 0x0002; // 1.5 Mbaud
constexpr int kHandshakeAttempts = 10;

/// The monotonic clock (core), signed so that differences of stamps can be negative.
std::int64_t nowNs() {
    return static_cast<std::int64_t>(monotonicNs());
}

std::string usbError(int rc) {
    return libusb_strerror(static_cast<libusb_error>(rc));
}

/// The newest decoded sample, written by the I/O thread.
struct Sample {
    Vec3 positionM{0.0};        ///< Device frame, workspace-centred (m).
    std::int16_t encoder[3]{};  ///< Raw encoder counts.
    std::uint8_t buttons = 0;   ///< Grip buttons.
    std::uint8_t homedMask = 0; ///< Homed flags.
    std::uint64_t sequence = 0; ///< 1, 2, ... per published sample.
    std::int64_t timeNs = 0;    ///< Monotonic time of arrival (ns).
};
static_assert(std::is_trivially_copyable_v<Sample> && sizeof(Sample) == 48,
              "Sample is six plain words");

/// The newest force, written by the servo (or control) thread.
struct Command {
    Vec3 forceN{0.0};        ///< Device frame (N).
    std::int64_t timeNs = 0; ///< Command-clock time of the write (ns).
};
static_assert(std::is_trivially_copyable_v<Command>);

enum class IoState : std::uint8_t { Running, Disconnected, Error };

struct Counters {
    std::atomic<std::uint64_t> commandsSent{0}, framesDecoded{0}, samplesPublished{0}, badFrames{0},
        garbageBytes{0}, shortTransfers{0}, kinematicsFailures{0}, transferErrors{0};
};

/// The first readable Falcon matching `config`, or an explanation.
struct Match {
    libusb_device* device = nullptr; ///< Referenced; caller unrefs.
    std::string why;
};

bool isFalcon(libusb_device* dev) {
    libusb_device_descriptor d{};
    return libusb_get_device_descriptor(dev, &d) == 0 && d.idVendor == kVendorId &&
           d.idProduct == kProductId;
}

std::string readSerial(libusb_device_handle* h, libusb_device* dev) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(dev, &d) != 0 || d.iSerialNumber == 0) {
        return {};
    }
    unsigned char buf[128]{};
    const int n = libusb_get_string_descriptor_ascii(h, d.iSerialNumber, buf, sizeof buf - 1);
    return n > 0 ? std::string(reinterpret_cast<const char*>(buf), static_cast<std::size_t>(n))
                 : std::string();
}

std::string where(libusb_device* dev) {
    return "bus " + std::to_string(libusb_get_bus_number(dev)) + " address " +
           std::to_string(libusb_get_device_address(dev));
}

const char* kUdevHint = "install the udev rule devices/udev/99-hapto-falcon.rules, add yourself "
                        "to the plugdev group and re-plug the Falcon (see README, \"Novint "
                        "Falcon\")";

} // namespace

// ---------------------------------------------------------------------------------------------
// Discovery

std::vector<FalconInfo> listFalcons(std::string& whyNone) {
    std::vector<FalconInfo> out;
    whyNone.clear();
    libusb_context* ctx = nullptr;
    if (const int rc = libusb_init(&ctx); rc != 0) {
        whyNone = "libusb could not be initialised: " + usbError(rc);
        return out;
    }
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx, &list);
    if (n < 0) {
        whyNone = "libusb could not list USB devices: " + usbError(static_cast<int>(n));
        libusb_exit(ctx);
        return out;
    }
    int found = 0;
    std::string denied;
    for (ssize_t i = 0; i < n; ++i) {
        libusb_device* dev = list[i];
        if (!isFalcon(dev)) {
            continue;
        }
        ++found;
        libusb_device_handle* h = nullptr;
        const int rc = libusb_open(dev, &h);
        if (rc == LIBUSB_ERROR_ACCESS) {
            denied += (denied.empty() ? "" : ", ") + where(dev);
            continue;
        }
        FalconInfo info;
        info.bus = libusb_get_bus_number(dev);
        info.address = libusb_get_device_address(dev);
        if (rc == 0) {
            info.serial = readSerial(h, dev);
            libusb_close(h);
        }
        out.push_back(std::move(info));
    }
    libusb_free_device_list(list, 1);
    libusb_exit(ctx);
    if (out.empty()) {
        whyNone = found == 0
                      ? "no 0403:cb48 device on the USB bus"
                      : "permission denied opening the Falcon on " + denied + ": " + kUdevHint;
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// The device

struct FalconDevice::Impl {
    // Configuration (control thread).
    std::string name;
    FalconConfig config;
    double maxForceN = kDefaultMaxForceN;
    FalconTimeouts timeouts;
    std::int64_t commandTimeoutNs = 2'000'000; ///< A command older than this is not applied.
    std::int64_t (*commandClock)() = &nowNs;   ///< Stamps commands and judges their age (ns).
    falcon::FalconKinematics kinematics;

    // USB (control thread, then owned by the I/O thread between open and close).
    libusb_context* ctx = nullptr;
    libusb_device_handle* handle = nullptr;
    libusb_transfer* inTransfer = nullptr;
    libusb_transfer* outTransfer = nullptr;
    std::array<unsigned char, kTransferSize> inBuffer{};
    std::array<unsigned char, falcon::kPacketSize> outBuffer{};
    std::thread ioThread;

    // State shared between threads.
    std::atomic<bool> open{false};
    std::atomic<bool> stopRequested{false};
    std::atomic<bool> homing{false};   // waiting for the homed flags: motor words held at zero
    std::atomic<std::uint8_t> leds{0}; // bit1 green, bit2 blue, bit3 red (packet layout)
    std::atomic<IoState> ioState{IoState::Running};
    std::atomic<bool> badSinceValid{false};
    std::atomic<int> lastUsbError{0};
    Mailbox<Sample> samples;
    Mailbox<Command> commands;
    Counters counters;
    bool firmwareWasLoaded = false;
    std::string error;

    // I/O-thread-only state.
    falcon::FalconStreamParser parser;
    bool inFlight = false;
    bool outFlight = false;
    bool replySinceSend = false;
    bool zeroSent = false;
    int consecutiveErrors = 0;
    std::uint64_t sequence = 0;
    Vec3 lastMechPosition = falcon::FalconKinematics::defaultStart();
    falcon::Angles lastAngles{};
    bool havePose = false;

    // ---- set-up (control thread) ------------------------------------------------------------

    bool fail(std::string message) {
        error = std::move(message);
        return false;
    }

    bool ftdi(std::uint8_t request, std::uint16_t value) {
        const int rc = libusb_control_transfer(handle, kFtdiOut, request, value, 0, nullptr, 0,
                                               static_cast<unsigned>(timeouts.usb.count()));
        if (rc < 0) {
            lastUsbError = rc;
            return fail("FTDI set-up request " + std::to_string(request) +
                        " failed: " + usbError(rc));
        }
        return true;
    }

    bool writeBytes(const std::uint8_t* data, std::size_t length) {
        int done = 0;
        const int rc = libusb_bulk_transfer(handle, kEndpointOut, const_cast<std::uint8_t*>(data),
                                            static_cast<int>(length), &done,
                                            static_cast<unsigned>(timeouts.usb.count()));
        if (rc != 0 || static_cast<std::size_t>(done) != length) {
            lastUsbError = rc;
            return fail("writing to the Falcon failed: " + usbError(rc));
        }
        return true;
    }

    /// Reads payload bytes (status bytes stripped) until `want` arrived or `timeout` passed.
    std::vector<std::uint8_t> readBytes(std::size_t want, std::chrono::milliseconds timeout) {
        std::vector<std::uint8_t> out;
        const auto deadline = Clock::now() + timeout;
        while (out.size() < want) {
            const auto left =
                std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
            if (left.count() <= 0) {
                break;
            }
            unsigned char buf[kTransferSize];
            int got = 0;
            const int rc = libusb_bulk_transfer(handle, kEndpointIn, buf, kTransferSize, &got,
                                                static_cast<unsigned>(left.count()));
            if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT) {
                lastUsbError = rc;
                break;
            }
            if (got > static_cast<int>(falcon::kFtdiStatusBytes)) {
                out.insert(out.end(), buf + falcon::kFtdiStatusBytes, buf + got);
            }
        }
        return out;
    }

    bool normalMode() {
        return ftdi(kReqLatency, 1) && ftdi(kReqBaud, kBaudNormal) && ftdi(kReqData, kData8N1) &&
               ftdi(kReqFlow, 0) && ftdi(kReqReset, kPurgeRx) && ftdi(kReqReset, kPurgeTx);
    }

    /// Sends one zero-force packet and waits briefly for any valid reply frame.
    bool firmwareAnswers() {
        falcon::FalconCommand probe;
        probe.homing = true; // a homed Falcon stays homed only while every packet asks for it
        const falcon::Packet p = falcon::encodeCommand(probe);
        if (!writeBytes(p.data(), p.size())) {
            return false;
        }
        falcon::FalconStreamParser replies;
        bool answered = false;
        const auto deadline = Clock::now() + timeouts.probe;
        while (!answered && Clock::now() < deadline) {
            const auto bytes = readBytes(falcon::kPacketSize, timeouts.probe);
            replies.pushPayload(bytes, [&](const falcon::Packet&) { answered = true; });
            if (lastUsbError == LIBUSB_ERROR_NO_DEVICE) {
                break;
            }
        }
        return answered;
    }

    bool uploadFirmware() {
        const auto& path = config.firmware;
        if (path.empty()) {
            return fail("the Falcon has no firmware loaded (it is lost at power-off) and no "
                        "firmware file is configured: set \"firmware\" in the device's "
                        "configuration to your Falcon firmware image (see README, \"Novint "
                        "Falcon\")");
        }
        std::ifstream in(path, std::ios::binary);
        if (!in) {
            return fail("cannot read the Falcon firmware file " + path.string() +
                        ": check the \"firmware\" path in the device configuration");
        }
        const std::vector<std::uint8_t> image((std::istreambuf_iterator<char>(in)),
                                              std::istreambuf_iterator<char>());
        if (image.empty()) {
            return fail("the Falcon firmware file " + path.string() + " is empty");
        }
        // 1. Bootloader line settings.
        if (!(ftdi(kReqReset, kPurgeRx) && ftdi(kReqReset, kPurgeTx) && ftdi(kReqLatency, 16) &&
              ftdi(kReqBaud, kBaudBootloader) && ftdi(kReqData, kData8N1) && ftdi(kReqFlow, 0) &&
              ftdi(kReqModem, kRtsLow) && ftdi(kReqModem, kDtrLow) && ftdi(kReqModem, kDtrHigh))) {
            return false;
        }
        // 2. Handshake: 0A 43 0D -> 0A 44 2C 0D (possibly after a 00).
        bool shook = false;
        for (int attempt = 0; attempt < kHandshakeAttempts && !shook; ++attempt) {
            const std::uint8_t hello[3] = {0x0A, 0x43, 0x0D};
            if (!writeBytes(hello, sizeof hello)) {
                return false;
            }
            auto reply = readBytes(4, timeouts.probe);
            if (!reply.empty() && reply.front() == 0x00) {
                reply.erase(reply.begin());
                const auto more = readBytes(4 - reply.size(), timeouts.probe);
                reply.insert(reply.end(), more.begin(), more.end());
            }
            shook = reply == std::vector<std::uint8_t>{0x0A, 0x44, 0x2C, 0x0D};
            if (!shook && !(ftdi(kReqReset, kPurgeRx) && ftdi(kReqReset, kPurgeTx))) {
                return false;
            }
        }
        if (!shook) {
            return fail("the Falcon's bootloader did not answer the firmware handshake (" +
                        std::to_string(kHandshakeAttempts) +
                        " tries): power-cycle the Falcon (unplug its power, not just USB) and "
                        "try again");
        }
        // 3. Upload mode.
        const std::uint8_t go = 0x41;
        if (!(ftdi(kReqModem, kDtrLow) && ftdi(kReqBaud, kBaudUpload) && writeBytes(&go, 1))) {
            return false;
        }
        if (readBytes(1, timeouts.usb) != std::vector<std::uint8_t>{go}) {
            return fail("the Falcon's bootloader did not acknowledge the upload: power-cycle "
                        "the Falcon and try again");
        }
        // 4. The image, in echoed chunks.
        for (std::size_t at = 0; at < image.size(); at += falcon::kMaxPayloadPerTransfer) {
            const std::size_t n = std::min(falcon::kMaxPayloadPerTransfer, image.size() - at);
            if (!writeBytes(image.data() + at, n)) {
                return false;
            }
            const auto echo = readBytes(n, timeouts.usb);
            if (echo.size() != n || !std::equal(echo.begin(), echo.end(), image.begin() + at)) {
                return fail("firmware upload failed at byte " + std::to_string(at) + " of " +
                            path.string() + ": the Falcon echoed " + std::to_string(echo.size()) +
                            " bytes that do not match; power-cycle it and try again");
            }
        }
        // 5. Back to normal I/O.
        return normalMode();
    }

    bool findAndOpen() {
        libusb_device** list = nullptr;
        const ssize_t n = libusb_get_device_list(ctx, &list);
        if (n < 0) {
            return fail("libusb could not list USB devices: " + usbError(static_cast<int>(n)));
        }
        std::string seen;
        std::string denied;
        for (ssize_t i = 0; i < n && !handle; ++i) {
            libusb_device* dev = list[i];
            if (!isFalcon(dev)) {
                continue;
            }
            if ((config.bus >= 0 && libusb_get_bus_number(dev) != config.bus) ||
                (config.address >= 0 && libusb_get_device_address(dev) != config.address)) {
                seen += (seen.empty() ? "" : "; ") + where(dev);
                continue;
            }
            libusb_device_handle* h = nullptr;
            const int rc = libusb_open(dev, &h);
            if (rc == LIBUSB_ERROR_ACCESS) {
                denied += (denied.empty() ? "" : ", ") + where(dev);
                continue;
            }
            if (rc != 0) {
                seen += (seen.empty() ? "" : "; ") + where(dev) + " (" + usbError(rc) + ")";
                continue;
            }
            const std::string serial = readSerial(h, dev);
            if (!config.serial.empty() && serial != config.serial) {
                seen += (seen.empty() ? "" : "; ") + where(dev) + " serial " +
                        (serial.empty() ? "(unreadable)" : serial);
                libusb_close(h);
                continue;
            }
            handle = h;
        }
        libusb_free_device_list(list, 1);
        if (handle) {
            return true;
        }
        if (!denied.empty()) {
            return fail("permission denied opening the Falcon on " + denied + ": " + kUdevHint);
        }
        std::string wanted = "Novint Falcon (USB 0403:cb48)";
        if (!config.serial.empty()) {
            wanted += " with serial " + config.serial;
        }
        if (config.bus >= 0 || config.address >= 0) {
            wanted += " on bus " + (config.bus >= 0 ? std::to_string(config.bus) : "any") +
                      " address " + (config.address >= 0 ? std::to_string(config.address) : "any");
        }
        return fail("device '" + name + "': no " + wanted + " found" +
                    (seen.empty() ? ": is it plugged in and powered? (`hapto devices` lists "
                                    "what is connected)"
                                  : "; found instead: " + seen));
    }

    // ---- I/O thread ---------------------------------------------------------------------------

    static void LIBUSB_CALL onIn(libusb_transfer* t) {
        static_cast<Impl*>(t->user_data)->inDone(t);
    }
    static void LIBUSB_CALL onOut(libusb_transfer* t) {
        static_cast<Impl*>(t->user_data)->outDone(t);
    }

    void markDisconnected() { ioState.store(IoState::Disconnected, std::memory_order_release); }

    void transferFailed(libusb_transfer_status status) {
        if (status == LIBUSB_TRANSFER_NO_DEVICE) {
            markDisconnected();
            return;
        }
        counters.transferErrors.fetch_add(1, std::memory_order_relaxed);
        if (++consecutiveErrors > 100) {
            ioState.store(IoState::Error, std::memory_order_release);
        }
    }

    void onFrame(const falcon::Packet& frame) {
        const auto reading = falcon::decode(frame);
        if (!reading) {
            badSinceValid.store(true, std::memory_order_relaxed);
            return;
        }
        counters.framesDecoded.fetch_add(1, std::memory_order_relaxed);
        replySinceSend = true;
        const falcon::Angles angles = falcon::FalconKinematics::encodersToAngles(reading->encoder);
        auto p = kinematics.forward(angles, havePose ? lastMechPosition
                                                     : falcon::FalconKinematics::defaultStart());
        if (!p && havePose) {
            p = kinematics.forward(angles); // a jump: retry from the workspace centre
        }
        if (!p) {
            counters.kinematicsFailures.fetch_add(1, std::memory_order_relaxed);
            badSinceValid.store(true, std::memory_order_relaxed);
            return;
        }
        lastMechPosition = *p;
        lastAngles = angles;
        havePose = true;
        Sample s{};
        s.positionM = Vec3(p->x, p->y, p->z - falcon::kWorkspaceOriginZ);
        for (int i = 0; i < 3; ++i) {
            s.encoder[i] = reading->encoder[static_cast<std::size_t>(i)];
        }
        s.buttons = reading->buttons;
        s.homedMask = reading->homedMask;
        s.sequence = ++sequence;
        s.timeNs = nowNs();
        samples.publish(s);
        badSinceValid.store(false, std::memory_order_relaxed);
        counters.samplesPublished.fetch_add(1, std::memory_order_relaxed);
    }

    /// Copies the parser's counters out; true when it saw new bad input.
    bool syncParserCounters() {
        const auto& st = parser.stats();
        const bool fresh =
            st.badFrames != counters.badFrames.load(std::memory_order_relaxed) ||
            st.garbageBytes != counters.garbageBytes.load(std::memory_order_relaxed) ||
            st.shortTransfers != counters.shortTransfers.load(std::memory_order_relaxed);
        counters.badFrames.store(st.badFrames, std::memory_order_relaxed);
        counters.garbageBytes.store(st.garbageBytes, std::memory_order_relaxed);
        counters.shortTransfers.store(st.shortTransfers, std::memory_order_relaxed);
        return fresh;
    }

    void inDone(libusb_transfer* t) {
        inFlight = false;
        if (t->status == LIBUSB_TRANSFER_COMPLETED) {
            consecutiveErrors = 0;
            const std::uint64_t before = sequence;
            parser.pushTransfer(std::span<const std::uint8_t>(
                                    t->buffer, static_cast<std::size_t>(t->actual_length)),
                                [this](const falcon::Packet& f) { onFrame(f); });
            // Bad input with no valid sample in the same transfer: BadData once samples go stale.
            if (syncParserCounters() && sequence == before) {
                badSinceValid.store(true, std::memory_order_relaxed);
            }
        } else if (t->status != LIBUSB_TRANSFER_CANCELLED) {
            transferFailed(t->status);
        }
        if (!stopRequested.load(std::memory_order_relaxed) &&
            ioState.load(std::memory_order_relaxed) == IoState::Running) {
            submitIn();
        }
    }

    void outDone(libusb_transfer* t) {
        outFlight = false;
        if (t->status == LIBUSB_TRANSFER_COMPLETED) {
            consecutiveErrors = 0;
            counters.commandsSent.fetch_add(1, std::memory_order_relaxed);
        } else if (t->status != LIBUSB_TRANSFER_CANCELLED) {
            transferFailed(t->status);
        }
    }

    void submitIn() {
        libusb_fill_bulk_transfer(inTransfer, handle, kEndpointIn, inBuffer.data(), kTransferSize,
                                  &Impl::onIn, this, 0);
        const int rc = libusb_submit_transfer(inTransfer);
        if (rc == 0) {
            inFlight = true;
        } else if (rc == LIBUSB_ERROR_NO_DEVICE) {
            markDisconnected();
        } else {
            lastUsbError = rc;
            ioState.store(IoState::Error, std::memory_order_release);
        }
    }

    /// The motor words for the newest force at the newest pose (zero while homing, without a
    /// pose, or when the newest command is older than the command timeout: a stalled servo).
    falcon::MotorWords motorWords(bool zero) {
        if (zero || !havePose || homing.load(std::memory_order_relaxed)) {
            return {0, 0, 0};
        }
        Command c{};
        if (!commands.read(c) || commandClock() - c.timeNs > commandTimeoutNs) {
            return {0, 0, 0};
        }
        const auto j = kinematics.jacobian(lastMechPosition, lastAngles);
        if (!j) {
            return {0, 0, 0};
        }
        const Vec3 tau = falcon::FalconKinematics::forceToTorque(*j, c.forceN);
        return falcon::FalconKinematics::torqueToMotorWords(tau, config.motorWordLimit);
    }

    void submitOut(bool zero) {
        falcon::FalconCommand cmd;
        cmd.motor = motorWords(zero);
        const std::uint8_t l = zero ? 0 : leds.load(std::memory_order_relaxed);
        // The homing bit in EVERY packet, during homing, after it and in the last zero packet:
        // "The homing mode bit must be set in each input packet sent in order for the falcon to
        // stay homed" (libnifalcon include/falcon/core/FalconFirmware.h, "Homing Mode").
        cmd.homing = true;
        cmd.ledGreen = (l & 2u) != 0;
        cmd.ledBlue = (l & 4u) != 0;
        cmd.ledRed = (l & 8u) != 0;
        outBuffer = falcon::encodeCommand(cmd);
        libusb_fill_bulk_transfer(outTransfer, handle, kEndpointOut, outBuffer.data(),
                                  static_cast<int>(outBuffer.size()), &Impl::onOut, this,
                                  static_cast<unsigned>(timeouts.usb.count()));
        const int rc = libusb_submit_transfer(outTransfer);
        if (rc == 0) {
            outFlight = true;
            replySinceSend = false;
        } else if (rc == LIBUSB_ERROR_NO_DEVICE) {
            markDisconnected();
        } else {
            transferFailed(LIBUSB_TRANSFER_ERROR);
        }
    }

    void pump(std::chrono::microseconds wait) {
        timeval tv{};
        tv.tv_sec = static_cast<time_t>(wait.count() / 1000000);
        tv.tv_usec = static_cast<suseconds_t>(wait.count() % 1000000);
        const int rc = libusb_handle_events_timeout_completed(ctx, &tv, nullptr);
        if (rc == LIBUSB_ERROR_NO_DEVICE) {
            markDisconnected();
        }
    }

    void ioLoop() {
        submitIn();
        auto nextSend = Clock::now();
        auto lastSend = Clock::now() - 1s;
        const auto replyGrace = 5 * timeouts.period;
        while (ioState.load(std::memory_order_relaxed) == IoState::Running) {
            const auto now = Clock::now();
            if (stopRequested.load(std::memory_order_acquire)) {
                if (!outFlight && !zeroSent) {
                    submitOut(true); // close(): zero force is the last command
                    zeroSent = true;
                } else if (!outFlight && zeroSent) {
                    break;
                }
            } else if (!outFlight && now >= nextSend &&
                       (replySinceSend || now - lastSend >= replyGrace)) {
                submitOut(false);
                lastSend = now;
                nextSend = std::max(nextSend + timeouts.period, now);
            }
            const auto until =
                std::chrono::duration_cast<std::chrono::microseconds>(nextSend - Clock::now());
            pump(std::clamp(until, std::chrono::microseconds(100), timeouts.period));
        }
        // Drain: cancel what is in flight and wait (bounded) for libusb to hand it back.
        const auto deadline =
            Clock::now() + std::max<std::chrono::milliseconds>(timeouts.usb, 200ms);
        bool cancelled = false;
        while ((inFlight || outFlight) && Clock::now() < deadline) {
            if (!cancelled) {
                if (inFlight) {
                    libusb_cancel_transfer(inTransfer);
                }
                if (outFlight && ioState.load() != IoState::Running) {
                    libusb_cancel_transfer(outTransfer);
                }
                cancelled = true;
            }
            pump(1ms);
        }
    }

    void startIo() {
        inTransfer = libusb_alloc_transfer(0);
        outTransfer = libusb_alloc_transfer(0);
        stopRequested = false;
        zeroSent = false;
        havePose = false;
        inFlight = outFlight = replySinceSend = false;
        consecutiveErrors = 0;
        ioState = IoState::Running;
        ioThread = std::thread([this] { ioLoop(); });
    }

    void stopIo() {
        if (ioThread.joinable()) {
            stopRequested.store(true, std::memory_order_release);
            ioThread.join();
        }
        // A transfer libusb still holds cannot be freed safely; leak it rather than crash.
        if (inTransfer && !inFlight) {
            libusb_free_transfer(inTransfer);
        }
        if (outTransfer && !outFlight) {
            libusb_free_transfer(outTransfer);
        }
        inTransfer = nullptr;
        outTransfer = nullptr;
    }

    void release() {
        stopIo();
        if (handle) {
            libusb_release_interface(handle, kInterface);
            libusb_close(handle);
            handle = nullptr;
        }
        if (ctx) {
            libusb_exit(ctx);
            ctx = nullptr;
        }
        open = false;
    }

    bool home() {
        homing = true;
        leds = 8; // red while homing
        const auto deadline = Clock::now() + timeouts.homing;
        bool prompted = false;
        const auto promptAt = Clock::now() + 500ms;
        while (Clock::now() < deadline) {
            Sample s{};
            if (ioState.load() != IoState::Running) {
                homing = false;
                return fail("device '" + name + "': the Falcon went away during homing");
            }
            if (samples.read(s) && s.homedMask == 0x7) {
                homing = false;
                leds = 2; // green: ready
                return true;
            }
            if (!prompted && Clock::now() > promptAt) {
                std::fprintf(stderr,
                             "hapto: Falcon '%s': pull the grip all the way out, then push it "
                             "all the way in, to home it\n",
                             name.c_str());
                prompted = true;
            }
            std::this_thread::sleep_for(2ms);
        }
        homing = false;
        Sample s{};
        const bool any = samples.read(s);
        return fail("device '" + name + "': homing timed out after " +
                    std::to_string(timeouts.homing.count() / 1000.0).substr(0, 4) +
                    " s (homed flags " + (any ? std::to_string(s.homedMask) : "none") +
                    " of 7): pull the grip all the way out and push it back in while hapto "
                    "starts");
    }

    DeviceStatus openDevice() {
        error.clear();
        if (const int rc = libusb_init(&ctx); rc != 0) {
            ctx = nullptr;
            fail("libusb could not be initialised: " + usbError(rc));
            return DeviceStatus::Error;
        }
        if (!findAndOpen()) {
            release();
            return DeviceStatus::Disconnected;
        }
        libusb_set_auto_detach_kernel_driver(handle, 1);
        if (const int rc = libusb_claim_interface(handle, kInterface); rc != 0) {
            fail("cannot claim the Falcon's USB interface: " + usbError(rc) +
                 (rc == LIBUSB_ERROR_BUSY ? " (another program is using it; close it)" : ""));
            release();
            return DeviceStatus::Error;
        }
        if (!(ftdi(kReqReset, kResetSio) && normalMode())) {
            release();
            return DeviceStatus::Error;
        }
        firmwareWasLoaded = firmwareAnswers();
        if (!firmwareWasLoaded) {
            if (lastUsbError == LIBUSB_ERROR_NO_DEVICE) {
                fail("the Falcon went away during set-up");
                release();
                return DeviceStatus::Disconnected;
            }
            if (!uploadFirmware()) {
                release();
                return DeviceStatus::Error;
            }
            if (!firmwareAnswers()) {
                fail("the firmware from " + config.firmware.string() +
                     " was uploaded but the Falcon does not answer: is it a Falcon firmware "
                     "image? Power-cycle the Falcon and try again");
                release();
                return DeviceStatus::Error;
            }
        }
        parser.reset();
        open = true;
        // Set before the I/O thread starts, so no force goes out before the homed flags arrive.
        homing = config.home;
        leds = config.home ? 8 : 2; // red while homing, green when ready
        startIo();
        if (config.home && !home()) {
            release();
            return DeviceStatus::Error;
        }
        return DeviceStatus::Ok;
    }
};

FalconDevice::FalconDevice(std::string name, const FalconConfig& config, double maxForceN)
    : mImpl(std::make_unique<Impl>()) {
    mImpl->name = std::move(name);
    mImpl->config = config;
    mImpl->maxForceN = maxForceN > 0.0 ? maxForceN : kDefaultMaxForceN;
    const double timeoutMs = std::isfinite(config.commandTimeoutMs) && config.commandTimeoutMs > 0.0
                                 ? std::min(config.commandTimeoutMs, kMaxCommandTimeoutMs)
                                 : defaultCommandTimeoutMs(1000.0);
    mImpl->commandTimeoutNs = static_cast<std::int64_t>(std::llround(timeoutMs * 1.0e6));
    mImpl->config.motorWordLimit = std::clamp(config.motorWordLimit, 1, falcon::kMaxMotorWordLimit);
}

FalconDevice::~FalconDevice() {
    close();
}

std::string_view FalconDevice::name() const {
    return mImpl->name;
}

DeviceCapabilities FalconDevice::capabilities() const {
    DeviceCapabilities c;
    c.model = "Novint Falcon";
    // The box the kinematics can reach everywhere (mechanism z 0.075..0.155 m, +-5 cm across),
    // relative to kWorkspaceOriginZ. NOTE: that origin (0.150 m, from the protocol notes) sits
    // near the top of this range; the reachable centre is nearer 0.115 m. To be checked on
    // hardware.
    c.workspace = Aabb{Vec3(-0.05, -0.05, 0.075 - falcon::kWorkspaceOriginZ),
                       Vec3(0.05, 0.05, 0.155 - falcon::kWorkspaceOriginZ)};
    c.maxForceN = mImpl->maxForceN;
    c.maxStiffness = 2000.0;
    c.nominalRateHz = 1.0e6 / static_cast<double>(mImpl->timeouts.period.count());
    c.buttonCount = 4;
    return c;
}

DeviceStatus FalconDevice::open() {
    if (mImpl->open) {
        return DeviceStatus::Ok;
    }
    return mImpl->openDevice();
}

void FalconDevice::close() {
    if (mImpl->ctx) {
        mImpl->release();
    }
}

DeviceStatus FalconDevice::read(DeviceState& state) noexcept {
    Impl& m = *mImpl;
    if (!m.open.load(std::memory_order_acquire)) {
        return DeviceStatus::NotOpen;
    }
    const IoState io = m.ioState.load(std::memory_order_acquire);
    Sample s{};
    const bool have = m.samples.read(s);
    if (have) {
        state.position = s.positionM;
        state.hasVelocity = false;
        state.buttons = s.buttons;
        state.sequence = s.sequence;
    }
    if (io == IoState::Disconnected) {
        return DeviceStatus::Disconnected;
    }
    if (io == IoState::Error) {
        return DeviceStatus::Error;
    }
    const std::int64_t staleNs =
        std::chrono::duration_cast<std::chrono::nanoseconds>(m.timeouts.stale).count();
    if (!have || nowNs() - s.timeNs > staleNs) {
        return m.badSinceValid.load(std::memory_order_relaxed) ? DeviceStatus::BadData
                                                               : DeviceStatus::Stalled;
    }
    return DeviceStatus::Ok;
}

DeviceStatus FalconDevice::write(const Vec3& forceN) noexcept {
    Impl& m = *mImpl;
    if (!m.open.load(std::memory_order_acquire)) {
        return DeviceStatus::NotOpen;
    }
    Vec3 f = forceN;
    if (!finite(f)) {
        f = Vec3(0.0);
    }
    const double len = glm::length(f);
    if (len > m.maxForceN) {
        f *= m.maxForceN / len;
    }
    m.commands.publish(Command{f, m.commandClock()});
    switch (m.ioState.load(std::memory_order_acquire)) {
    case IoState::Running:
        return DeviceStatus::Ok;
    case IoState::Disconnected:
        return DeviceStatus::Disconnected;
    case IoState::Error:
        break;
    }
    return DeviceStatus::Error;
}

std::string FalconDevice::errorMessage() const {
    const Impl& m = *mImpl;
    if (!m.error.empty()) {
        return m.error;
    }
    switch (m.ioState.load()) {
    case IoState::Disconnected:
        return "device '" + m.name + "': the Falcon was unplugged or powered off";
    case IoState::Error:
        return "device '" + m.name + "': USB I/O failed repeatedly (" +
               usbError(m.lastUsbError.load()) + "); re-plug the Falcon";
    case IoState::Running:
        break;
    }
    return {};
}

void FalconDevice::setLeds(bool green, bool blue, bool red) {
    mImpl->leds = static_cast<std::uint8_t>((green ? 2 : 0) | (blue ? 4 : 0) | (red ? 8 : 0));
}

void FalconDevice::setTimeouts(const FalconTimeouts& timeouts) {
    mImpl->timeouts = timeouts;
}

void FalconDevice::setCommandClock(std::int64_t (*nowNs)()) {
    mImpl->commandClock = nowNs ? nowNs : &hapto::nowNs;
}

bool FalconDevice::firmwareWasLoaded() const {
    return mImpl->firmwareWasLoaded;
}

FalconIoStats FalconDevice::ioStats() const {
    const Counters& c = mImpl->counters;
    FalconIoStats s;
    s.commandsSent = c.commandsSent.load();
    s.framesDecoded = c.framesDecoded.load();
    s.samplesPublished = c.samplesPublished.load();
    s.badFrames = c.badFrames.load();
    s.garbageBytes = c.garbageBytes.load();
    s.shortTransfers = c.shortTransfers.load();
    s.kinematicsFailures = c.kinematicsFailures.load();
    s.transferErrors = c.transferErrors.load();
    return s;
}

} // namespace hapto
