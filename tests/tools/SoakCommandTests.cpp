// `hapto soak` end to end, short: every kind of injected fault is handled, the report holds
// drift, misses and memory per window, and bad arguments exit 2.

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <set>

using namespace hapto::test;
using nlohmann::json;

TEST_CASE("hapto soak injects every kind of fault, each device comes back, and the report says "
          "so") {
    TempDir dir;
    // 12 s, a fault every 0.5 s: the five kinds each at least once over three hands. The
    // watchdog is generous so a slow (sanitizer) build does not trip it by itself.
    const CommandResult r =
        runHapto("soak --minutes 0.2 --devices 3 --fault-every 0.5 --window 2 --watchdog-ms 200 "
                 "--reopen-ms 50 --no-realtime --memory-tolerance 64 --report " +
                 (dir / "soak.json").string());
    INFO(r.output);
    CHECK(r.exitCode == 0);
    CHECK_THAT(r.output, Catch::Contains("soak: PASS"));
    const json j = json::parse(readFile(dir / "soak.json"));
    CHECK(j["pass"] == true);
    CHECK(j["faults_ok"] == true);
    CHECK(j["faults_injected"].get<int>() >= 10);
    REQUIRE(j["devices"].size() == 3);
    std::set<std::string> kinds;
    int faults = 0;
    for (const json& d : j["devices"]) {
        INFO(d.dump(2));
        CHECK(d["ok"] == true);
        CHECK(d["fault"] == "");
        CHECK(d["faults"] == d["faults_expected"]);
        CHECK(d["reopens"] == d["faults"]);
        CHECK(d["ticks"].get<int>() > 1000);
        faults += d["faults"].get<int>();
        for (const json& e : d["events"]) {
            const std::string text = e.get<std::string>();
            for (const char* k : {"disconnected", "bad-data", "watchdog", "read-failed: error"}) {
                if (text.find(k) != std::string::npos) {
                    kinds.insert(k);
                }
            }
            if (text.find("force zeroed") == std::string::npos &&
                text.find("reopen") == std::string::npos) {
                FAIL("unexpected event: " << text);
            }
        }
    }
    CHECK(faults >= 8);
    CHECK(kinds.size() == 4); // every kind that is a fault was seen
    CHECK(j["windows"].size() >= 5);
    for (const json& w : j["windows"]) {
        CHECK(w["rss_mib"].get<double>() > 0.0);
        REQUIRE(w["devices"].size() == 3);
    }
    CHECK(j["world"]["updates"].get<int>() > 100);
    CHECK(j["world"]["unfreed_snapshots"] == 0);
    CHECK(j["memory"].contains("growth_mib"));
}

TEST_CASE("hapto soak rejects bad arguments with exit 2") {
    for (const char* args : {"soak --minutes -1", "soak --devices 0", "soak --fault-every 0",
                             "soak --index octree:x"}) {
        INFO(args);
        const CommandResult r = runHapto(args);
        CHECK(r.exitCode == 2);
    }
}
