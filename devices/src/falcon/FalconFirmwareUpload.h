#pragma once
/// Firmware on the Falcon: probing for running firmware and uploading an image when none runs
/// (the Falcon forgets its firmware at power-off).

#include "FalconTransport.h"

#include <chrono>
#include <cstdint>
#include <filesystem>

namespace hapto::falcon {

/// Handshake attempts with the bootloader before giving up.
inline constexpr int kHandshakeAttempts = 10;

/// Sends one zero-force packet (homing bit set) and waits up to `probe` for any valid reply
/// frame: true when firmware runs. Stops early when the device went away
/// (usb.lastUsbError() == LIBUSB_ERROR_NO_DEVICE). [control]
bool firmwareAnswers(FalconTransport& usb, std::chrono::milliseconds probe);

/// Uploads the firmware image at `path`: bootloader line settings, the 0A 43 0D handshake, upload
/// mode, the image in echoed chunks, then normal mode again (libnifalcon
/// src/comm/FalconCommLibUSB.cpp, setFirmwareMode; src/core/FalconFirmware.cpp,
/// FalconFirmware::loadFirmware). False with usb's error set (what to do) on failure.
/// `probe` bounds each handshake reply. [control]
bool uploadFirmware(FalconTransport& usb, const std::filesystem::path& path,
                    std::chrono::milliseconds probe);

} // namespace hapto::falcon
