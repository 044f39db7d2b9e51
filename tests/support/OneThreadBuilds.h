#pragma once
// Index builds on the calling thread alone, for a test case whose checks are about what a
// build gives, not about its threads.

#include <tbb/global_control.h>

namespace hapto::test {

/// From this call to the end of the process, TBB runs every parallel loop on the calling thread
/// and starts no worker thread. A case that calls it first thing starts no thread, so it needs
/// no [threads] tag and the ThreadSanitizer build leaves it to release and ASan: its checks
/// (brute-force references over every index) cost TSan a minute and give it no threads to
/// watch. The parallel builds themselves are race-checked by the [threads] cases that build
/// with every thread (BuildPinTests.cpp: the same bits on any number of threads). The limit is
/// never lifted: lifting it makes TBB start its workers at once, inside the case. CTest runs
/// each case in a process of its own; a binary run by hand builds on one thread after the
/// first such case.
inline void buildOnOneThread() {
    static const tbb::global_control* const limit =
        new tbb::global_control(tbb::global_control::max_allowed_parallelism, 1);
    static_cast<void>(limit);
}

} // namespace hapto::test
