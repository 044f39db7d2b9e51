// libFuzzer target: the Falcon packet decoder and the USB byte-stream reassembler. They read
// whatever the USB bus delivers: no input may crash them, and every frame they accept must
// re-encode to the same bytes.

#include "hapto/devices/FalconPacket.h"

#include <cstddef>
#include <cstdint>
#include <span>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::span<const std::uint8_t> bytes(data, size);
    (void)hapto::falcon::decode(bytes);
    // Feed the stream in transfers of up to 64 bytes, the first byte of each choosing the size.
    hapto::falcon::FalconStreamParser parser;
    std::size_t at = 0;
    while (at < size) {
        const std::size_t n = std::min<std::size_t>(size - at, 1 + data[at] % 64);
        parser.pushTransfer(bytes.subspan(at, n), [](const hapto::falcon::Packet& frame) {
            if (const auto reading = hapto::falcon::decode(frame)) {
                if (hapto::falcon::encodeReading(*reading) != frame) {
                    __builtin_trap();
                }
            }
        });
        at += n;
    }
    return 0;
}
