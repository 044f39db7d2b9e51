// The finite-range check for numeric options.

#include "Options.h"

#include <arpa/inet.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace hapto::cli {
namespace {

std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.15g", v);
    return text;
}

} // namespace

CLI::Validator finiteRange(double lo, double hi) {
    const std::string range = "from " + number(lo) + " to " + number(hi);
    return CLI::Validator(
        [lo, hi, range](std::string& text) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(text, v)) {
                return "'" + text + "' is not a number; expected a number " + range;
            }
            if (!std::isfinite(v)) {
                return "'" + text + "' is not a finite number; expected a number " + range;
            }
            if (v < lo || v > hi) {
                return text + " is out of range; expected a number " + range;
            }
            return {};
        },
        "in [" + number(lo) + ", " + number(hi) + "]", "FINITE_RANGE");
}

CLI::Validator wholeNumber(double lo, double hi) {
    const std::string range = "from " + number(lo) + " to " + number(hi);
    return CLI::Validator(
        [lo, hi, range](std::string& text) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(text, v)) {
                return "'" + text + "' is not a number; expected a whole number " + range;
            }
            if (!std::isfinite(v) || std::floor(v) != v) {
                return "'" + text + "' is not a whole number; expected a whole number " + range;
            }
            if (v < lo || v > hi) {
                return text + " is out of range; expected a whole number " + range;
            }
            text = number(v); // "2e5" -> "200000", which an integer option reads
            return {};
        },
        "whole number in [" + number(lo) + ", " + number(hi) + "]", "WHOLE_NUMBER");
}

CLI::Option* addNumberListOption(CLI::App* cmd, const std::string& name,
                                 std::vector<double>& values, std::size_t count, double lo,
                                 double hi, const std::string& help) {
    return cmd->add_option(name, values, help)
        ->delimiter(',')
        ->expected(static_cast<int>(count))
        ->check(finiteRange(lo, hi));
}

CLI::Option* addRealtimeFlag(CLI::App* cmd, bool& realtime, const std::string& what) {
    return cmd->add_flag("--realtime,!--no-realtime", realtime,
                         "Ask for SCHED_FIFO and CPU pinning (" + what +
                             "); --no-realtime: do not (the runtime falls back to normal "
                             "scheduling when refused and says so)");
}

CLI::Option* addIndexOption(CLI::App* cmd, std::string& spec) {
    return cmd->add_option("--index", spec,
                           "Spatial index: brute, grid:N, octree:M:MIN (MIN in m), optional "
                           ":aabb. Default: octree:2:0.005; over meshes octree:8:E, E the median "
                           "triangle's longest edge (m, within 0.0001-0.005)");
}

std::string defaultIndexSpec(const Scene& scene) {
    std::vector<double> edges; // each triangle's longest edge (m)
    for (const SceneObject& o : scene.objects()) {
        if (o.shape != Shape::Mesh || !o.mesh) {
            continue;
        }
        for (std::uint32_t t = 0; t < o.mesh->triangleCount(); ++t) {
            const auto [p, q, r] = o.mesh->corners(t);
            edges.push_back(std::sqrt(std::max(
                {glm::dot(q - p, q - p), glm::dot(r - q, r - q), glm::dot(p - r, p - r)})));
        }
    }
    if (edges.empty()) {
        return "octree:2:0.005";
    }
    const auto middle = edges.begin() + static_cast<std::ptrdiff_t>(edges.size() / 2);
    std::nth_element(edges.begin(), middle, edges.end());
    const double edge = std::clamp(*middle, 1e-4, 5e-3);
    char spec[64];
    std::snprintf(spec, sizeof spec, "octree:8:%.2g", edge);
    return spec;
}

IndexSpec sessionIndexSpec(const std::string& given, const Scene& scene,
                           std::uint64_t maxMegabytes) {
    return IndexSpec::parse(given.empty() ? defaultIndexSpec(scene) : given)
        .withMaxMegabytes(maxMegabytes);
}

CLI::Option* addMaxIndexMbOption(CLI::App* cmd, std::uint64_t& megabytes) {
    return cmd
        ->add_option("--max-index-mb", megabytes,
                     "Most memory an index build may take (MB); a larger index is refused")
        ->capture_default_str()
        ->check(finiteRange(1, kMaxIndexMbOption));
}

CLI::Option* addWakeLatencyOption(CLI::App* cmd, std::int32_t& us, const std::string& what) {
    return cmd
        ->add_option("--wake-latency-us", us,
                     "Ask the kernel that no idle CPU take longer than this to wake (us) while " +
                         what +
                         " (/dev/cpu_dma_latency, as cyclictest does; needs root): 0 keeps idle "
                         "CPUs polling instead of halting, which cuts the tail of a tick after "
                         "its sleep (docs/results/tick.md) and makes every idle core spin")
        ->check(finiteRange(0, 1e6));
}

CLI::Option* addViewBindOption(CLI::App* cmd, ViewArgs& args) {
    return cmd
        ->add_option("--view-bind", args.bindAddress,
                     "Address the view listens on (default 127.0.0.1, this machine only; "
                     "another address lets anyone who reaches it watch, read-only)")
        ->check([](const std::string& text) -> std::string {
            in6_addr any{};
            if (inet_pton(AF_INET, text.c_str(), &any) == 1 ||
                inet_pton(AF_INET6, text.c_str(), &any) == 1) {
                return {};
            }
            return "'" + text + "' is not an IPv4 or IPv6 address";
        });
}

void addViewOptions(CLI::App* cmd, ViewArgs& args) {
    auto* view = cmd->add_option_function<int>(
                        "--view",
                        [&args](int port) {
                            args.enabled = true;
                            args.port = port;
                        },
                        "Serve a live 3-D view of the session on http://127.0.0.1:PORT/ (default " +
                            std::to_string(kDefaultViewPort) + "; 0 takes any free port)")
                     ->expected(0, 1)
                     ->default_str(std::to_string(kDefaultViewPort))
                     ->check(finiteRange(0, 65535));
    addViewBindOption(cmd, args)->needs(view);
}

} // namespace hapto::cli
