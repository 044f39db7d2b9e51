#pragma once
/// `hapto soak` as a library: D simulated hands over a world that keeps changing, with faults
/// injected on a schedule; drift, misses, memory and fault handling, with a verdict.

#include "hapto/index/DefaultIndex.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/scenes/Scene.h"

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace hapto::experiments {

/// What a soak runs: durations in seconds unless the name says otherwise.
struct SoakOptions {
    double durationS = 60.0;                   ///< How long to run (s).
    std::string durationOption = "--duration"; ///< The option as given, for messages.
    int devices = 2;                           ///< Simulated hands (D).
    double rateHz = 1000.0;                    ///< Servo rate of every hand (Hz).
    std::string index{kDefaultIndexSpec};      ///< Spatial index specification.
    std::uint64_t maxIndexMb = IndexSpec::kDefaultMaxMegabytes; ///< Index memory limit (MB).
    double faultEveryS = 15.0; ///< A fault every this many seconds, hands in turn.
    double windowS = 60.0;     ///< Report window (s).
    double watchdogMs = 50.0;  ///< Watchdog timeout (ms); stalls are sized by it.
    /// Reopen period after a fault (ms): the runtime's, as `hapto run` has it.
    double reopenMs = static_cast<double>(RuntimeOptions{}.reopenAfterNs) / 1e6;
    double memoryToleranceMiB = 2.0; ///< Allowed resident-memory growth (MiB).
    std::string report;              ///< JSON report path; empty: none.
    bool realtime = true;            ///< Ask for SCHED_FIFO and pinning.
};

/// What the caller lends a soak: how it learns of a stop request, and a hook that sees the
/// runtime before it starts (to arm an emergency stop). Both optional.
struct SoakControl {
    std::function<bool()> stopRequested;     ///< True once the soak should end (no verdict).
    std::function<void(Runtime&)> onRuntime; ///< Called once, before the devices start.
};

/// How long before the end no more faults are injected, so the last one can recover (s).
/// [any thread]
double soakQuietTailS(const SoakOptions& options);
/// Refuses a soak that could test nothing (it would end before its first fault), throwing
/// InputError naming the option. [any thread]
void checkSoakOptions(const SoakOptions& options);
/// Runs the soak over `scene` (shared with the World, not copied), printing each window and the
/// verdict (stdout) and writing the JSON report atomically when asked. Returns 0 on PASS, 1 on
/// FAIL or when stopped (no verdict). Throws InputError for bad options. [control]
int runSoak(std::shared_ptr<const Scene> scene, const SoakOptions& options,
            const SoakControl& control);

/// Least-squares slope of y over x, per hour when x is in seconds; 0 for fewer than two
/// points or no spread in x. [any thread]
double slopePerHour(const std::vector<double>& xS, const std::vector<double>& y);

} // namespace hapto::experiments
