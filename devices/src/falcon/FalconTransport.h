#pragma once
/// The Falcon's USB link: the libusb context and handle, the FTDI bridge's vendor requests, and
/// the blocking bulk reads and writes that set-up uses (the I/O thread uses the handle itself).

#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"

#include <libusb.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hapto::falcon {

inline constexpr std::uint16_t kVendorId = 0x0403;  ///< FTDI (the Falcon's USB bridge).
inline constexpr std::uint16_t kProductId = 0xCB48; ///< Novint Falcon.
inline constexpr unsigned char kEndpointOut = 0x02; ///< Bulk OUT.
inline constexpr unsigned char kEndpointIn = 0x81;  ///< Bulk IN.
inline constexpr int kInterface = 0;                ///< The one interface.
inline constexpr int kTransferSize = 64;            ///< One bulk IN transfer (bytes).

// FTDI vendor requests (bmRequestType 0x40, wIndex 0), as libnifalcon sends them
// (src/comm/FalconCommLibUSB.cpp, the SIO_* defines taken from libftdi).
inline constexpr std::uint8_t kFtdiOut = 0x40; ///< bmRequestType of every vendor request.
inline constexpr std::uint8_t kReqReset = 0, kReqModem = 1, kReqFlow = 2, kReqBaud = 3,
                              kReqData = 4, kReqLatency = 9;
inline constexpr std::uint16_t kResetSio = 0, kPurgeRx = 1, kPurgeTx = 2;
inline constexpr std::uint16_t kDtrLow = 0x0100, kDtrHigh = 0x0101, kRtsLow = 0x0200;
inline constexpr std::uint16_t kData8N1 = 0x0008;
inline constexpr std::uint16_t kBaudBootloader = 0x4138; ///< 9600 baud (setFirmwareMode).
inline constexpr std::uint16_t kBaudUpload = 0x0015;     ///< Firmware upload (setFirmwareMode).
inline constexpr std::uint16_t kBaudNormal = 0x0002;     ///< 1.5 Mbaud (setNormalMode).

/// libusb's text for an error code. [any thread]
std::string usbError(int rc);

/// What to do when the Falcon cannot be opened for lack of permission.
inline constexpr const char* kUdevHint =
    "install the udev rule devices/udev/99-hapto-falcon.rules, add yourself to the plugdev "
    "group and re-plug the Falcon (see README, \"Novint Falcon\")";

/// One Falcon's USB link. Set-up calls are [control]; once the I/O thread runs it owns the
/// handle's traffic, and only close() (after the I/O thread stopped) touches it again.
class FalconTransport {
public:
    /// A closed link; failures are written to `error` (for people). [control]
    explicit FalconTransport(std::string& error) : mError(error) {}
    /// Releases the link if open. [control]
    ~FalconTransport() { close(); }
    FalconTransport(const FalconTransport&) = delete;
    FalconTransport& operator=(const FalconTransport&) = delete;

    /// Initialises libusb, opens the first Falcon matching `config` (serial, bus, address),
    /// claims its interface, resets the FTDI bridge and puts it in normal mode. Returns Ok,
    /// Disconnected (none found) or Error, with error() saying what to do; on failure the link
    /// is closed again. `deviceName` names the device in messages. [control]
    DeviceStatus open(const std::string& deviceName, const FalconConfig& config);
    /// Releases the interface, closes the handle, exits libusb. Safe twice. [control]
    void close();
    /// True between a successful open() and close(). [control]
    bool isOpen() const { return mHandle != nullptr; }

    /// One FTDI vendor request; false (and error()) when it fails. [control]
    bool ftdi(std::uint8_t request, std::uint16_t value);
    /// Writes `length` bytes, blocking up to the USB timeout. [control]
    bool writeBytes(const std::uint8_t* data, std::size_t length);
    /// Reads payload bytes (FTDI status bytes stripped) until `want` arrived or `timeout`
    /// passed; may return fewer. [control]
    std::vector<std::uint8_t> readBytes(std::size_t want, std::chrono::milliseconds timeout);
    /// The normal I/O line settings: latency 1 ms, 1.5 Mbaud, 8N1, no flow control, both
    /// buffers purged (libnifalcon src/comm/FalconCommLibUSB.cpp, setNormalMode). [control]
    bool normalMode();

    /// Records a failure for people; returns false. [control]
    bool fail(std::string message);
    /// The last libusb error code a transfer gave (0: none). [any thread]
    int lastUsbError() const noexcept { return mLastUsbError.load(std::memory_order_relaxed); }
    /// Records a libusb error code. [any thread]
    void setLastUsbError(int rc) noexcept { mLastUsbError.store(rc, std::memory_order_relaxed); }
    /// Timeout of one synchronous transfer. [control]
    void setUsbTimeout(std::chrono::milliseconds timeout) { mUsbTimeout = timeout; }
    /// Timeout of one synchronous transfer. [any thread]
    std::chrono::milliseconds usbTimeout() const { return mUsbTimeout; }

    /// The libusb context (null when closed). [control]
    libusb_context* context() const { return mContext; }
    /// The device handle (null when closed). [control]
    libusb_device_handle* handle() const { return mHandle; }

private:
    bool findAndOpen(const std::string& deviceName, const FalconConfig& config);

    std::string& mError;
    libusb_context* mContext = nullptr;
    libusb_device_handle* mHandle = nullptr;
    std::chrono::milliseconds mUsbTimeout{500};
    std::atomic<int> mLastUsbError{0};
};

} // namespace hapto::falcon
