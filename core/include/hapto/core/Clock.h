#pragma once
/// The clocks every module reads, in nanoseconds: the monotonic clock (CLOCK_MONOTONIC) and
/// the calling thread's CPU clock (CLOCK_THREAD_CPUTIME_ID).

#include <cstdint>

namespace hapto {

/// CLOCK_MONOTONIC now, in nanoseconds (the clock std::chrono::steady_clock reads on Linux).
/// No allocation, lock or syscall beyond the vDSO read. [servo]
std::uint64_t monotonicNs() noexcept;

/// The calling thread's CPU time (CLOCK_THREAD_CPUTIME_ID), in nanoseconds: what the thread ran,
/// without the time other processes held the core. A system call (Linux's vDSO serves only the
/// realtime, monotonic, boottime and TAI clocks: lib/vdso/gettimeofday.c), so for measuring,
/// not for the servo path. [any thread]
std::uint64_t threadCpuNs() noexcept;

} // namespace hapto
