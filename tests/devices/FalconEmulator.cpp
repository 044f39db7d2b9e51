#include "FalconEmulator.h"

#include <umockdev.h>

#include <linux/usbdevice_fs.h>
#include <sys/ioctl.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace hapto::test {
namespace {

constexpr std::uint8_t kStatus0 = 0x31; // FTDI modem status bytes, as a real FT232 sends them
constexpr std::uint8_t kStatus1 = 0x60;
constexpr std::uint16_t kBaudBootloader = 0x4138;
constexpr std::uint16_t kBaudUpload = 0x0015;
constexpr std::uint16_t kBaudNormal = 0x0002;

// Device (18), configuration (9), interface (9, vendor class), bulk IN 0x81 and OUT 0x02 (7 each).
constexpr const char* kDeviceText =
    "P: /devices/pci0000:00/0000:00:14.0/usb1/1-2\n"
    "N: bus/usb/001/002\n"
    "E: SUBSYSTEM=usb\n"
    "E: DEVTYPE=usb_device\n"
    "E: DRIVER=usb\n"
    "E: BUSNUM=001\n"
    "E: DEVNUM=002\n"
    "E: DEVNAME=/dev/bus/usb/001/002\n"
    "E: PRODUCT=403/cb48/600\n"
    "A: idVendor=0403\\n\n"
    "A: idProduct=cb48\\n\n"
    "A: busnum=1\\n\n"
    "A: devnum=2\\n\n"
    "A: bConfigurationValue=1\\n\n"
    "A: speed=12\\n\n"
    "A: manufacturer=Novint\\n\n"
    "A: product=FALCON HAPTIC\\n\n"
    "H: descriptors="
    "1201000200000040030448cb000601020301" // device: 0403:cb48, bcdDevice 6.00, strings 1-3
    "090220000101008032"                   // configuration 1, 32 bytes in all
    "0904000002ffffff02"                   // interface 0, two endpoints, vendor class
    "07058102400000"                       // bulk IN 0x81, 64 bytes
    "07050202400000\n";                    // bulk OUT 0x02, 64 bytes

std::vector<std::uint8_t> stringDescriptor(std::uint16_t value, const std::string& serial) {
    const std::uint8_t index = value & 0xFF;
    std::string text;
    switch (index) {
    case 0:
        return {4, 3, 0x09, 0x04}; // US English
    case 1:
        text = "Novint";
        break;
    case 2:
        text = "FALCON HAPTIC";
        break;
    case 3:
        text = serial;
        break;
    default:
        return {};
    }
    std::vector<std::uint8_t> d{static_cast<std::uint8_t>(2 + 2 * text.size()), 3};
    for (char c : text) {
        d.push_back(static_cast<std::uint8_t>(c));
        d.push_back(0);
    }
    return d;
}

/// A reply frame as the firmware sends it: '<', three words as nibbles + 0x41 least significant
/// first, byte 13 = 0x41 + buttons + (homed << 4), byte 14 'A', '>'.
falcon::Packet replyFrame(const std::array<std::int16_t, 3>& encoders, std::uint8_t buttons,
                          std::uint8_t homedMask) {
    falcon::Packet p{};
    p[0] = '<';
    for (std::size_t w = 0; w < 3; ++w) {
        const auto u = static_cast<std::uint16_t>(encoders[w]);
        for (std::size_t n = 0; n < 4; ++n) {
            p[1 + 4 * w + n] = static_cast<std::uint8_t>(0x41 + ((u >> (4 * n)) & 0xF));
        }
    }
    p[13] = static_cast<std::uint8_t>(0x41 + (buttons & 0xF) + ((homedMask & 0x7) << 4));
    p[14] = 0x41;
    p[15] = '>';
    return p;
}

/// A host command frame's fields, or nothing when a payload byte is outside 'A'..'P'.
std::optional<falcon::FalconCommand> parseCommandFrame(const std::uint8_t* f) {
    for (std::size_t i = 1; i < 15; ++i) {
        if (f[i] < 0x41 || f[i] > 0x50) {
            return std::nullopt;
        }
    }
    falcon::FalconCommand c;
    for (std::size_t w = 0; w < 3; ++w) {
        std::uint16_t u = 0;
        for (std::size_t n = 0; n < 4; ++n) {
            u = static_cast<std::uint16_t>(u | (f[1 + 4 * w + n] - 0x41) << (4 * n));
        }
        c.motor[w] = static_cast<std::int16_t>(u);
    }
    const unsigned flags = f[13] - 0x41u;
    c.homing = (flags & 1u) != 0;
    c.ledGreen = (flags & 2u) != 0;
    c.ledBlue = (flags & 4u) != 0;
    c.ledRed = (flags & 8u) != 0;
    return c;
}

} // namespace

