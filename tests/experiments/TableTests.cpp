// hapto::experiments::Table: one column list, three forms that agree.

#include "hapto/experiments/Table.h"

#include <catch2/catch.hpp>

#include <sstream>
#include <string>
#include <vector>

using namespace hapto::experiments;

namespace {

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        out.push_back(line);
    }
    return out;
}

Table sample() {
    Table t({{"name", "", -1, "device"},
             {"rate_hz", "Hz"},
             {"ticks", ""},
             {"load_p50_pct", "%", 2},
             {"stable", ""},
             {"note", "", -1, "", ColumnIn::Data},
             {"verdict", "", -1, "verdict", ColumnIn::Markdown}});
    t.add({std::string("hand0"), 1000.0, std::int64_t{150}, 12.345678, true, std::string(""),
           std::string("stable")});
    t.add({std::string("hand, \"one\""), 4000.0, std::int64_t{600}, 0.5, false,
           std::string("line\nbreak"), std::string("UNSTABLE")});
    return t;
}

} // namespace

TEST_CASE("a table writes the same columns, in the same order, to CSV and JSON") {
    const Table t = sample();
    const std::vector<std::string> csv = lines(t.csv());
    REQUIRE(!csv.empty());
    CHECK(csv[0] == "name,rate_hz,ticks,load_p50_pct,stable,note");
    const auto j = t.json();
    REQUIRE(j.size() == 2);
    std::vector<std::string> keys;
    for (const auto& [key, value] : j[0].items()) {
        keys.push_back(key);
    }
    CHECK(keys ==
          std::vector<std::string>{"name", "rate_hz", "ticks", "load_p50_pct", "stable", "note"});
    // Typed cells: numbers stay numbers, flags are booleans in JSON and 1/0 in CSV.
    CHECK(j[0]["ticks"] == 150);
    CHECK(j[0]["rate_hz"] == 1000.0);
    CHECK(j[0]["stable"] == true);
    CHECK(j[1]["stable"] == false);
    CHECK(j[1]["note"] == "line\nbreak");
    CHECK(csv[1] == "hand0,1000,150,12.3457,1,");
    CHECK(t.json(1) == j[1]);
}

TEST_CASE("a table's markdown shows its markdown columns under their headings") {
    const std::vector<std::string> md = lines(sample().markdown());
    REQUIRE(md.size() == 4); // header, rule, two rows
    CHECK(md[0].find("| device") == 0);
    CHECK(md[0].find("rate_hz (Hz)") != std::string::npos);     // name and unit by default
    CHECK(md[0].find("load_p50_pct (%)") != std::string::npos); // the unit in brackets
    CHECK(md[0].find("verdict") != std::string::npos);          // markdown-only column
    CHECK(md[0].find("note") == std::string::npos);             // data-only column
    CHECK(md[2].find("12.35") != std::string::npos);            // two places, as declared
    CHECK(md[2].find("yes") != std::string::npos);
    CHECK(md[3].find("no") != std::string::npos);
    // Every line has the same number of cells.
    for (const std::string& line : md) {
        CHECK(std::count(line.begin(), line.end(), '|') == 7);
    }
    const std::string some = sample().markdown([](std::size_t i) { return i == 1; });
    CHECK(lines(some).size() == 3);
    CHECK(some.find("hand0") == std::string::npos);
}

TEST_CASE("CSV fields with commas, quotes or line breaks are quoted, quotes doubled") {
    CHECK(csvField("plain") == "plain");
    CHECK(csvField("a,b") == "\"a,b\"");
    CHECK(csvField("say \"hi\"") == "\"say \"\"hi\"\"\"");
    CHECK(csvField("two\nlines") == "\"two\nlines\"");
    CHECK(csvField("cr\r") == "\"cr\r\"");
    const std::string csv = sample().csv();
    CHECK(csv.find("\"hand, \"\"one\"\"\",4000,600,0.5,0,\"line\nbreak\"\n") != std::string::npos);
}

TEST_CASE("a table refuses rows of the wrong width and repeated column names") {
    Table t({{"a"}, {"b"}});
    CHECK_THROWS_AS(t.add({1.0}), std::logic_error);
    CHECK_THROWS_AS(t.add({1.0, 2.0, 3.0}), std::logic_error);
    CHECK_NOTHROW(t.add({1.0, 2.0}));
    CHECK(t.size() == 1);
    CHECK_THROWS_AS(Table({{"a"}, {"a"}}), std::logic_error);
    CHECK_THROWS_AS(Table(std::vector<Column>{}), std::logic_error);
    CHECK(t.column("b") == 1);
    CHECK_THROWS_AS(t.column("c"), std::logic_error);
}
