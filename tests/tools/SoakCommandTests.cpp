// `hapto soak` end to end, short: every kind of injected fault is handled, the report holds
// drift, misses and memory per window, and bad arguments exit 2.

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <chrono>
#include <fcntl.h>
#include <filesystem>
#include <set>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

extern char** environ;

using namespace hapto::test;
using nlohmann::json;

TEST_CASE("hapto soak injects every kind of fault, each device comes back, and the report says "
          "so",
          "[threads]") {
    TempDir dir;
    // 12 s, a fault every 0.5 s: the five kinds each at least once over three hands. The
    // watchdog is generous so a slow (sanitizer) build does not trip it by itself.
    const CommandResult r =
        runHapto("soak --minutes 0.2 --hands 3 --fault-every 0.5 --window 2 --watchdog-ms 200 "
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

TEST_CASE("hapto soak rejects bad arguments with exit 2", "[threads]") {
    for (const char* args : {"soak --minutes -1", "soak --hands 0", "soak --hands 33",
                             "soak --fault-every 0", "soak --index octree:x"}) {
        INFO(args);
        const CommandResult r = runHapto(args);
        CHECK(r.exitCode == 2);
    }
}

TEST_CASE("an interrupted soak gives no verdict: it does not print PASS and exits 1", "[threads]") {
    TempDir dir;
    const std::string exe = std::string(HAPTO_BINARY_DIR) + "/tools/hapto";
    const std::string out = (dir / "out.txt").string();
    const std::string report = (dir / "soak.json").string();
    const char* argv[] = {exe.c_str(),     "soak",     "--minutes",    "1",
                          "--fault-every", "0.5",      "--window",     "0.5",
                          "--no-realtime", "--report", report.c_str(), nullptr};
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    pid_t pid = 0;
    REQUIRE(posix_spawn(&pid, exe.c_str(), &actions, nullptr, const_cast<char**>(argv), environ) ==
            0);
    posix_spawn_file_actions_destroy(&actions);
    // The first window's line (flushed as it closes) shows the soak is under way, with its
    // signal handlers installed; wait for it (at most a minute, on a loaded machine).
    bool running = false;
    for (int i = 0; i < 600 && !running; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        running = readFile(out).find("hand0") != std::string::npos;
    }
    REQUIRE(kill(pid, SIGINT) == 0);
    int status = 0;
    REQUIRE(waitpid(pid, &status, 0) == pid);
    const std::string output = readFile(out);
    INFO(output);
    REQUIRE(running);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 1);
    CHECK_THAT(output, Catch::Contains("soak: INTERRUPTED"));
    CHECK_THAT(output, !Catch::Contains("PASS"));
    const json j = json::parse(readFile(report));
    CHECK(j["interrupted"] == true);
    CHECK(j["pass"] == false);
}

TEST_CASE("a soak too short to reach its first fault is refused before it starts", "[threads]") {
    TempDir dir;
    const CommandResult r =
        runHapto("soak --minutes 0.05 --fault-every 15 --no-realtime --report " +
                 (dir / "soak.json").string());
    INFO(r.output);
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("--minutes") && Catch::Contains("first fault"));
    CHECK_FALSE(std::filesystem::exists(dir / "soak.json"));
}
