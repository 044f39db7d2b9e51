// The surface a newcomer meets: `hapto --version`, an unknown command named as unknown, the
// help (every command at every depth, wrapped, with examples), and the option conventions
// (--rates with --rate kept, --duration in seconds with soak's --minutes kept, --realtime and
// --no-realtime everywhere, counts as numbers, one name for one thing).

#include "TestSupport.h"

#include "hapto/Version.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <deque>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

using namespace hapto;

namespace {

/// The commands `help` (a `--help` text) lists under "Subcommands:".
std::vector<std::string> commandsIn(const std::string& help) {
    std::vector<std::string> names;
    bool in = false;
    for (const std::string& line : test::linesOf(help)) {
        if (line == "Subcommands:") {
            in = true;
        } else if (in && line.empty()) {
            break;
        } else if (in && line.size() > 2 && line.rfind("  ", 0) == 0 && line[2] != ' ') {
            names.push_back(line.substr(2, line.find(' ', 2) - 2));
        }
    }
    return names;
}

/// The option names of `help` (a `--help` text): the first word of each option line, such as
/// "--per-side" or "-o,--output", help flags left out.
std::vector<std::string> optionsIn(const std::string& help) {
    std::vector<std::string> names;
    for (const std::string& line : test::linesOf(help)) {
        if (line.rfind("  -", 0) == 0) {
            const std::string name = line.substr(2, line.find(' ', 2) - 2);
            if (name != "-h,--help" && name != "--help-all") {
                names.push_back(name);
            }
        }
    }
    return names;
}

/// The line of `help` that starts with `option` (after its indent), or "".
std::string optionLine(const std::string& help, const std::string& option) {
    for (const std::string& line : test::linesOf(help)) {
        if (line.rfind("  " + option + " ", 0) == 0) {
            return line;
        }
    }
    return "";
}

} // namespace

TEST_CASE("hapto --version prints the project's version") {
    const auto r = test::runHapto("--version");
    INFO(r.output);
    CHECK(r.exitCode == 0);
    CHECK(r.output.find(std::string("hapto ") + HAPTO_VERSION_STRING) != std::string::npos);
}

TEST_CASE("an unknown command is named as unknown, exit 2") {
    const auto r = test::runHapto("frobnicate");
    INFO(r.output);
    CHECK(r.exitCode == 2);
    CHECK(r.output.find("hapto: unknown command 'frobnicate'; see hapto --help") !=
          std::string::npos);
    // A known command still runs, and an unknown option is still CLI11's message.
    CHECK(test::runHapto("scene default -o -").exitCode == 0);
    CHECK(test::runHapto("--frobnicate").exitCode == 2);
}

TEST_CASE("options follow one convention, the old spellings still work", "[threads]") {
    test::TempDir dir;
    const std::string out = " --out " + dir.path().string();
    // --rates, and --rate as its old spelling, on every experiment; numbers as numbers.
    for (const std::string args : {
             "experiment scaling --quick --no-cursor --max-devices 1 --rates 1000",
             "experiment scaling --quick --no-cursor --max-devices 1 --rate 1000 --realtime",
             "experiment scaling --quick --max-devices 1 --cursor-objects 1e2 --walk-steps 2e3",
         }) {
        const auto r = test::runHapto(args + out + " --no-realtime");
        INFO(args << "\n" << r.output);
        CHECK(r.exitCode == 0);
    }
    // Counts refused as counts: a fraction, zero where one is needed, a fraction in a list.
    for (const std::string args : {
             "experiment scaling --quick --walk-steps 2.5",
             "experiment paper2 --quick --counts 10,2.5",
             "bench query --steps 0",
             "scene random --count 1.5 -o -",
         }) {
        const auto r = test::runHapto(args + (args.rfind("experiment", 0) == 0 ? out : ""));
        INFO(args << "\n" << r.output);
        CHECK(r.exitCode == 2);
    }
    // Soak: --duration in seconds, --minutes kept; not both.
    const auto both = test::runHapto("soak --duration 60 --minutes 1 --no-realtime");
    INFO(both.output);
    CHECK(both.exitCode == 2);
    const auto tooShort = test::runHapto("soak --duration 2 --no-realtime");
    CHECK(tooShort.exitCode == 2);
    CHECK(tooShort.output.find("--duration 2") != std::string::npos);
    const auto tooShortMinutes = test::runHapto("soak --minutes 0.02 --no-realtime");
    CHECK(tooShortMinutes.exitCode == 2);
    CHECK(tooShortMinutes.output.find("--minutes 0.02") != std::string::npos);
}

