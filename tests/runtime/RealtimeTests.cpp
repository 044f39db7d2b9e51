// rt::WakeLatencyHold: the CPU latency request a session may hold while its servo threads run.
// Facts about the kernel's side are from Documentation/power/pm_qos_interface.rst ("From user
// space"): holding /dev/cpu_dma_latency open registers a request; an s32 written to it is the
// request's value (us); closing it removes the request; the value in force is the minimum of
// all requests (2000 s when there is none), and reading the file returns that value.

#include "CubeScene.h"
#include "ScriptedDevice.h"

#include "hapto/index/DefaultIndex.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/Runtime.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include <cstring>
#include <fstream>
#include <optional>
#include <unistd.h>

using namespace hapto;

namespace {

/// The s32 at the start of a file, if it has four bytes.
std::optional<std::int32_t> readS32(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::int32_t v = 0;
    if (!in.read(reinterpret_cast<char*>(&v), sizeof v)) {
        return std::nullopt;
    }
    return v;
}

const std::string kQos(rt::WakeLatencyHold::kDefaultPath);

/// The kernel's interface is there and this process may write to it (root).
bool canHold() {
    return ::access(kQos.c_str(), W_OK) == 0;
}

/// One scripted hand pressing into the cube, on its own servo thread, under `options`
/// (normal scheduling).
struct OneHand {
    World world{test::cubeScene(), IndexSpec::parse(kDefaultIndexSpec)};
    std::unique_ptr<Runtime> runtime;

    explicit OneHand(RuntimeOptions options) {
        std::vector<RuntimeDevice> rds;
        rds.push_back({std::make_unique<test::ScriptedDevice>("d0", test::pressIntoCube(0.0)),
                       test::scriptedConfig(0, 1000.0), nullptr});
        options.realtime = false;
        runtime = std::make_unique<Runtime>(world, std::move(rds), options);
    }
};

} // namespace

TEST_CASE("a wake-latency hold writes its request as an s32 and names what failed") {
    test::TempDir dir;
    const std::string file = (dir / "qos").string();
    test::writeFile(file, "");
    SECTION("held") {
        rt::WakeLatencyHold hold(25, file);
        CHECK(hold.held());
        CHECK(hold.us() == 25);
        CHECK(hold.note().empty());
        CHECK(readS32(file) == std::optional<std::int32_t>(25));
        rt::WakeLatencyHold moved(std::move(hold));
        CHECK(moved.held());
        CHECK_FALSE(hold.held()); // NOLINT: the moved-from hold holds nothing
        moved = rt::WakeLatencyHold();
        CHECK_FALSE(moved.held());
    }
    SECTION("a file that cannot be opened") {
        const std::string missing = (dir / "no" / "such").string();
        const rt::WakeLatencyHold hold(0, missing);
        CHECK_FALSE(hold.held());
        CHECK_THAT(hold.note(), Catch::Contains(missing));
        CHECK_THAT(hold.note(), Catch::Contains(std::strerror(ENOENT)));
    }
    SECTION("a negative request") {
        const rt::WakeLatencyHold hold(-1, file);
        CHECK_FALSE(hold.held());
        CHECK_THAT(hold.note(), Catch::Contains("at least 0"));
        CHECK(std::filesystem::file_size(file) == 0); // nothing was written
    }
    SECTION("nothing asked") {
        const rt::WakeLatencyHold hold;
        CHECK_FALSE(hold.held());
        CHECK(hold.note().empty());
    }
}

TEST_CASE("a wake-latency hold is a request the kernel keeps while it is held") {
    if (!canHold()) {
        // Not root, or no PM QoS in this kernel: the hold says so instead of holding.
        const rt::WakeLatencyHold hold(7);
        CHECK_FALSE(hold.held());
        CHECK_THAT(hold.note(), Catch::Contains(kQos));
        return;
    }
    std::optional<rt::WakeLatencyHold> hold(std::in_place, 7);
    REQUIRE(hold->held());
    // The value in force is the minimum over every request: at most ours while we hold it.
    const std::optional<std::int32_t> inForce = readS32(kQos);
    REQUIRE(inForce);
    CHECK(*inForce <= 7);
    CHECK(*inForce >= 0);
}

TEST_CASE("a session asked to hold a wake latency holds it while its servo threads run",
          "[realtime]") {
    RuntimeOptions opt;
    opt.wakeLatencyUs = 3;
    OneHand hand(opt);
    Runtime& runtime = *hand.runtime;
    REQUIRE(runtime.start() == 1);
    if (canHold()) {
        const std::optional<std::int32_t> inForce = readS32(kQos);
        REQUIRE(inForce);
        CHECK(*inForce <= 3);
    }
    runtime.stop();
    const RunReport r = runtime.report();
    const auto j = nlohmann::json::parse(reportToJson(r));
    if (canHold()) {
        CHECK(r.wakeLatencyUs == 3);
        CHECK(j["total"]["wake_latency_us"] == 3);
        CHECK(r.realtimeNote.find(kQos) == std::string::npos);
    } else {
        CHECK(r.wakeLatencyUs == -1);
        CHECK_FALSE(j["total"].contains("wake_latency_us"));
        CHECK_THAT(r.realtimeNote, Catch::Contains(kQos));
    }
}

TEST_CASE("a session holds no wake latency unless asked", "[realtime]") {
    OneHand hand(RuntimeOptions{});
    Runtime& runtime = *hand.runtime;
    REQUIRE(runtime.start() == 1);
    runtime.stop();
    const RunReport r = runtime.report();
    CHECK(r.wakeLatencyUs == -1);
    CHECK_FALSE(nlohmann::json::parse(reportToJson(r))["total"].contains("wake_latency_us"));
}