bool FalconEmulator::inMockEnvironment() {
    // umockdev_in_mock_environment() only turns true once a test bed exists (it looks at
    // $UMOCKDEV_DIR); before that, the wrapper's preload library is the sign.
    const char* preload = std::getenv("LD_PRELOAD");
    return umockdev_in_mock_environment() ||
           (preload && std::strstr(preload, "libumockdev-preload") != nullptr);
}

FalconEmulator::FalconEmulator(FalconEmulatorOptions options) : mOptions(std::move(options)) {
    mFirmware = mOptions.firmwareLoaded;
    mTestbed = umockdev_testbed_new();
    mHandler = umockdev_ioctl_base_new();
    g_signal_connect(mHandler, "handle-ioctl", G_CALLBACK(&FalconEmulator::onIoctl), this);
    GError* error = nullptr;
    // Attach the handler before the node exists, so libusb never sees an unhandled device.
    if (!umockdev_testbed_attach_ioctl(mTestbed, "/dev/bus/usb/001/002", mHandler, &error)) {
        const std::string what = error ? error->message : "unknown error";
        g_clear_error(&error);
        throw std::runtime_error("umockdev attach_ioctl failed: " + what);
    }
    if (!umockdev_testbed_add_from_string(mTestbed, kDeviceText, &error)) {
        const std::string what = error ? error->message : "unknown error";
        g_clear_error(&error);
        throw std::runtime_error("umockdev add_from_string failed: " + what);
    }
    mSysPath = "/sys/devices/pci0000:00/0000:00:14.0/usb1/1-2";
}

FalconEmulator::~FalconEmulator() {
    {
        std::lock_guard lock(mMutex);
        for (auto* q : {&mDone, &mInUrbs}) {
            for (auto& u : *q) {
                umockdev_ioctl_data_unref(u.data);
            }
            q->clear();
        }
    }
    g_object_unref(mHandler);
    g_object_unref(mTestbed);
}

void FalconEmulator::setEncoders(const std::array<std::int16_t, 3>& counts) {
    std::lock_guard lock(mMutex);
    mEncoders = counts;
}

void FalconEmulator::setButtons(std::uint8_t buttons) {
    std::lock_guard lock(mMutex);
    mButtons = buttons;
}

void FalconEmulator::setReplyMode(ReplyMode mode) {
    std::lock_guard lock(mMutex);
    mMode = mode;
}

void FalconEmulator::unplug() {
    {
        std::lock_guard lock(mMutex);
        mUnplugged = true;
        mInData.clear();
    }
    umockdev_testbed_uevent(mTestbed, mSysPath.c_str(), "remove");
}

void FalconEmulator::replug() {
    {
        std::lock_guard lock(mMutex);
        mUnplugged = false;
        mInData.clear();
        mBoot = Boot::Idle;
        mDtr = false;
        mFirmware = mOptions.firmwareLoaded;
        mCommandBytes.clear();
        mHomedMask = 0; // a power cycle loses homing
        mHomingPackets = 0;
    }
    umockdev_testbed_uevent(mTestbed, mSysPath.c_str(), "add");
}

std::vector<FtdiRequest> FalconEmulator::ftdiRequests() const {
    std::lock_guard lock(mMutex);
    return mFtdi;
}

std::vector<falcon::FalconCommand> FalconEmulator::commands() const {
    std::lock_guard lock(mMutex);
    return mCommands;
}

std::size_t FalconEmulator::badCommandFrames() const {
    std::lock_guard lock(mMutex);
    return mBadCommandFrames;
}