TEST_CASE("hapto --help-all gives every command's options at every depth, each command has "
          "examples, and no help line is wider than 100 columns") {
    const auto all = test::runHapto("--help-all");
    REQUIRE(all.exitCode == 0);
    std::deque<std::string> todo;
    for (const std::string& name : commandsIn(test::runHapto("--help").output)) {
        todo.push_back(name);
    }
    int commands = 0;
    int options = 0;
    while (!todo.empty()) {
        const std::string path = todo.front();
        todo.pop_front();
        const auto help = test::runHapto(path + " --help");
        INFO("hapto " << path << " --help\n" << help.output);
        REQUIRE(help.exitCode == 0);
        ++commands;
        for (const std::string& name : commandsIn(help.output)) {
            todo.push_back(path + " " + name);
        }
        CHECK_THAT(help.output, Catch::Contains("\nExamples:\n  hapto " + path));
        for (const std::string& line : test::linesOf(help.output)) {
            CHECK(line.size() <= 100);
        }
        // Its part of --help-all: from its heading to the next command's.
        const std::size_t start = all.output.find("\nhapto " + path + "\n");
        REQUIRE(start != std::string::npos);
        const std::string part =
            all.output.substr(start, all.output.find("\nhapto ", start + 1) - start);
        for (const std::string& option : optionsIn(help.output)) {
            INFO(option);
            CHECK_THAT(part, Catch::Contains("\n  " + option + " ") ||
                                 Catch::Contains("\n  " + option + "\n"));
            ++options;
        }
        CHECK_THAT(part, Catch::Contains("Examples:"));
    }
    CHECK(commands >= 30); // scene grid ... view; CLI11 alone listed 12 with their options
    CHECK(options >= 150);
    for (const std::string& line : test::linesOf(all.output)) {
        INFO(line);
        CHECK(line.size() <= 100);
    }
    // A renamed command is no command of its own in the help.
    CHECK_THAT(all.output, !Catch::Contains("hapto experiment devices"));
}

TEST_CASE("the help says what an option does by default: realtime, the view, the ranges") {
    const std::string run = test::runHapto("run --help").output;
    const std::string demo = test::runHapto("demo grasp --help").output;
    INFO(run << demo);
    // --realtime: the default in words, not CLI11's {false}.
    CHECK_THAT(run, !Catch::Contains("{false}") && Catch::Contains("Default: ask"));
    CHECK_THAT(demo, !Catch::Contains("{false}") && Catch::Contains("Default: do not"));
    // --view is off unless given; its port is --view-port, as in `hapto view`.
    CHECK_THAT(optionLine(run, "--view"), !Catch::Contains("8340"));
    CHECK_THAT(optionLine(run, "--view-port"), Catch::Contains("=8340"));
    CHECK_THAT(optionLine(demo, "--view-port"), Catch::Contains("=8340"));
    const std::string view = test::runHapto("view --help").output;
    CHECK_THAT(optionLine(view, "--view-port"), Catch::Contains("=8340"));
    CHECK(optionLine(view, "--port").empty());
    // A scale and a stiffness above 0: the range says so.
    const std::string import = test::runHapto("scene import --help").output;
    CHECK_THAT(optionLine(import, "--scale"), Catch::Contains("in (0, "));
    CHECK_THAT(optionLine(import, "--stiffness"), Catch::Contains("in (0, "));
    // One reopen default for run and soak.
    const std::string soak = test::runHapto("soak --help").output;
    const std::string runReopen = optionLine(run, "--reopen-ms");
    const std::string soakReopen = optionLine(soak, "--reopen-ms");
    REQUIRE(runReopen.find('=') != std::string::npos);
    REQUIRE(soakReopen.find('=') != std::string::npos);
    CHECK(runReopen.substr(runReopen.find('=')) == soakReopen.substr(soakReopen.find('=')));
}

TEST_CASE("one name, one meaning: a renamed option or command is refused naming the new one",
          "[realtime]") {
    test::TempDir dir;
    for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
             {"soak --devices hands.json --no-realtime", "use --hands N"},
             {"soak --devices 3 --no-realtime", "use --hands N"},
             {"view --trace t.trace --port 0 --duration 1", "use --view-port PORT"},
             {"experiment devices --quick --out " + dir.path().string(),
              "`hapto experiment devices` is renamed `hapto experiment scaling`"},
             {"run --view-port 0 --duration 0.1 --no-realtime --quiet", "requires --view"},
         }) {
        const auto r = test::runHapto(args);
        INFO(args << "\n" << r.output);
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains(expected));
    }
    CHECK(std::filesystem::is_empty(dir.path()));
    // The new spellings run.
    const auto soak = test::runHapto("soak --hands 0 --no-realtime");
    CHECK(soak.exitCode == 2);
    CHECK_THAT(soak.output, Catch::Contains("--hands"));
    const auto run =
        test::runHapto("run --view --view-port 0 --duration 0.2 --no-realtime --quiet");
    INFO(run.output);
    // Accepted and run: not refused (2). Its verdict (0, or 1 when a loaded machine stalls a
    // servo thread past the watchdog, as under a sanitizer beside a build) is the wall
    // clock's, not the spelling's.
    CHECK(run.exitCode != 2);
    CHECK_THAT(run.output, Catch::Contains("hapto run: 2 devices"));
    CHECK_THAT(run.output, Catch::Contains("http://127.0.0.1:"));
}
