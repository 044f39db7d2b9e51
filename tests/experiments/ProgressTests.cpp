// The progress bar: drawn on its stream, erased before results print.

#include "hapto/experiments/Progress.h"

#include <catch2/catch.hpp>

#include <cstdio>
#include <string>

using namespace hapto::experiments;

namespace {

std::string contents(std::FILE* f) {
    std::fflush(f);
    std::rewind(f);
    std::string text;
    for (int c = std::fgetc(f); c != EOF; c = std::fgetc(f)) {
        text += static_cast<char>(c);
    }
    return text;
}

} // namespace

TEST_CASE("finish() erases the bar, and nothing is drawn after it") {
    std::FILE* f = std::tmpfile();
    REQUIRE(f);
    {
        Progress p("devices", 4, f, true);
        p.advance(1, "1 device at 1 kHz");
        p.finish();
        const std::string afterFinish = contents(f);
        CHECK(afterFinish.find("devices [") != std::string::npos);
        // The last thing written returns to the line's start and clears it.
        const std::string erase = "\r\x1b[2K";
        REQUIRE(afterFinish.size() >= erase.size());
        CHECK(afterFinish.substr(afterFinish.size() - erase.size()) == erase);
        std::fseek(f, 0, SEEK_END);
        p.advance(3, "more");
        p.note("a note still prints");
        CHECK(contents(f) == afterFinish + "a note still prints\n");
    }
    std::fclose(f);
}

TEST_CASE("a disabled bar (not a terminal) writes only notes") {
    std::FILE* f = std::tmpfile();
    REQUIRE(f);
    {
        Progress p("paper1", 2, f, false);
        p.advance(1, "x");
        p.note("plot skipped");
        p.finish();
    }
    CHECK(contents(f) == "plot skipped\n");
    std::fclose(f);
}