std::uint8_t FalconEmulator::homedMask() const {
    std::lock_guard lock(mMutex);
    return mHomedMask;
}

falcon::Packet FalconEmulator::lastReply() const {
    std::lock_guard lock(mMutex);
    return mLastReply;
}

std::size_t FalconEmulator::commandCount() const {
    std::lock_guard lock(mMutex);
    return mCommands.size();
}

std::vector<std::uint8_t> FalconEmulator::uploadedImage() const {
    std::lock_guard lock(mMutex);
    return mImage;
}

bool FalconEmulator::firmwareRunning() const {
    std::lock_guard lock(mMutex);
    return mFirmware;
}

std::vector<unsigned long> FalconEmulator::unknownIoctls() const {
    std::lock_guard lock(mMutex);
    return mUnknown;
}

int FalconEmulator::onIoctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, void* self) {
    return static_cast<FalconEmulator*>(self)->handleIoctl(client) ? TRUE : FALSE;
}

// ---- the model (called with mMutex held) -------------------------------------------------------

void FalconEmulator::queueReply(std::vector<std::uint8_t> bytes) {
    mInData.push_back({std::move(bytes), false});
}

void FalconEmulator::receiveCommand(const falcon::FalconCommand& cmd) {
    mCommands.push_back(cmd);
    if (cmd.homing) {
        ++mHomingPackets;
        if (mOptions.homeAfterPackets >= 0 && mHomingPackets >= mOptions.homeAfterPackets) {
            mHomedMask = 0x7;
        }
    } else {
        mHomingPackets = 0; // homing mode off: the motors do not stay homed
        mHomedMask = 0;
    }
    const falcon::Packet reply = replyFrame(mEncoders, mButtons, cmd.homing ? mHomedMask : 0);
    mLastReply = reply;
    ++mReplies;
    switch (mMode) {
    case ReplyMode::Normal:
        queueReply({reply.begin(), reply.end()});
        break;
    case ReplyMode::Fragmented: {
        // Garbage, a false start, a status-only transfer, a malformed short transfer, then the
        // frame in three pieces, the last one merged with more garbage.
        queueReply({0xFF, 'Z', '<', 'A', 0x00});
        queueReply({});
        mInData.push_back({{}, true});
        queueReply({reply.begin(), reply.begin() + 5});
        queueReply({reply.begin() + 5, reply.begin() + 11});
        std::vector<std::uint8_t> tail(reply.begin() + 11, reply.end());
        tail.push_back('?');
        queueReply(std::move(tail));
        break;
    }
    case ReplyMode::Garbage: {
        falcon::Packet bad = reply;
        bad[7] = 'Z'; // not a nibble byte
        queueReply({bad.begin(), bad.end()});
        break;
    }
    case ReplyMode::Silent:
        break;
    }
}

void FalconEmulator::receiveBytes(const std::uint8_t* bytes, std::size_t n) {
    if (mFirmware) {
        // Frame the input like the public reference does: from a '<', 16 bytes ending in '>'.
        mCommandBytes.insert(mCommandBytes.end(), bytes, bytes + n);
        std::size_t at = 0;
        while (at < mCommandBytes.size()) {
            if (mCommandBytes[at] != '<') {
                ++at;
                continue;
            }
            if (mCommandBytes.size() - at < falcon::kPacketSize) {
                break;
            }
            const std::uint8_t* f = mCommandBytes.data() + at;
            if (f[15] != '>') {
                ++mBadCommandFrames;
                ++at;
                continue;
            }
            if (const auto cmd = parseCommandFrame(f)) {
                receiveCommand(*cmd);
            } else {
                ++mBadCommandFrames;
            }
            at += falcon::kPacketSize;
        }
        mCommandBytes.erase(mCommandBytes.begin(), mCommandBytes.begin() + static_cast<long>(at));
        return;
    }
    switch (mBoot) {
    case Boot::Idle:
        if (mBaud != kBaudBootloader || !mDtr) {
            return; // wrong line settings: the bootloader hears noise
        }
        mBootInput.insert(mBootInput.end(), bytes, bytes + n);
        if (mBootInput.size() >= 3 &&
            std::equal(mBootInput.end() - 3, mBootInput.end(),
                       std::array<std::uint8_t, 3>{0x0A, 0x43, 0x0D}.begin())) {
            std::vector<std::uint8_t> reply{0x0A, 0x44, 0x2C, 0x0D};
            if (mOptions.handshakeLeadingZero) {
                reply.insert(reply.begin(), 0x00);
            }
            queueReply(std::move(reply));
            mBoot = Boot::Handshaken;
            mBootInput.clear();
        }
        return;
    case Boot::Handshaken:
        if (mBaud == kBaudUpload && !mDtr && n >= 1 && bytes[0] == 0x41) {
            queueReply({0x41});
            mBoot = Boot::Uploading;
        }
        return;
    case Boot::Uploading: {
        std::vector<std::uint8_t> echo(bytes, bytes + n);
        const long at = mOptions.corruptEchoAt - static_cast<long>(mImage.size());
        if (at >= 0 && at < static_cast<long>(n)) {
            echo[static_cast<std::size_t>(at)] ^= 0x5A; // a bit error on the line
        }
        mImage.insert(mImage.end(), bytes, bytes + n);
        queueReply(std::move(echo));
        return;
    }
    }
}

