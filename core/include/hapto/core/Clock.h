#pragma once
/// The monotonic clock every module reads: CLOCK_MONOTONIC in nanoseconds.

#include <cstdint>

namespace hapto {

/// CLOCK_MONOTONIC now, in nanoseconds (the clock std::chrono::steady_clock reads on Linux).
/// No allocation, lock or syscall beyond the vDSO read. [servo]
std::uint64_t monotonicNs() noexcept;

} // namespace hapto
