#include "FalconIoThread.h"

#include "hapto/core/Clock.h"

#include <algorithm>
#include <span>

namespace hapto::falcon {
namespace {
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
} // namespace

std::int64_t ioNowNs() noexcept {
    return static_cast<std::int64_t>(monotonicNs());
}

FalconIoStats FalconIoThread::stats() const {
    const Counters& c = mCounters;
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

void LIBUSB_CALL FalconIoThread::onIn(libusb_transfer* t) {
    static_cast<FalconIoThread*>(t->user_data)->inDone(t);
}
void LIBUSB_CALL FalconIoThread::onOut(libusb_transfer* t) {
    static_cast<FalconIoThread*>(t->user_data)->outDone(t);
}

void FalconIoThread::markDisconnected() {
    mState.store(IoState::Disconnected, std::memory_order_release);
}

void FalconIoThread::transferFailed(libusb_transfer_status status) {
    if (status == LIBUSB_TRANSFER_NO_DEVICE) {
        markDisconnected();
        return;
    }
    mCounters.transferErrors.fetch_add(1, std::memory_order_relaxed);
    if (++mConsecutiveErrors > 100) {
        mState.store(IoState::Error, std::memory_order_release);
    }
}

void FalconIoThread::onFrame(const Packet& frame) {
    const auto reading = decode(frame);
    if (!reading) {
        mBadSinceValid.store(true, std::memory_order_relaxed);
        return;
    }
    mCounters.framesDecoded.fetch_add(1, std::memory_order_relaxed);
    mReplySinceSend = true;
    const Angles angles = FalconKinematics::encodersToAngles(reading->encoder);
    auto p = mKinematics.forward(angles,
                                 mHavePose ? mLastMechPosition : FalconKinematics::defaultStart());
    if (!p && mHavePose) {
        p = mKinematics.forward(angles); // a jump: retry from the workspace centre
    }
    if (!p) {
        mCounters.kinematicsFailures.fetch_add(1, std::memory_order_relaxed);
        mBadSinceValid.store(true, std::memory_order_relaxed);
        return;
    }
    mLastMechPosition = *p;
    mLastAngles = angles;
    mHavePose = true;
    IoSample s{};
    s.positionM = Vec3(p->x, p->y, p->z - kWorkspaceOriginZ);
    for (int i = 0; i < 3; ++i) {
        s.encoder[i] = reading->encoder[static_cast<std::size_t>(i)];
    }
    s.buttons = reading->buttons;
    s.homedMask = reading->homedMask;
    s.sequence = ++mSequence;
    s.timeNs = ioNowNs();
    mSamples.publish(s);
    mBadSinceValid.store(false, std::memory_order_relaxed);
    mCounters.samplesPublished.fetch_add(1, std::memory_order_relaxed);
}

/// Copies the parser's counters out; true when it saw new bad input.
bool FalconIoThread::syncParserCounters() {
    const auto& st = mParser.stats();
    const bool fresh =
        st.badFrames != mCounters.badFrames.load(std::memory_order_relaxed) ||
        st.garbageBytes != mCounters.garbageBytes.load(std::memory_order_relaxed) ||
        st.shortTransfers != mCounters.shortTransfers.load(std::memory_order_relaxed);
    mCounters.badFrames.store(st.badFrames, std::memory_order_relaxed);
    mCounters.garbageBytes.store(st.garbageBytes, std::memory_order_relaxed);
    mCounters.shortTransfers.store(st.shortTransfers, std::memory_order_relaxed);
    return fresh;
}

void FalconIoThread::inDone(libusb_transfer* t) {
    mInFlight = false;
    if (t->status == LIBUSB_TRANSFER_COMPLETED) {
        mConsecutiveErrors = 0;
        const std::uint64_t before = mSequence;
        mParser.pushTransfer(
            std::span<const std::uint8_t>(t->buffer, static_cast<std::size_t>(t->actual_length)),
            [this](const Packet& f) { onFrame(f); });
        // Bad input with no valid sample in the same transfer: BadData once samples go stale.
        if (syncParserCounters() && mSequence == before) {
            mBadSinceValid.store(true, std::memory_order_relaxed);
        }
    } else if (t->status != LIBUSB_TRANSFER_CANCELLED) {
        transferFailed(t->status);
    }
    if (!mStopRequested.load(std::memory_order_relaxed) &&
        mState.load(std::memory_order_relaxed) == IoState::Running) {
        submitIn();
    }
}

void FalconIoThread::outDone(libusb_transfer* t) {
    mOutFlight = false;
    if (t->status == LIBUSB_TRANSFER_COMPLETED) {
        mConsecutiveErrors = 0;
        mCounters.commandsSent.fetch_add(1, std::memory_order_relaxed);
    } else if (t->status != LIBUSB_TRANSFER_CANCELLED) {
        transferFailed(t->status);
    }
}

void FalconIoThread::submitIn() {
    libusb_fill_bulk_transfer(mInTransfer, mUsb->handle(), kEndpointIn, mInBuffer.data(),
                              kTransferSize, &FalconIoThread::onIn, this, 0);
    const int rc = libusb_submit_transfer(mInTransfer);
    if (rc == 0) {
        mInFlight = true;
    } else if (rc == LIBUSB_ERROR_NO_DEVICE) {
        markDisconnected();
    } else {
        mUsb->setLastUsbError(rc);
        mState.store(IoState::Error, std::memory_order_release);
    }
}

/// The motor words for the newest force at the newest pose (zero while homing, without a
/// pose, or when the newest command is older than the command timeout: a stalled servo).
MotorWords FalconIoThread::motorWords(bool zero) {
    if (zero || !mHavePose || mHoming.load(std::memory_order_relaxed)) {
        return {0, 0, 0};
    }
    IoForce c{};
    if (!mCommands.read(c) || mSettings.commandClock() - c.timeNs > mSettings.commandTimeoutNs) {
        return {0, 0, 0};
    }
    const auto j = mKinematics.jacobian(mLastMechPosition, mLastAngles);
    if (!j) {
        return {0, 0, 0};
    }
    const Vec3 tau = FalconKinematics::forceToTorque(*j, c.forceN);
    return FalconKinematics::torqueToMotorWords(tau, mSettings.motorWordLimit);
}

void FalconIoThread::submitOut(bool zero) {
    FalconCommand cmd;
    cmd.motor = motorWords(zero);
    const std::uint8_t l = zero ? 0 : mLeds.load(std::memory_order_relaxed);
    // The homing bit in EVERY packet, during homing, after it and in the last zero packet:
    // "The homing mode bit must be set in each input packet sent in order for the falcon to
    // stay homed" (libnifalcon include/falcon/core/FalconFirmware.h, "Homing Mode").
    cmd.homing = true;
    cmd.ledGreen = (l & 2u) != 0;
    cmd.ledBlue = (l & 4u) != 0;
    cmd.ledRed = (l & 8u) != 0;
    mOutBuffer = encodeCommand(cmd);
    libusb_fill_bulk_transfer(mOutTransfer, mUsb->handle(), kEndpointOut, mOutBuffer.data(),
                              static_cast<int>(mOutBuffer.size()), &FalconIoThread::onOut, this,
                              static_cast<unsigned>(mSettings.timeouts.usb.count()));
    const int rc = libusb_submit_transfer(mOutTransfer);
    if (rc == 0) {
        mOutFlight = true;
        mReplySinceSend = false;
    } else if (rc == LIBUSB_ERROR_NO_DEVICE) {
        markDisconnected();
    } else {
        transferFailed(LIBUSB_TRANSFER_ERROR);
    }
}

void FalconIoThread::pump(std::chrono::microseconds wait) {
    timeval tv{};
    tv.tv_sec = static_cast<time_t>(wait.count() / 1000000);
    tv.tv_usec = static_cast<suseconds_t>(wait.count() % 1000000);
    const int rc = libusb_handle_events_timeout_completed(mUsb->context(), &tv, nullptr);
    if (rc == LIBUSB_ERROR_NO_DEVICE) {
        markDisconnected();
    }
}

void FalconIoThread::loop() {
    submitIn();
    auto nextSend = Clock::now();
    auto lastSend = Clock::now() - 1s;
    const auto replyGrace = 5 * mSettings.timeouts.period;
    while (mState.load(std::memory_order_relaxed) == IoState::Running) {
        const auto now = Clock::now();
        if (mStopRequested.load(std::memory_order_acquire)) {
            if (!mOutFlight && !mZeroSent) {
                submitOut(true); // close(): zero force is the last command
                mZeroSent = true;
            } else if (!mOutFlight && mZeroSent) {
                break;
            }
        } else if (!mOutFlight && now >= nextSend &&
                   (mReplySinceSend || now - lastSend >= replyGrace)) {
            submitOut(false);
            lastSend = now;
            nextSend = std::max(nextSend + mSettings.timeouts.period, now);
        }
        const auto until =
            std::chrono::duration_cast<std::chrono::microseconds>(nextSend - Clock::now());
        pump(std::clamp(until, std::chrono::microseconds(100), mSettings.timeouts.period));
    }
    // Drain: cancel what is in flight and wait (bounded) for libusb to hand it back.
    const auto deadline =
        Clock::now() + std::max<std::chrono::milliseconds>(mSettings.timeouts.usb, 200ms);
    bool cancelled = false;
    while ((mInFlight || mOutFlight) && Clock::now() < deadline) {
        if (!cancelled) {
            if (mInFlight) {
                libusb_cancel_transfer(mInTransfer);
            }
            if (mOutFlight && mState.load() != IoState::Running) {
                libusb_cancel_transfer(mOutTransfer);
            }
            cancelled = true;
        }
        pump(1ms);
    }
}

void FalconIoThread::start(FalconTransport& usb) {
    mUsb = &usb;
    mInTransfer = libusb_alloc_transfer(0);
    mOutTransfer = libusb_alloc_transfer(0);
    mStopRequested = false;
    mZeroSent = false;
    mHavePose = false;
    mInFlight = mOutFlight = mReplySinceSend = false;
    mConsecutiveErrors = 0;
    mState = IoState::Running;
    mThread = std::thread([this] { loop(); });
}

void FalconIoThread::stop() {
    if (mThread.joinable()) {
        mStopRequested.store(true, std::memory_order_release);
        mThread.join();
    }
    // A transfer libusb still holds cannot be freed safely; leak it rather than crash.
    if (mInTransfer && !mInFlight) {
        libusb_free_transfer(mInTransfer);
    }
    if (mOutTransfer && !mOutFlight) {
        libusb_free_transfer(mOutTransfer);
    }
    mInTransfer = nullptr;
    mOutTransfer = nullptr;
}

} // namespace hapto::falcon
