// Times an index's memory estimate and build apart from loading the scene (a timing program
// beside the benchmarks, never a test). Loads the scene, then for each spec resets the peak
// resident memory (Linux: /proc/self/clear_refs "5") and reports wall and CPU seconds and the
// peak RSS above the loaded scene's, of estimateIndexMemory or (prefix build=) of buildIndex.
//
//   index_memory_timing SCENE [--max-index-mb N] SPEC|build=SPEC ...

#include "hapto/index/IndexSpec.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/scenes/SceneFile.h"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>

using namespace hapto;

namespace {

/// A /proc/self/status field in kB ("VmRSS:", "VmHWM:"), -1 when missing.
long statusKb(const std::string& key) {
    std::ifstream f("/proc/self/status");
    for (std::string line; std::getline(f, line);) {
        if (line.rfind(key, 0) == 0) {
            return std::stol(line.substr(key.size()));
        }
    }
    return -1;
}

/// This process's user + system CPU time (s).
double cpuSeconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Runs one estimate or build and returns what it found.
std::string runOne(const Scene& scene, const IndexSpec& spec, bool build) {
    if (!build) {
        const IndexMemoryEstimate e = estimateIndexMemory(scene, spec);
        return "floor " + std::to_string(e.nodesAtLeast) + " nodes, " +
               std::to_string(e.atLeastBytes >> 20) + " MB; ceiling " +
               std::to_string(e.atMostBytes >> 20) + " MB";
    }
    try {
        const auto index = buildIndex(scene, spec);
        return "built: " + std::to_string(index->stats().nodes) + " nodes, " +
               std::to_string(index->stats().bytes >> 20) + " MB";
    } catch (const std::exception& e) {
        return std::string("refused: ") + e.what();
    }
}

} // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::fprintf(stderr,
                     "usage: index_memory_timing SCENE [--max-index-mb N] SPEC|build=SPEC...\n");
        return 2;
    }
    const Scene scene = loadSceneFile(argv[1]);
    std::uint64_t maxBytes = 0;
    for (int i = 2; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg == "--max-index-mb" && i + 1 < argc) {
            maxBytes = std::stoull(argv[++i]) << 20;
            continue;
        }
        const bool build = arg.rfind("build=", 0) == 0;
        IndexSpec spec = IndexSpec::parse(build ? arg.substr(6) : arg);
        if (maxBytes > 0) {
            spec.maxBytes = maxBytes;
        }
        { std::ofstream("/proc/self/clear_refs") << "5"; } // peak RSS := current RSS
        const long base = statusKb("VmRSS:");
        const auto t0 = std::chrono::steady_clock::now();
        const double c0 = cpuSeconds();
        const std::string what = runOne(scene, spec, build);
        const double wall =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("%s %s (limit %llu MB): %.3f s wall, %.3f s CPU, peak RSS %.1f MB above the "
                    "loaded scene; %s\n",
                    build ? "build" : "estimate", spec.toString().c_str(),
                    static_cast<unsigned long long>(spec.maxBytes >> 20), wall, cpuSeconds() - c0,
                    static_cast<double>(statusKb("VmHWM:") - base) / 1024.0, what.c_str());
        std::fflush(stdout);
    }
    return 0;
}
