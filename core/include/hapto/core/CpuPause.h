#pragma once
/// cpuPause(): the spin-wait hint of the CPU we build for, so busy-wait loops build on x86-64
/// and ARM64 alike.

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace hapto {

/// Tells the CPU the thread is spinning: `pause` on x86 (Intel SDM, PAUSE), `yield` on AArch64
/// (Arm ARM, YIELD), nothing elsewhere. Never blocks. [servo]
inline void cpuPause() noexcept {
#if defined(__x86_64__) || defined(__i386__)
    _mm_pause();
#elif defined(__aarch64__)
    asm volatile("yield" ::: "memory");
#endif
}

} // namespace hapto
