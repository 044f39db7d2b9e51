// libFuzzer target: the trace reader. Any bytes read as a trace or are refused with an
// InputError naming the byte offset; nothing else may escape or crash. The input is handed to
// the real file reader through an in-memory file (memfd), so the reading code under test is
// the one `hapto trace` and replay devices use.

#include "hapto/devices/TraceReader.h"
#include "hapto/io/InputError.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <sys/mman.h>
#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const int fd = memfd_create("hapto-fuzz-trace", 0);
    if (fd < 0) {
        return 0;
    }
    std::size_t written = 0;
    while (written < size) {
        const ssize_t n = write(fd, data + written, size - written);
        if (n <= 0) {
            close(fd);
            return 0;
        }
        written += static_cast<std::size_t>(n);
    }
    try {
        hapto::TraceHeader header;
        const auto samples =
            hapto::TraceReader::load("/proc/self/fd/" + std::to_string(fd), &header);
        // ... a unit orientation and at most three contacts, and a usable configuration.
        if (!(header.transform.scale > 0.0) ||
            std::abs(glm::length(header.transform.rotation) - 1.0) > 1e-6) {
            __builtin_trap();
        }
        for (const hapto::TraceSample& s : samples) {
            if (std::abs(glm::length(s.orientation) - 1.0) > 1e-6 || s.contactCount > 3) {
                __builtin_trap();
            }
            // The reader promises finite values.
            for (int i = 0; i < 3; ++i) {
                if (!std::isfinite(s.positionM[i]) || !std::isfinite(s.forceN[i]) ||
                    !std::isfinite(s.proxyM[i]) || !std::isfinite(s.velocityMps[i]) ||
                    !std::isfinite(s.angularVelocity[i])) {
                    __builtin_trap();
                }
            }
        }
    } catch (const hapto::InputError&) {
    }
    close(fd);
    return 0;
}
