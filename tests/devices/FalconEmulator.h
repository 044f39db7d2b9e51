#pragma once
/// An emulated Novint Falcon for tests: a umockdev test bed holding a 0403:cb48 USB device and
/// a fake FTDI bridge + Falcon firmware that answers libusb's URBs.
//
// Design note. umockdev's preload library (the test must run under `umockdev-wrapper`) turns
// the process's view of /sys and /dev/bus/usb into a test bed; every usbdevfs ioctl libusb makes
// on the emulated node is handed to our handler on umockdev's worker thread. The handler keeps
// a small model: the FTDI line settings (baud divisor, DTR), a bootloader that does the
// firmware handshake and echoes the upload, and, once firmware runs, a Falcon that answers
// each 16-byte command frame with one reading frame. The firmware model follows the public
// reference, not hapto's driver, and builds and parses its frames itself (it does not use
// FalconPacket's codec): a reply's byte 13 is 0x41 + buttons (bits 0-3) + homed flags << 4
// (bits 4-6), so a homed Falcon answers with byte 13 above 'P' (libnifalcon
// src/firmware/FalconFirmwareNovintSDK.cpp, formatOutput; include/falcon/firmware/
// FalconFirmwareNovintSDK.h, "Buttons and Homing Control Report"); byte 14 is 'A' (that header's
// sample reply "<HNGPOKOPFPOPAA>"). Homed flags are reported only while the command asks for
// homing mode ("(If homing mode on) ... Encoder Homed", same header), and a command without the
// homing bit loses the homed state ("The homing mode bit must be set in each input packet sent
// in order for the falcon to stay homed", include/falcon/core/FalconFirmware.h). URBs complete when
// reaped: control and OUT URBs at once, IN URBs when the model has bytes to send (EAGAIN until
// then). All model state is behind one mutex; the handler never blocks. Fault injection: fragmented
// replies with garbage and short transfers, garbage-only replies, silence, and unplugging.

#include "hapto/devices/FalconPacket.h"

#include <array>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

typedef struct _UMockdevTestbed UMockdevTestbed;
typedef struct _UMockdevIoctlBase UMockdevIoctlBase;
typedef struct _UMockdevIoctlClient UMockdevIoctlClient;
typedef struct _UMockdevIoctlData UMockdevIoctlData;

namespace hapto::test {

/// One FTDI vendor control request the emulator received.
struct FtdiRequest {
    std::uint8_t request = 0; ///< bRequest (0 reset, 1 modem, 2 flow, 3 baud, 4 data, 9 latency).
    std::uint16_t value = 0;  ///< wValue.
    std::uint16_t index = 0;  ///< wIndex.
    /// Field-wise equality.
    bool operator==(const FtdiRequest&) const = default;
};

/// How the emulated firmware answers command frames.
enum class ReplyMode {
    Normal,     ///< One clean frame per IN transfer.
    Fragmented, ///< Each frame split over several transfers, with garbage and short transfers.
    Garbage,    ///< Only invalid frames.
    Silent,     ///< No answers at all.
};

/// Start-up state of the emulated Falcon.
struct FalconEmulatorOptions {
    bool firmwareLoaded = true;       ///< False: only the bootloader runs until an upload.
    std::string serial = "FTHAPTO1";  ///< USB serial number.
    int homeAfterPackets = 5;         ///< Homing packets until all homed; -1 = never.
    bool handshakeLeadingZero = true; ///< Prefix the bootloader's handshake reply with 0x00.
    long corruptEchoAt = -1;          ///< Upload byte whose echo is wrong; -1 = none.
};

/// The emulated Falcon. Create it before the code under test calls libusb_init; destroy it
/// after libusb_exit. Every public method is thread-safe.
class FalconEmulator {
public:
    /// Sets up the test bed, the device node /dev/bus/usb/001/002 and the ioctl handler.
    explicit FalconEmulator(FalconEmulatorOptions options = {});
    ~FalconEmulator();
    FalconEmulator(const FalconEmulator&) = delete;
    FalconEmulator& operator=(const FalconEmulator&) = delete;

