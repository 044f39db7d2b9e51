#pragma once
/// The command line's shared conventions: the checks numeric options go through, the options
/// several commands share, and how help is laid out (wrapped, with examples, every depth).

#include "hapto/index/DefaultIndex.h" // defaultIndexSpec, sessionIndexSpec: what --index chooses

#include <CLI/CLI.hpp>

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
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
/// Like finiteRange, for a number above 0 (0 refused) and at most `hi`: what a scale or a
/// stiffness takes. Its range reads "(0, hi]" in the help. [control]
CLI::Validator positiveRange(double hi);

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

/// The option conventions every command follows (docs/guide/conventions.md): durations in seconds
/// (`--duration S`), one servo rate `--rate HZ`, several `--rates HZ,HZ`, lists
/// comma-separated, numbers read as numbers by CLI11, real-time scheduling asked for with
/// `--realtime` and declined with `--no-realtime`, `--devices FILE` a device file, the view
/// `--view`, `--view-port`, `--view-bind`. A renamed option or command is refused naming its
/// new spelling (addRenamedOption), except `--rate` (experiments), `--minutes` (soak) and
/// `--view PORT`, kept as deprecated spellings.
/// Adds `--realtime` and `--no-realtime` as one flag setting `realtime` (the last one given
/// wins); its help names the default, `realtime`'s value now, and `why` (may be empty).
/// [control]
CLI::Option* addRealtimeFlag(CLI::App* cmd, bool& realtime, const std::string& why);
/// Adds a hidden option `oldName` (taking at most one value) that refuses any use with "OLD:
/// renamed; use NEW" and `why`, exit code 2: a renamed option fails loudly instead of being
/// read as something else. [control]
CLI::Option* addRenamedOption(CLI::App* cmd, const std::string& oldName,
                              const std::string& newSpelling, const std::string& why);
/// Adds a hidden subcommand `oldName` to `parent` that refuses any use naming `newSpelling`
/// (exit code 2), whatever options follow it. [control]
CLI::App* addRenamedCommand(CLI::App* parent, const std::string& oldName,
                            const std::string& newSpelling);
/// Adds `--index SPEC` (brute, grid:N, octree:M:MIN, optional :aabb); left empty when not
/// given, for the library's defaultIndexSpec (hapto/index/DefaultIndex.h) to choose; a
/// session's index is then sessionIndexSpec(spec, scene, `--max-index-mb`). [control]
CLI::Option* addIndexOption(CLI::App* cmd, std::string& spec);
/// Adds `--max-index-mb MB`, the most memory an index build may take. [control]
CLI::Option* addMaxIndexMbOption(CLI::App* cmd, std::uint64_t& megabytes);
/// Adds `--wake-latency-us US` (0 or more; unset leaves `us` at -1): a CPU wake-latency
/// request (rt::WakeLatencyHold) held while `what`. [control]
CLI::Option* addWakeLatencyOption(CLI::App* cmd, std::int32_t& us, const std::string& what);

/// The view's default port (`--view-port` not given).
inline constexpr int kDefaultViewPort = 8340;

/// Where a command serves its view.
struct ViewArgs {
    bool enabled = false;                  ///< `--view` given.
    int port = kDefaultViewPort;           ///< `--view-port PORT`; 0 takes any free one.
    std::string bindAddress = "127.0.0.1"; ///< `--view-bind ADDR`.
};
/// Adds `--view-port PORT` (default kDefaultViewPort; 0 takes any free port). [control]
CLI::Option* addViewPortOption(CLI::App* cmd, ViewArgs& args);
/// Adds `--view-bind ADDR` (an IPv4 or IPv6 address; a non-loopback one is warned about when
/// the view starts) to a command that serves the view. [control]
CLI::Option* addViewBindOption(CLI::App* cmd, ViewArgs& args);
/// Adds `--view` (serve a live 3-D view in the browser; off unless given), and `--view-port
/// PORT` and `--view-bind ADDR`, which need it. `--view PORT`, the old spelling, is refused
/// naming `--view-port`. [control]
void addViewOptions(CLI::App* cmd, ViewArgs& args);

/// The width (columns) the command line wraps its text to: no line of `--help`, `--help-all`
/// or of a note under a report's row is longer, save a single word that is.
inline constexpr std::size_t kTextWidth = 100;
/// Wraps `text` at spaces into lines of at most `width` characters (a longer word stands alone
/// on its line) and starts each line after the first with `indent` spaces (not counted in
/// `width`). A newline in `text` is kept as a line break. [any thread]
std::string wrapText(std::string_view text, std::size_t width, std::size_t indent);
/// Sets `cmd`'s examples: whole command lines, shown under "Examples:" at the end of its help
/// and of its part of `--help-all`. [control]
void setExamples(CLI::App* cmd, std::initializer_list<std::string_view> lines);

/// CLI11's help layout with hapto's rules: descriptions wrapped to kTextWidth, a flag shown
/// without CLI11's `{false}`, and `--help-all` giving every command at every depth, each under
/// its whole name ("hapto scene grid") with its options and examples. Set it on the root app
/// before adding commands: they inherit it. [control]
class HelpFormatter : public CLI::Formatter {
public:
    HelpFormatter();
    std::string make_option(const CLI::Option* opt, bool isPositional) const override;
    std::string make_option_name(const CLI::Option* opt, bool isPositional) const override;
    std::string make_description(const CLI::App* app) const override;
    std::string make_subcommand(const CLI::App* sub) const override;
    std::string make_subcommands(const CLI::App* app, CLI::AppFormatMode mode) const override;
    std::string make_expanded(const CLI::App* sub) const override;
};

} // namespace hapto::cli
