#include "FalconTransport.h"

#include "hapto/devices/FalconDevice.h"
#include "hapto/devices/FalconPacket.h"

#include <string>
#include <utility>

namespace hapto::falcon {
namespace {

using Clock = std::chrono::steady_clock;

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

} // namespace

std::string usbError(int rc) {
    return libusb_strerror(static_cast<libusb_error>(rc));
}

bool FalconTransport::fail(std::string message) {
    mError = std::move(message);
    return false;
}

DeviceStatus FalconTransport::open(const std::string& deviceName, const FalconConfig& config) {
    if (const int rc = libusb_init(&mContext); rc != 0) {
        mContext = nullptr;
        fail("libusb could not be initialised: " + usbError(rc));
        return DeviceStatus::Error;
    }
    if (!findAndOpen(deviceName, config)) {
        close();
        return DeviceStatus::Disconnected;
    }
    libusb_set_auto_detach_kernel_driver(mHandle, 1);
    if (const int rc = libusb_claim_interface(mHandle, kInterface); rc != 0) {
        fail("cannot claim the Falcon's USB interface: " + usbError(rc) +
             (rc == LIBUSB_ERROR_BUSY ? " (another program is using it; close it)" : ""));
        close();
        return DeviceStatus::Error;
    }
    if (!(ftdi(kReqReset, kResetSio) && normalMode())) {
        close();
        return DeviceStatus::Error;
    }
    return DeviceStatus::Ok;
}

void FalconTransport::close() {
    if (mHandle) {
        libusb_release_interface(mHandle, kInterface);
        libusb_close(mHandle);
        mHandle = nullptr;
    }
    if (mContext) {
        libusb_exit(mContext);
        mContext = nullptr;
    }
}

bool FalconTransport::ftdi(std::uint8_t request, std::uint16_t value) {
    const int rc = libusb_control_transfer(mHandle, kFtdiOut, request, value, 0, nullptr, 0,
                                           static_cast<unsigned>(mUsbTimeout.count()));
    if (rc < 0) {
        setLastUsbError(rc);
        return fail("FTDI set-up request " + std::to_string(request) + " failed: " + usbError(rc));
    }
    return true;
}

bool FalconTransport::writeBytes(const std::uint8_t* data, std::size_t length) {
    int done = 0;
    const int rc = libusb_bulk_transfer(mHandle, kEndpointOut, const_cast<std::uint8_t*>(data),
                                        static_cast<int>(length), &done,
                                        static_cast<unsigned>(mUsbTimeout.count()));
    if (rc != 0 || static_cast<std::size_t>(done) != length) {
        setLastUsbError(rc);
        return fail("writing to the Falcon failed: " + usbError(rc));
    }
    return true;
}

std::vector<std::uint8_t> FalconTransport::readBytes(std::size_t want,
                                                     std::chrono::milliseconds timeout) {
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
        const int rc = libusb_bulk_transfer(mHandle, kEndpointIn, buf, kTransferSize, &got,
                                            static_cast<unsigned>(left.count()));
        if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT) {
            setLastUsbError(rc);
            break;
        }
        if (got > static_cast<int>(falcon::kFtdiStatusBytes)) {
            out.insert(out.end(), buf + falcon::kFtdiStatusBytes, buf + got);
        }
    }
    return out;
}

bool FalconTransport::normalMode() {
    return ftdi(kReqLatency, 1) && ftdi(kReqBaud, kBaudNormal) && ftdi(kReqData, kData8N1) &&
           ftdi(kReqFlow, 0) && ftdi(kReqReset, kPurgeRx) && ftdi(kReqReset, kPurgeTx);
}

bool FalconTransport::findAndOpen(const std::string& deviceName, const FalconConfig& config) {
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(mContext, &list);
    if (n < 0) {
        return fail("libusb could not list USB devices: " + usbError(static_cast<int>(n)));
    }
    std::string seen;
    std::string denied;
    for (ssize_t i = 0; i < n && !mHandle; ++i) {
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
        mHandle = h;
    }
    libusb_free_device_list(list, 1);
    if (mHandle) {
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
    return fail("device '" + deviceName + "': no " + wanted + " found" +
                (seen.empty() ? ": is it plugged in and powered? (`hapto devices` lists "
                                "what is connected)"
                              : "; found instead: " + seen));
}

} // namespace hapto::falcon

namespace hapto {

// ---------------------------------------------------------------------------------------------
// Discovery

std::vector<FalconInfo> listFalcons(std::string& whyNone) {
    std::vector<FalconInfo> out;
    whyNone.clear();
    libusb_context* ctx = nullptr;
    if (const int rc = libusb_init(&ctx); rc != 0) {
        whyNone = "libusb could not be initialised: " + falcon::usbError(rc);
        return out;
    }
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx, &list);
    if (n < 0) {
        whyNone = "libusb could not list USB devices: " + falcon::usbError(static_cast<int>(n));
        libusb_exit(ctx);
        return out;
    }
    int found = 0;
    std::string denied;
    for (ssize_t i = 0; i < n; ++i) {
        libusb_device* dev = list[i];
        if (!falcon::isFalcon(dev)) {
            continue;
        }
        ++found;
        libusb_device_handle* h = nullptr;
        const int rc = libusb_open(dev, &h);
        if (rc == LIBUSB_ERROR_ACCESS) {
            denied += (denied.empty() ? "" : ", ") + falcon::where(dev);
            continue;
        }
        FalconInfo info;
        info.bus = libusb_get_bus_number(dev);
        info.address = libusb_get_device_address(dev);
        if (rc == 0) {
            info.serial = falcon::readSerial(h, dev);
            libusb_close(h);
        }
        out.push_back(std::move(info));
    }
    libusb_free_device_list(list, 1);
    libusb_exit(ctx);
    if (out.empty()) {
        whyNone = found == 0 ? "no 0403:cb48 device on the USB bus"
                             : "permission denied opening the Falcon on " + denied + ": " +
                                   falcon::kUdevHint;
    }
    return out;
}

} // namespace hapto
