#pragma once
/// The one check every numeric command-line option goes through: a finite number in a range.

#include "hapto/index/IndexSpec.h"
#include "hapto/scenes/Scene.h"

#include <CLI/CLI.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hapto::cli {

/// The largest seed option value: the largest 64-bit unsigned integer, for finiteRange.
inline constexpr double kMaxSeed = 18446744073709551615.0;
/// The largest `--max-index-mb` (MB): 2^40, a limit no machine reaches.
inline constexpr double kMaxIndexMbOption = 1099511627776.0;

/// A CLI11 check for a number from `lo` to `hi` (inclusive). It refuses NaN, infinities, text
/// that is not a number and values out of range, naming the value and the range allowed; the
/// option's name is added by CLI11, and main() turns the refusal into exit code 2. Use it on
/// every numeric option (integers too: it also catches "-1" given to an unsigned option, which
/// CLI11 would otherwise wrap round). [control]
CLI::Validator finiteRange(double lo, double hi);

/// A CLI11 transform (add it with ->transform, not ->check, which cannot rewrite) for a whole
/// number from `lo` to `hi` (inclusive), written plainly or with an exponent ("200000",
/// "2e5"); it rewrites the text as plain digits so that CLI11 can read it into an integer
/// option (or each item of a `,`-delimited list; CLI11 skips empty items). Refuses fractions,
/// NaN, infinities and values out of range like finiteRange. [control]
CLI::Validator wholeNumber(double lo, double hi);

/// Adds an option taking exactly `count` numbers, comma-separated ("--center 0,0.1,0"), each
/// finite and from `lo` to `hi` (finiteRange), read into `values`. A wrong count, NaN, text or a
/// value out of range is refused naming the option (exit code 2). [control]
CLI::Option* addNumberListOption(CLI::App* cmd, const std::string& name,
                                 std::vector<double>& values, std::size_t count, double lo,
                                 double hi, const std::string& help);

/// The option conventions every command follows (README, "Commands"): durations in seconds
/// (`--duration S`), one servo rate `--rate HZ`, several `--rates HZ,HZ`, lists
/// comma-separated, numbers read as numbers by CLI11, real-time scheduling asked for with
/// `--realtime` and declined with `--no-realtime`. Old spellings stay as deprecated aliases.
/// Adds `--realtime` and `--no-realtime` as one flag setting `realtime`. [control]
CLI::Option* addRealtimeFlag(CLI::App* cmd, bool& realtime, const std::string& what);
/// Adds `--index SPEC` (brute, grid:N, octree:M:MIN, optional :aabb); left empty when not
/// given, for defaultIndexSpec to choose. [control]
CLI::Option* addIndexOption(CLI::App* cmd, std::string& spec);
/// The index a session builds when `--index` is not given: the paper's octree:2:0.005 over
/// boxes and spheres; over mesh triangles an octree of at most 8 items per leaf whose smallest
/// leaf is the scene's median triangle's longest edge (two significant digits, within 0.1 to
/// 5 mm), so that a leaf of a fine scan holds a few triangles rather than hundreds. [control]
std::string defaultIndexSpec(const Scene& scene);
/// The index a session over `scene` builds: `given` (an `--index` text) or, when it is empty,
/// defaultIndexSpec(scene); at most `maxMegabytes` (`--max-index-mb`). Throws InputError for a
/// bad `given`. [control]
IndexSpec sessionIndexSpec(const std::string& given, const Scene& scene,
                           std::uint64_t maxMegabytes);
/// Adds `--max-index-mb MB`, the most memory an index build may take. [control]
CLI::Option* addMaxIndexMbOption(CLI::App* cmd, std::uint64_t& megabytes);
/// Adds `--wake-latency-us US` (0 or more; unset leaves `us` at -1): a CPU wake-latency
/// request (rt::WakeLatencyHold) held while `what`. [control]
CLI::Option* addWakeLatencyOption(CLI::App* cmd, std::int32_t& us, const std::string& what);

/// The view's default port (`--view` without a port).
inline constexpr int kDefaultViewPort = 8340;

/// Where a command serves its view.
struct ViewArgs {
    bool enabled = false;                  ///< `--view` given.
    int port = kDefaultViewPort;           ///< TCP port; 0 takes any free one.
    std::string bindAddress = "127.0.0.1"; ///< `--view-bind ADDR`.
};
/// Adds `--view-bind ADDR` (an IPv4 or IPv6 address; a non-loopback one is warned about when
/// the view starts) to a command that serves the view. [control]
CLI::Option* addViewBindOption(CLI::App* cmd, ViewArgs& args);
/// Adds `--view [PORT]` (live 3-D view in the browser, default port kDefaultViewPort) and
/// `--view-bind ADDR`, which needs it. [control]
void addViewOptions(CLI::App* cmd, ViewArgs& args);

} // namespace hapto::cli
