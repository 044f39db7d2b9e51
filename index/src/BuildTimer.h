#pragma once
/// Measures an index build: wall-clock time and the CPU time of all the process's threads.

#include "hapto/index/IndexStats.h"

#include <chrono>
#include <sys/resource.h>

namespace hapto {

/// Starts timing when made; finish() writes buildSeconds and buildCpuSeconds. [control]
class BuildTimer {
public:
    BuildTimer() noexcept : mWall(std::chrono::steady_clock::now()), mCpu(cpuSeconds()) {}
    /// Writes the elapsed times into the stats. [control]
    void finish(IndexStats& stats) const noexcept {
        stats.buildSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - mWall).count();
        stats.buildCpuSeconds = cpuSeconds() - mCpu;
    }

private:
    static double cpuSeconds() noexcept {
        rusage u{};
        getrusage(RUSAGE_SELF, &u);
        return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
               1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
    }
    std::chrono::steady_clock::time_point mWall;
    double mCpu;
};

} // namespace hapto
