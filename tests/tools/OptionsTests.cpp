// The command line's conventions (tools/src/Options.h), in process: the checks numeric options
// go through (finiteRange, positiveRange, wholeNumber), the shared options (realtime, the view,
// renamed ones) and the help layout (wrapText, HelpFormatter, examples).

#include "Options.h"
#include "TestSupport.h"
#include "hapto/io/InputError.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

using namespace hapto::cli;

namespace {

/// Parses `--x VALUE` into a double option checked by finiteRange(lo, hi); the error or "".
template <class T> std::string parse(const std::string& value, double lo, double hi) {
    CLI::App app;
    T x{};
    app.add_option("--x", x)->check(finiteRange(lo, hi));
    std::vector<std::string> args{value, "--x"}; // CLI11 takes them in reverse
    try {
        app.parse(args);
    } catch (const CLI::ParseError& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST_CASE("finiteRange refuses NaN, infinities, text and values out of range, naming them") {
    for (const char* bad : {"nan", "NaN", "-nan", "inf", "-inf", "infinity", "1e400"}) {
        INFO(bad);
        const std::string error = parse<double>(bad, 0, 10);
        CHECK_THAT(error, Catch::Contains("--x") && Catch::Contains(bad) &&
                              Catch::Contains("from 0 to 10"));
    }
    CHECK_THAT(parse<double>("ten", 0, 10), Catch::Contains("not a number"));
    CHECK_THAT(parse<double>("10.5", 0, 10), Catch::Contains("out of range"));
    CHECK_THAT(parse<double>("-0.1", 0, 10), Catch::Contains("out of range"));
    CHECK(parse<double>("0", 0, 10).empty());
    CHECK(parse<double>("10", 0, 10).empty());
    CHECK(parse<double>("2.5e0", 0, 10).empty());
}

TEST_CASE("finiteRange on integer options also catches negatives an unsigned option would wrap") {
    CHECK_THAT(parse<std::uint64_t>("-1", 0, kMaxSeed), Catch::Contains("out of range"));
    CHECK(parse<std::uint64_t>("18446744073709551615", 0, kMaxSeed).empty());
    CHECK_THAT(parse<int>("nan", 1, 32), Catch::Contains("--x"));
    CHECK_THAT(parse<int>("33", 1, 32), Catch::Contains("from 1 to 32"));
    CHECK(parse<int>("32", 1, 32).empty());
}

namespace {

/// Parses `args` (in order) with a fresh app holding `--n` (a std::size_t read through
/// wholeNumber) and `--list` (a comma-delimited std::vector<std::size_t>); the error or "".
std::string parseWhole(std::vector<std::string> args, std::size_t& n,
                       std::vector<std::size_t>& list) {
    CLI::App app;
    app.add_option("--n", n)->transform(wholeNumber(1, 1e8));
    app.add_option("--list", list)->delimiter(',')->transform(wholeNumber(1, 1e8));
    std::reverse(args.begin(), args.end()); // CLI11 takes them in reverse
    try {
        app.parse(args);
    } catch (const CLI::ParseError& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST_CASE("wholeNumber reads counts as numbers, with or without an exponent") {
    std::size_t n = 0;
    std::vector<std::size_t> list;
    CHECK(parseWhole({"--n", "2e5"}, n, list).empty());
    CHECK(n == 200000);
    CHECK(parseWhole({"--n", "1000"}, n, list).empty());
    CHECK(n == 1000);
    CHECK(parseWhole({"--list", "10,20,1e3"}, n, list).empty());
    CHECK(list == std::vector<std::size_t>{10, 20, 1000});
    CHECK_THAT(parseWhole({"--n", "0"}, n, list), Catch::Contains("out of range"));
    CHECK_THAT(parseWhole({"--n", "2.5"}, n, list), Catch::Contains("not a whole number"));
    CHECK_THAT(parseWhole({"--n", "nan"}, n, list), Catch::Contains("--n"));
    CHECK_THAT(parseWhole({"--n", "1e9"}, n, list), Catch::Contains("from 1 to 100000000"));
    CHECK_THAT(parseWhole({"--list", "10,0"}, n, list), Catch::Contains("--list"));
    // CLI11's list syntax skips empty items.
    CHECK(parseWhole({"--list", "10,,20"}, n, list).empty());
    CHECK(list == std::vector<std::size_t>{10, 20});
    CHECK_THAT(parseWhole({"--list", "10,x"}, n, list), Catch::Contains("not a number"));
}

TEST_CASE("positiveRange refuses 0 and says so in the range it shows") {
    const auto parsePositive = [](const std::string& value) -> std::string {
        CLI::App app;
        double x = 1.0;
        app.add_option("--x", x)->check(positiveRange(10));
        std::vector<std::string> args{value, "--x"}; // CLI11 takes them in reverse
        try {
            app.parse(args);
        } catch (const CLI::ParseError& e) {
            return e.what();
        }
        return "";
    };
    CHECK_THAT(parsePositive("0"),
               Catch::Contains("out of range") && Catch::Contains("above 0 and at most 10"));
    CHECK_THAT(parsePositive("-1"), Catch::Contains("out of range"));
    CHECK_THAT(parsePositive("nan"), Catch::Contains("not a finite number"));
    CHECK_THAT(parsePositive("11"), Catch::Contains("out of range"));
    CHECK(parsePositive("1e-9").empty());
    CHECK(parsePositive("10").empty());
    CHECK(positiveRange(10).get_description() == "in (0, 10]");
    CHECK(finiteRange(0, 10).get_description() == "in [0, 10]");
}

TEST_CASE("wrapText breaks at spaces within the width and indents the lines after the first") {
    CHECK(wrapText("one two three four", 9, 2) == "one two\n  three\n  four");
    CHECK(wrapText("short", 80, 4) == "short");
    // A word longer than the width stands alone; a newline is kept, with the indent.
    CHECK(wrapText("a verylongword b", 5, 0) == "a\nverylongword\nb");
    CHECK(wrapText("first\nsecond line", 80, 3) == "first\n   second line");
    // A line's own leading spaces (an example's indent) start each of its pieces.
    CHECK(wrapText("  aa bb cc", 7, 0) == "  aa bb\n  cc");
}

namespace {

/// The help of `app` laid out by HelpFormatter, as `--help` (or, with `all`, `--help-all`)
/// prints it.
std::string helpOf(CLI::App& app, bool all = false) {
    return app.help("", all ? CLI::AppFormatMode::All : CLI::AppFormatMode::Normal);
}

} // namespace

TEST_CASE("HelpFormatter: --help-all gives every command at every depth, wrapped, with examples") {
    CLI::App app("A tool.", "tool");
    app.formatter(std::make_shared<HelpFormatter>());
    app.set_help_all_flag("--help-all", "Everything");
    CLI::App* group = app.add_subcommand("group", "A group of commands");
    CLI::App* leaf = group->add_subcommand("leaf", "A command two levels down");
    double depth = 1.0;
    leaf->add_option("--deep-option", depth,
                     std::string(40, 'a') + " " + std::string(40, 'b') + " " +
                         std::string(40, 'c') + " " + std::string(40, 'd'));
    setExamples(leaf, {"tool group leaf --deep-option 2"});
    const std::string all = helpOf(app, true);
    INFO(all);
    // CLI11 by itself lists `leaf` under `group` by name only.
    CHECK_THAT(all, Catch::Contains("\ntool group leaf\n"));
    CHECK_THAT(all, Catch::Contains("--deep-option FLOAT"));
    CHECK_THAT(all, Catch::Contains("Examples:\n  tool group leaf --deep-option 2"));
    for (const std::string& line : hapto::test::linesOf(all)) {
        INFO(line);
        CHECK(line.size() <= kTextWidth);
    }
    // A command's own help wraps the same way.
    for (const std::string& line : hapto::test::linesOf(helpOf(*leaf))) {
        CHECK(line.size() <= kTextWidth);
    }
}

TEST_CASE("the realtime flag's help names its default in words, not as CLI11's flag value") {
    for (const bool asks : {true, false}) {
        CLI::App app;
        app.formatter(std::make_shared<HelpFormatter>());
        bool realtime = asks;
        addRealtimeFlag(&app, realtime, "");
        const std::string help = helpOf(app);
        INFO(help);
        CHECK_THAT(help, Catch::Contains("--realtime,--no-realtime") && !Catch::Contains("{"));
        CHECK_THAT(help, Catch::Contains(asks ? "Default: ask" : "Default: do not"));
    }
}

TEST_CASE("a renamed option is refused naming its new spelling, whatever it is given") {
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"hands.json", "--devices"}, {"3", "--devices"}, {"--devices"}}) {
        CLI::App app;
        int hands = 2;
        app.add_option("--hands", hands);
        addRenamedOption(&app, "--devices", "--hands N", "a device file elsewhere");
        std::vector<std::string> reversed = args;
        std::string error;
        try {
            app.parse(reversed);
        } catch (const CLI::ParseError& e) {
            error = e.what();
        }
        CHECK_THAT(error, Catch::Contains("--devices") && Catch::Contains("use --hands N"));
    }
}

TEST_CASE("the view's options: --view serves it, --view-port and --view-bind need --view") {
    const auto parseView = [](std::vector<std::string> args, ViewArgs& view) -> std::string {
        CLI::App app;
        addViewOptions(&app, view);
        std::reverse(args.begin(), args.end()); // CLI11 takes them in reverse
        try {
            app.parse(args);
        } catch (const CLI::ParseError& e) {
            return e.what();
        }
        return "";
    };
    ViewArgs off;
    CHECK(parseView({}, off).empty());
    CHECK_FALSE(off.enabled);
    ViewArgs on;
    CHECK(parseView({"--view"}, on).empty());
    CHECK(on.enabled);
    CHECK(on.port == kDefaultViewPort);
    ViewArgs any;
    CHECK(parseView({"--view", "--view-port", "0"}, any).empty());
    CHECK((any.enabled && any.port == 0));
    ViewArgs old; // the old spelling is refused, naming the new one
    CHECK_THAT(parseView({"--view", "0"}, old), Catch::Contains("--view-port 0"));
    CHECK_FALSE(old.enabled);
    ViewArgs alone;
    CHECK_THAT(parseView({"--view-port", "0"}, alone), Catch::Contains("--view"));
    CHECK_THAT(parseView({"--view", "--view-port", "70000"}, alone),
               Catch::Contains("--view-port"));
    CHECK_THAT(parseView({"--view", "nan"}, alone), Catch::Contains("--view"));
    // Its help does not read as if the view were on by default.
    CLI::App app;
    app.formatter(std::make_shared<HelpFormatter>());
    ViewArgs shown;
    addViewOptions(&app, shown);
    const std::string help = helpOf(app);
    INFO(help);
    CHECK_THAT(help, Catch::Contains("--view-port PORT") && Catch::Contains("=8340") &&
                         !Catch::Contains("--view INT") && !Catch::Contains("--view :"));
}

TEST_CASE("the realtime flag takes --realtime and --no-realtime") {
    for (const auto& [args, expected] : std::vector<std::pair<std::vector<std::string>, bool>>{
             {{}, true}, {{"--no-realtime"}, false}, {{"--realtime"}, true}}) {
        CLI::App app;
        bool realtime = true;
        addRealtimeFlag(&app, realtime, "");
        std::vector<std::string> reversed(args.rbegin(), args.rend());
        app.parse(reversed);
        CHECK(realtime == expected);
    }
}

TEST_CASE("a number list option takes exactly its count of finite numbers in range") {
    const auto parseList = [](const std::string& value, std::vector<double>& v) -> std::string {
        CLI::App app;
        addNumberListOption(&app, "--center", v, 3, -10, 10, "x,y,z");
        std::vector<std::string> args{value, "--center"}; // CLI11 takes them in reverse
        try {
            app.parse(args);
        } catch (const CLI::ParseError& e) {
            return e.what();
        }
        return "";
    };
    std::vector<double> v{0, 0, 0};
    CHECK(parseList("1,-2.5,3e0", v).empty());
    CHECK(v == std::vector<double>{1, -2.5, 3});
    for (const char* bad : {"1,2", "1,2,3,4", "1,nan,3", "1,inf,3", "1,x,3", "1,2,11"}) {
        INFO(bad);
        std::vector<double> w{0, 0, 0};
        CHECK_THAT(parseList(bad, w), Catch::Contains("--center"));
    }
}
