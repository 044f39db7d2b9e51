// The command line's shared conventions: numeric checks, shared options, the help layout.

#include "Options.h"

#include "hapto/io/InputError.h"

#include <arpa/inet.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>

namespace hapto::cli {
namespace {

std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.15g", v);
    return text;
}

// A number from `lo` (or, when `loOpen`, above it) to `hi`; finiteRange and positiveRange.
CLI::Validator numberRange(double lo, bool loOpen, double hi) {
    const std::string range = loOpen ? "above " + number(lo) + " and at most " + number(hi)
                                     : "from " + number(lo) + " to " + number(hi);
    return CLI::Validator(
        [lo, loOpen, hi, range](std::string& text) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(text, v)) {
                return "'" + text + "' is not a number; expected a number " + range;
            }
            if (!std::isfinite(v)) {
                return "'" + text + "' is not a finite number; expected a number " + range;
            }
            if (v < lo || (loOpen && v == lo) || v > hi) {
                return text + " is out of range; expected a number " + range;
            }
            return {};
        },
        (loOpen ? "in (" : "in [") + number(lo) + ", " + number(hi) + "]", "FINITE_RANGE");
}

} // namespace

CLI::Validator finiteRange(double lo, double hi) {
    return numberRange(lo, false, hi);
}

CLI::Validator positiveRange(double hi) {
    return numberRange(0.0, true, hi);
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

CLI::Option* addRealtimeFlag(CLI::App* cmd, bool& realtime, const std::string& why) {
    return cmd->add_flag("--realtime,!--no-realtime", realtime,
                         std::string("--realtime: ask for SCHED_FIFO and CPU pinning (when "
                                     "refused, the session runs at normal priority and says "
                                     "so); --no-realtime: do not. Default: ") +
                             (realtime ? "ask" : "do not") + (why.empty() ? "" : ", " + why));
}

CLI::Option* addRenamedOption(CLI::App* cmd, const std::string& oldName,
                              const std::string& newSpelling, const std::string& why) {
    const std::string message =
        "renamed; use " + newSpelling + (why.empty() ? "" : " (" + why + ")");
    return cmd
        ->add_option_function<std::string>(oldName,
                                           [oldName, message](const std::string&) {
                                               throw CLI::ValidationError(oldName, message);
                                           })
        ->expected(0, 1)
        ->group(""); // hidden from the help
}

CLI::App* addRenamedCommand(CLI::App* parent, const std::string& oldName,
                            const std::string& newSpelling) {
    std::string oldPath = oldName;
    for (const CLI::App* p = parent; p != nullptr; p = p->get_parent()) {
        oldPath = p->get_name() + " " + oldPath;
    }
    CLI::App* cmd = parent->add_subcommand(oldName, "Renamed: " + newSpelling);
    cmd->group(""); // hidden from the help
    cmd->allow_extras();
    cmd->callback([oldPath, newSpelling] {
        throw InputError("`" + oldPath + "` is renamed `" + newSpelling + "`");
    });
    return cmd;
}

CLI::Option* addIndexOption(CLI::App* cmd, std::string& spec) {
    return cmd->add_option("--index", spec,
                           "Spatial index: brute, grid:N, octree:M:MIN (MIN in m), optional "
                           ":aabb. Default: " +
                               std::string(kDefaultIndexSpec) +
                               "; over meshes octree:" + std::to_string(kMeshIndexLeafItems) +
                               ":E, E the median triangle's longest edge (m, within " +
                               number(kMeshIndexMinLeafM) + "-" + number(kMeshIndexMaxLeafM) + ")");
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

CLI::Option* addViewPortOption(CLI::App* cmd, ViewArgs& args) {
    return cmd
        ->add_option("--view-port", args.port, "TCP port the view listens on; 0 takes any free one")
        ->type_name("PORT")
        ->capture_default_str()
        ->check(finiteRange(0, 65535));
}

CLI::Option* addViewBindOption(CLI::App* cmd, ViewArgs& args) {
    return cmd
        ->add_option("--view-bind", args.bindAddress,
                     "Address the view listens on (default 127.0.0.1, this machine only; "
                     "another address lets anyone who reaches it watch, read-only)")
        ->type_name("ADDR")
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
    // `--view PORT` was the old spelling of `--view --view-port PORT`: one spelling now, so a
    // value after --view is refused with the new spelling (exit 2), never taken silently.
    auto* view = cmd->add_option_function<std::string>(
                        "--view",
                        [&args](const std::string& port) {
                            if (!port.empty()) {
                                throw CLI::ValidationError(
                                    "--view", "takes no value; the port is --view-port " + port);
                            }
                            args.enabled = true;
                        },
                        "Serve a live 3-D view of the session in the browser (off unless given), "
                        "on http://127.0.0.1:" +
                            std::to_string(kDefaultViewPort) +
                            "/ unless --view-port or --view-bind say otherwise")
                     ->expected(0, 1)
                     ->type_name("");
    addViewPortOption(cmd, args)->needs(view);
    addViewBindOption(cmd, args)->needs(view);
}

namespace {

/// `left` padded to `column`, then `text` wrapped in the column after it (on the next line
/// when `left` reaches into it).
std::string twoColumns(const std::string& left, const std::string& text, std::size_t column) {
    std::string out = left;
    if (!text.empty()) {
        if (left.size() + 1 > column) {
            out += "\n" + std::string(column, ' ');
        } else {
            out.append(column - left.size(), ' ');
        }
        out += wrapText(text, kTextWidth - column, column);
    }
    return out + "\n";
}

} // namespace

std::string wrapText(std::string_view text, std::size_t width, std::size_t indent) {
    const std::string newline = "\n" + std::string(indent, ' ');
    std::string out;
    for (std::size_t start = 0;;) {
        const std::size_t end = text.find('\n', start);
        const std::string_view line =
            text.substr(start, end == std::string_view::npos ? end : end - start);
        // A line's own leading spaces (an example's indent) start each of its pieces.
        const std::size_t lead = std::min(line.find_first_not_of(' '), line.size());
        out.append(lead, ' ');
        std::size_t length = lead;
        for (std::size_t w = lead; w < line.size();) {
            const std::size_t wordEnd = std::min(line.find(' ', w), line.size());
            if (wordEnd > w) {
                const std::size_t wordLength = wordEnd - w;
                if (length > lead && length + 1 + wordLength > width) {
                    out += newline;
                    out.append(lead, ' ');
                    length = lead;
                } else if (length > lead) {
                    out += ' ';
                    ++length;
                }
                out.append(line.substr(w, wordLength));
                length += wordLength;
            }
            w = wordEnd + 1;
        }
        if (end == std::string_view::npos) {
            return out;
        }
        out += newline;
        start = end + 1;
    }
}

void setExamples(CLI::App* cmd, std::initializer_list<std::string_view> lines) {
    std::string footer = "Examples:";
    for (const std::string_view line : lines) {
        footer += "\n  ";
        footer += line;
    }
    cmd->footer(footer);
}

HelpFormatter::HelpFormatter() {
    column_width(30);
}

std::string HelpFormatter::make_option(const CLI::Option* opt, bool isPositional) const {
    return twoColumns("  " + make_option_name(opt, isPositional) + make_option_opts(opt),
                      make_option_desc(opt), column_width_);
}

std::string HelpFormatter::make_option_name(const CLI::Option* opt, bool isPositional) const {
    // CLI11 shows a negated flag's value ("--no-realtime{false}"), which reads as a default.
    std::string name = CLI::Formatter::make_option_name(opt, isPositional);
    for (std::size_t open = name.find('{'); open != std::string::npos; open = name.find('{')) {
        const std::size_t close = name.find('}', open);
        if (close == std::string::npos) {
            break;
        }
        name.erase(open, close - open + 1);
    }
    return name;
}

std::string HelpFormatter::make_description(const CLI::App* app) const {
    std::string text = CLI::Formatter::make_description(app);
    if (text.empty()) {
        return text;
    }
    text.pop_back(); // CLI11's closing newline
    return wrapText(text, kTextWidth, 0) + "\n";
}

std::string HelpFormatter::make_subcommand(const CLI::App* sub) const {
    return twoColumns("  " + sub->get_display_name(true), sub->get_description(), column_width_);
}

std::string HelpFormatter::make_subcommands(const CLI::App* app, CLI::AppFormatMode mode) const {
    if (mode == CLI::AppFormatMode::Normal) {
        return CLI::Formatter::make_subcommands(app, mode);
    }
    // --help-all: every command in full, at every depth (CLI11 expands one level only).
    std::string out;
    for (const CLI::App* sub : app->get_subcommands({})) {
        if (!sub->get_name().empty() && !sub->get_group().empty()) { // not hidden
            out += "\n" + make_expanded(sub);
        }
    }
    return out;
}

std::string HelpFormatter::make_expanded(const CLI::App* sub) const {
    if (sub->get_name().empty()) { // an option group
        return CLI::Formatter::make_expanded(sub);
    }
    std::string path = sub->get_name();
    for (const CLI::App* p = sub->get_parent(); p != nullptr; p = p->get_parent()) {
        path = p->get_name() + " " + path;
    }
    std::string out = path + "\n" + make_description(sub) + make_positionals(sub) +
                      make_groups(sub, CLI::AppFormatMode::Sub);
    if (const std::string footer = make_footer(sub); !footer.empty()) {
        out += "\n" + footer;
    }
    return out + make_subcommands(sub, CLI::AppFormatMode::Sub);
}

} // namespace hapto::cli
