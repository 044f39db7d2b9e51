#pragma once
/// Heap bytes in use, from glibc's mallinfo2(), to measure what a structure's build keeps;
/// and the build benchmarks' loop, which starts each run from a trimmed heap.

#include <benchmark/benchmark.h>
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

/// A build benchmark's loop: one build per iteration; freeing the previous one is not timed.
/// Returns the last build (a smart pointer) and sets `heapBytesPerItem` to the heap growth of
/// the first over `count` items.
///
/// Each run starts from a trimmed heap, as in a fresh process: the heap is trimmed
/// (malloc_trim returns free pages to the kernel) before the first build, so that build pays
/// for every page it first writes whatever ran before it. A build's time at 10^6 follows the
/// fresh pages it touches (about 11 us a page on the VM of docs/results/index-builds.md);
/// without the trim a build that got the pages an earlier benchmark had freed ran up to 2x
/// faster than the same build in a process of its own, and which structure got them depended
/// on the order the benchmarks ran in. The run's later builds each free the previous one
/// first and reuse what the allocator kept, as a program that builds again does (at 10^3
/// items a fresh build is mostly page faults). [control]
template <class Build>
auto buildLoop(benchmark::State& state, std::size_t count, double& heapBytesPerItem,
               Build&& build) {
    bool first = true;
    decltype(build()) last;
    for (auto _ : state) {
        state.PauseTiming();
        last.reset();
        if (first) {
            malloc_trim(0);
        }
        const std::size_t before = heapBytesInUse();
        state.ResumeTiming();
        auto built = build();
        state.PauseTiming();
        if (first) {
            const std::size_t after = heapBytesInUse();
            heapBytesPerItem = after > before ? static_cast<double>(after - before) / count : 0.0;
            first = false;
        }
        last = std::move(built);
        state.ResumeTiming();
    }
    return last;
}

} // namespace hapto::bench