    /// True when running under umockdev-wrapper (umockdev's preload library is active).
    static bool inMockEnvironment();

    /// Encoder counts reported from now on.
    void setEncoders(const std::array<std::int16_t, 3>& counts);
    /// Grip buttons reported from now on.
    void setButtons(std::uint8_t buttons);
    /// How replies are sent from now on.
    void setReplyMode(ReplyMode mode);
    /// Unplugs the device: in-flight URBs fail with ESHUTDOWN, later calls with ENODEV, and
    /// udev sees a "remove" event.
    void unplug();
    /// Plugs it back in after unplug(): firmware state back to the options' (a power cycle),
    /// and udev sees an "add" event.
    void replug();

    /// FTDI vendor requests received so far, in order.
    std::vector<FtdiRequest> ftdiRequests() const;
    /// Valid command frames received while firmware ran, in order.
    std::vector<falcon::FalconCommand> commands() const;
    /// Frames between '<' and '>' that were not valid commands (a payload byte outside 'A'..'P').
    std::size_t badCommandFrames() const;
    /// The homed flags (bit i: motor i) the firmware holds now.
    std::uint8_t homedMask() const;
    /// The last reply frame the firmware built (all zero before the first).
    falcon::Packet lastReply() const;
    /// Number of command frames received.
    std::size_t commandCount() const;
    /// The bytes uploaded to the bootloader.
    std::vector<std::uint8_t> uploadedImage() const;
    /// True once firmware runs (loaded at start or uploaded).
    bool firmwareRunning() const;
    /// ioctl requests the handler did not know (a newer libusb may send some).
    std::vector<unsigned long> unknownIoctls() const;

private:
    struct PendingUrb {
        UMockdevIoctlData* data = nullptr; ///< The URB as resolved at submit (referenced).
        int status = 0;                    ///< Completion status (negative errno).
        int actualLength = 0;              ///< Completion length.
    };
    struct InChunk {
        std::vector<std::uint8_t> payload; ///< Bytes after the 2 status bytes.
        bool truncated = false;            ///< Send only 1 status byte (a malformed transfer).
    };

    static int onIoctl(UMockdevIoctlBase* handler, UMockdevIoctlClient* client, void* self);
    bool handleIoctl(UMockdevIoctlClient* client);
    void handleControl(PendingUrb& urb, std::uint8_t* buffer, int length);
    void receiveBytes(const std::uint8_t* bytes, std::size_t n);
    void receiveCommand(const falcon::FalconCommand& cmd);
    void queueReply(std::vector<std::uint8_t> bytes);

    FalconEmulatorOptions mOptions;
    UMockdevTestbed* mTestbed = nullptr;
    UMockdevIoctlBase* mHandler = nullptr;
    std::string mSysPath;

    mutable std::mutex mMutex;
    std::deque<PendingUrb> mDone;   ///< Completed, waiting to be reaped.
    std::deque<PendingUrb> mInUrbs; ///< IN URBs waiting for data.
    std::deque<InChunk> mInData;    ///< What the next IN transfers carry.
    std::vector<FtdiRequest> mFtdi;
    std::vector<falcon::FalconCommand> mCommands;
    std::vector<unsigned long> mUnknown;
    std::vector<std::uint8_t> mImage;
    std::vector<std::uint8_t> mBootInput;
    std::vector<std::uint8_t> mCommandBytes; ///< Firmware input not yet framed.
    std::size_t mBadCommandFrames = 0;
    falcon::Packet mLastReply{};
    std::array<std::int16_t, 3> mEncoders{};
    std::uint8_t mButtons = 0;
    std::uint8_t mHomedMask = 0;
    int mHomingPackets = 0;
    ReplyMode mMode = ReplyMode::Normal;
    std::uint16_t mBaud = 0;
    bool mDtr = false;
    enum class Boot { Idle, Handshaken, Uploading } mBoot = Boot::Idle;
    bool mFirmware = false;
    bool mUnplugged = false;
    std::uint64_t mReplies = 0;
};

} // namespace hapto::test