void FalconEmulator::handleControl(PendingUrb& urb, std::uint8_t* buffer, int length) {
    if (length < 8) {
        urb.status = -EPIPE;
        return;
    }
    const std::uint8_t type = buffer[0];
    const std::uint8_t request = buffer[1];
    const auto value = static_cast<std::uint16_t>(buffer[2] | buffer[3] << 8);
    const auto index = static_cast<std::uint16_t>(buffer[4] | buffer[5] << 8);
    const auto wLength = static_cast<std::uint16_t>(buffer[6] | buffer[7] << 8);
    if (type == 0x40) {
        mFtdi.push_back({request, value, index});
        if (request == 3) {
            mBaud = value;
            if (value == kBaudNormal && mBoot == Boot::Uploading && !mImage.empty()) {
                mFirmware = true; // the bootloader jumps into the uploaded image
                mCommandBytes.clear();
            }
        } else if (request == 1 && (value & 0x0100)) {
            mDtr = (value & 0x0001) != 0;
        } else if (request == 0 && value == 1) {
            mInData.clear(); // purge RX (device to host)
        }
        urb.actualLength = 0;
        return;
    }
    if (type == 0x80 && request == 6 && (value >> 8) == 3) {
        const auto d = stringDescriptor(value, mOptions.serial);
        const int n = std::min<int>({static_cast<int>(d.size()), wLength, length - 8});
        if (d.empty()) {
            urb.status = -EPIPE;
            return;
        }
        std::memcpy(buffer + 8, d.data(), static_cast<std::size_t>(n));
        urb.actualLength = n;
        return;
    }
    urb.status = -EPIPE; // anything else: stall
}

