#include "hapto/core/Clock.h"

#include <ctime>

namespace hapto {
namespace {

/// `clock` now, in nanoseconds.
std::uint64_t readNs(clockid_t clock) noexcept {
    timespec ts;
    clock_gettime(clock, &ts);
    return static_cast<std::uint64_t>(ts.tv_sec) * 1'000'000'000ull +
           static_cast<std::uint64_t>(ts.tv_nsec);
}

} // namespace

std::uint64_t monotonicNs() noexcept {
    return readNs(CLOCK_MONOTONIC);
}

std::uint64_t threadCpuNs() noexcept {
    return readNs(CLOCK_THREAD_CPUTIME_ID);
}

} // namespace hapto
