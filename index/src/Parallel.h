#pragma once
/// The one place TBB appears: parallel loops and sorts for index builds (control threads only;
/// a servo thread never joins a TBB arena).

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cstddef>
#include <thread>

// ThreadSanitizer cannot see the synchronisation inside the (uninstrumented) TBB library and
// reports races in TBB's own partitioner. Under TSan the loops therefore split their range in
// two and run the halves on two std::threads, which TSan does see, so our loop bodies are
// still checked for races; only TBB's scheduler is left out.
#if defined(__SANITIZE_THREAD__)
#define HAPTO_PARALLEL_PLAIN_THREADS 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define HAPTO_PARALLEL_PLAIN_THREADS 1
#endif
#endif

namespace hapto::parallel {

/// Calls body(lo, hi) on disjoint sub-ranges covering [begin, end), in parallel. Nested calls
/// are fine. [control]
template <class Body>
void forRanges(std::size_t begin, std::size_t end, std::size_t grain, const Body& body) {
    if (begin >= end) {
        return;
    }
#if defined(HAPTO_PARALLEL_PLAIN_THREADS)
    if (end - begin <= std::max<std::size_t>(grain, 1)) {
        body(begin, end);
        return;
    }
    const std::size_t mid = begin + (end - begin) / 2;
    std::thread upper([&] { body(mid, end); });
    body(begin, mid);
    upper.join();
#else
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, grain == 0 ? 1 : grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
#endif
}

/// Calls body(i) for every i in [begin, end), in parallel. [control]
template <class Body>
void forEach(std::size_t begin, std::size_t end, std::size_t grain, const Body& body) {
    forRanges(begin, end, grain, [&](std::size_t lo, std::size_t hi) {
        for (std::size_t i = lo; i < hi; ++i) {
            body(i);
        }
    });
}

/// Sorts [first, last) in parallel. [control]
template <class It> void sort(It first, It last) {
#if defined(HAPTO_PARALLEL_PLAIN_THREADS)
    std::sort(first, last);
#else
    tbb::parallel_sort(first, last);
#endif
}

} // namespace hapto::parallel
