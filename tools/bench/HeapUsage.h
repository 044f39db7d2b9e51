#pragma once
/// Heap bytes in use, from glibc's mallinfo2(), to measure what a structure's build keeps.

#include <malloc.h>

#include <cstddef>
#include <cstdint>

namespace hapto::bench {

/// Bytes the process holds from malloc right now: small-chunk bytes in use (uordblks) plus
/// mmapped large blocks (hblkhd), summed over every arena. Walks the arenas: not for hot
/// loops. [control]
inline std::size_t heapBytesInUse() {
    const struct mallinfo2 info = mallinfo2();
    return info.uordblks + info.hblkhd;
}

/// Runs `make` and returns what it built together with the heap growth it left behind
/// (bytes; 0 if the heap shrank). Single-threaded builds only see their own allocations;
/// a parallel build's worker threads are counted too, as mallinfo2 sums every arena.
/// [control]
template <class Make> auto measureHeap(Make&& make, std::size_t& grownBytes) {
    const std::size_t before = heapBytesInUse();
    auto built = make();
    const std::size_t after = heapBytesInUse();
    grownBytes = after > before ? after - before : 0;
    return built;
}

} // namespace hapto::bench
