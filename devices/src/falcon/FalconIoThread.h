#pragma once
/// The Falcon's I/O thread: all USB traffic once the Falcon is set up. One bulk IN transfer is
/// always in flight and one OUT command goes per period (~1 kHz); frames are reassembled,
/// decoded and turned into positions (forward kinematics), and the servo's newest force into
/// motor words (the Jacobian at the newest pose).
//
// Design note. The servo thread never touches libusb: it copies the newest sample out of, and
// the newest force into, two lock-free seqlock mailboxes (newestSample, command). A slow bus
// can make samples stale, never block the servo. Safety: a command older than the command
// timeout (a stalled servo), no pose yet, or homing in progress sends zero motor words; stop()
// sends a zero-force packet last. Every packet carries the homing bit (libnifalcon
// include/falcon/core/FalconFirmware.h, "Homing Mode").

#include "FalconTransport.h"

#include "hapto/core/Geometry.h"
#include "hapto/core/Mailbox.h"
#include "hapto/devices/FalconDevice.h"
#include "hapto/devices/FalconKinematics.h"
#include "hapto/devices/FalconPacket.h"

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <type_traits>

namespace hapto::falcon {

/// The newest decoded sample, written by the I/O thread.
struct IoSample {
    Vec3 positionM{0.0};        ///< Device frame, workspace-centred (m).
    std::int16_t encoder[3]{};  ///< Raw encoder counts.
    std::uint8_t buttons = 0;   ///< Grip buttons.
    std::uint8_t homedMask = 0; ///< Homed flags.
    std::uint64_t sequence = 0; ///< 1, 2, ... per published sample.
    std::int64_t timeNs = 0;    ///< Monotonic time of arrival (ns).
};
static_assert(std::is_trivially_copyable_v<IoSample> && sizeof(IoSample) == 48,
              "IoSample is six plain words");

/// The newest force, written by the servo (or control) thread.
struct IoForce {
    Vec3 forceN{0.0};        ///< Device frame (N).
    std::int64_t timeNs = 0; ///< Command-clock time of the write (ns).
};
static_assert(std::is_trivially_copyable_v<IoForce>);

/// How the I/O thread is doing.
enum class IoState : std::uint8_t { Running, Disconnected, Error };

/// The monotonic clock (core), signed so that differences of stamps can be negative. [any thread]
std::int64_t ioNowNs() noexcept;

/// What the I/O thread runs with; fixed while it runs.
struct IoSettings {
    FalconTimeouts timeouts;                     ///< Period, USB timeout.
    std::int64_t commandTimeoutNs = 2'000'000;   ///< A command older than this is not applied.
    std::int64_t (*commandClock)() = &ioNowNs;   ///< Stamps commands and judges their age (ns).
    int motorWordLimit = kDefaultMotorWordLimit; ///< Largest |motor word| sent.
};

/// One Falcon's I/O thread and what it shares with the servo and control threads.
class FalconIoThread {
public:
    FalconIoThread() = default;
    /// Stops the thread if it runs. [control]
    ~FalconIoThread() { stop(); }
    FalconIoThread(const FalconIoThread&) = delete;
    FalconIoThread& operator=(const FalconIoThread&) = delete;

    /// Sets what the next start() runs with; only while the thread is stopped and nobody calls
    /// command() (the device is not open). [control]
    void configure(const IoSettings& settings) { mSettings = settings; }
    /// Starts the thread on `usb` (open, in normal mode), forgetting any pose. [control]
    void start(FalconTransport& usb);
    /// Sends a zero-force packet, cancels what is in flight (bounded wait), joins the thread
    /// and frees the transfers. Safe when not running. [control]
    void stop();

    /// Copies the newest sample; false when none yet (or every retry raced a write). [servo]
    bool newestSample(IoSample& out) const noexcept { return mSamples.read(out); }
    /// Publishes the newest force (N, device frame), stamped on the command clock. [servo]
    void command(const Vec3& forceN) noexcept {
        mCommands.publish(IoForce{forceN, mSettings.commandClock()});
    }
    /// Running, Disconnected or Error. [any thread]
    IoState state() const noexcept { return mState.load(std::memory_order_acquire); }
    /// True when only undecodable data arrived since the last valid sample. [any thread]
    bool badSinceValid() const noexcept { return mBadSinceValid.load(std::memory_order_relaxed); }
    /// While true the motor words stay zero (waiting for the homed flags). [any thread]
    void setHoming(bool homing) noexcept { mHoming.store(homing, std::memory_order_relaxed); }
    /// LEDs sent with every packet: bit1 green, bit2 blue, bit3 red (packet layout). [any thread]
    void setLeds(std::uint8_t leds) noexcept { mLeds.store(leds, std::memory_order_relaxed); }
    /// The frame parser starts afresh (before start()). [control]
    void resetParser() { mParser.reset(); }
    /// I/O counters so far. [any thread]
    FalconIoStats stats() const;

private:
    struct Counters {
        std::atomic<std::uint64_t> commandsSent{0}, framesDecoded{0}, samplesPublished{0},
            badFrames{0}, garbageBytes{0}, shortTransfers{0}, kinematicsFailures{0},
            transferErrors{0};
    };

    static void LIBUSB_CALL onIn(libusb_transfer* t);
    static void LIBUSB_CALL onOut(libusb_transfer* t);
    void markDisconnected();
    void transferFailed(libusb_transfer_status status);
    void onFrame(const Packet& frame);
    bool syncParserCounters();
    void inDone(libusb_transfer* t);
    void outDone(libusb_transfer* t);
    void submitIn();
    MotorWords motorWords(bool zero);
    void submitOut(bool zero);
    void pump(std::chrono::microseconds wait);
    void loop();

    // Fixed while the thread runs.
    FalconTransport* mUsb = nullptr;
    IoSettings mSettings;
    FalconKinematics mKinematics;
    libusb_transfer* mInTransfer = nullptr;
    libusb_transfer* mOutTransfer = nullptr;
    std::array<unsigned char, kTransferSize> mInBuffer{};
    std::array<unsigned char, kPacketSize> mOutBuffer{};
    std::thread mThread;

    // Shared between threads.
    std::atomic<bool> mStopRequested{false};
    std::atomic<bool> mHoming{false};
    std::atomic<std::uint8_t> mLeds{0};
    std::atomic<IoState> mState{IoState::Running};
    std::atomic<bool> mBadSinceValid{false};
    Mailbox<IoSample> mSamples;
    Mailbox<IoForce> mCommands;
    Counters mCounters;

    // I/O thread only.
    FalconStreamParser mParser;
    bool mInFlight = false;
    bool mOutFlight = false;
    bool mReplySinceSend = false;
    bool mZeroSent = false;
    int mConsecutiveErrors = 0;
    std::uint64_t mSequence = 0;
    Vec3 mLastMechPosition = FalconKinematics::defaultStart();
    Angles mLastAngles{};
    bool mHavePose = false;
};

} // namespace hapto::falcon