bool FalconEmulator::handleIoctl(UMockdevIoctlClient* client) {
    const unsigned long request = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData* arg = umockdev_ioctl_client_get_arg(client);
    std::lock_guard lock(mMutex);

    switch (request) {
    case USBDEVFS_GET_CAPABILITIES: {
        UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(std::uint32_t), nullptr);
        const std::uint32_t caps = USBDEVFS_CAP_BULK_CONTINUATION |
                                   USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                                   USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
        std::memcpy(d->data, &caps, sizeof caps);
        umockdev_ioctl_data_unref(d);
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
    }
    case USBDEVFS_GETDRIVER:
    case USBDEVFS_IOCTL: // libusb's kernel-driver detach: no driver is bound
        umockdev_ioctl_client_complete(client, -1, ENODATA);
        return true;
    case USBDEVFS_DISCONNECT_CLAIM: // libusb falls back to detach + claim
        umockdev_ioctl_client_complete(client, -1, ENOTTY);
        return true;
    case USBDEVFS_CLAIMINTERFACE:
    case USBDEVFS_RELEASEINTERFACE:
    case USBDEVFS_CLEAR_HALT:
    case USBDEVFS_RESETEP:
        if (mUnplugged) {
            umockdev_ioctl_client_complete(client, -1, ENODEV);
        } else {
            umockdev_ioctl_client_complete(client, 0, 0);
        }
        return true;
    case USBDEVFS_SUBMITURB: {
        if (mUnplugged) {
            umockdev_ioctl_client_complete(client, -1, ENODEV);
            return true;
        }
        UMockdevIoctlData* urbData =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
        auto* urb = reinterpret_cast<usbdevfs_urb*>(urbData->data);
        UMockdevIoctlData* buf =
            umockdev_ioctl_data_resolve(urbData, offsetof(usbdevfs_urb, buffer),
                                        static_cast<gsize>(urb->buffer_length), nullptr);
        PendingUrb pending{urbData, 0, 0};
        if (urb->type == USBDEVFS_URB_TYPE_CONTROL) {
            handleControl(pending, buf->data, urb->buffer_length);
            mDone.push_back(pending);
        } else if (urb->type == USBDEVFS_URB_TYPE_BULK && urb->endpoint == 0x02) {
            receiveBytes(buf->data, static_cast<std::size_t>(urb->buffer_length));
            pending.actualLength = urb->buffer_length;
            mDone.push_back(pending);
        } else if (urb->type == USBDEVFS_URB_TYPE_BULK && urb->endpoint == 0x81) {
            mInUrbs.push_back(pending);
        } else {
            pending.status = -EPIPE;
            mDone.push_back(pending);
        }
        umockdev_ioctl_data_unref(buf);
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
    }
    case USBDEVFS_REAPURB:
    case USBDEVFS_REAPURBNDELAY: {
        PendingUrb done{};
        if (!mDone.empty()) {
            done = mDone.front();
            mDone.pop_front();
        } else if (!mInUrbs.empty() && mUnplugged) {
            done = mInUrbs.front();
            mInUrbs.pop_front();
            done.status = -ESHUTDOWN;
        } else if (!mInUrbs.empty() && !mInData.empty()) {
            done = mInUrbs.front();
            mInUrbs.pop_front();
            auto* urb = reinterpret_cast<usbdevfs_urb*>(done.data->data);
            auto* out = static_cast<std::uint8_t*>(urb->buffer);
            InChunk& chunk = mInData.front();
            const int room = urb->buffer_length - 2;
            const int n = std::min<int>(room, static_cast<int>(chunk.payload.size()));
            out[0] = kStatus0;
            out[1] = kStatus1;
            if (n > 0) { // an empty chunk (a short transfer) has no data pointer to copy from
                std::memcpy(out + 2, chunk.payload.data(), static_cast<std::size_t>(n));
            }
            done.actualLength = chunk.truncated ? 1 : 2 + n;
            if (static_cast<std::size_t>(n) < chunk.payload.size() && !chunk.truncated) {
                chunk.payload.erase(chunk.payload.begin(), chunk.payload.begin() + n);
            } else {
                mInData.pop_front();
            }
        } else {
            umockdev_ioctl_client_complete(client, -1, mUnplugged ? ENODEV : EAGAIN);
            return true;
        }
        auto* urb = reinterpret_cast<usbdevfs_urb*>(done.data->data);
        urb->status = done.status;
        urb->actual_length = done.actualLength;
        UMockdevIoctlData* ptr = umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr);
        umockdev_ioctl_data_set_ptr(ptr, 0, done.data);
        umockdev_ioctl_data_unref(ptr);
        umockdev_ioctl_data_unref(done.data);
        umockdev_ioctl_client_complete(client, 0, 0);
        return true;
    }
    case USBDEVFS_DISCARDURB: {
        const auto addr = reinterpret_cast<gulong>(*reinterpret_cast<void**>(arg->data));
        for (auto it = mInUrbs.begin(); it != mInUrbs.end(); ++it) {
            if (it->data->client_addr == addr) {
                PendingUrb u = *it;
                mInUrbs.erase(it);
                u.status = -ENOENT;
                u.actualLength = 0;
                mDone.push_back(u);
                umockdev_ioctl_client_complete(client, 0, 0);
                return true;
            }
        }
        umockdev_ioctl_client_complete(client, -1, EINVAL);
        return true;
    }
    default:
        mUnknown.push_back(request);
        umockdev_ioctl_client_complete(client, -1, ENOTTY);
        return true;
    }
}

} // namespace hapto::test
