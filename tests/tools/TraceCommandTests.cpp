#include "hapto/devices/TraceRecorder.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>

using namespace hapto;

namespace {

void writeSmallTrace(const std::filesystem::path& p) {
    TraceHeader h;
    h.name = "left";
    h.kind = "sim";
    TraceRecorder rec(p, h);
    for (std::uint64_t t = 0; t < 3; ++t) {
        TraceSample s;
        s.tick = 100 + t;
        s.timeNs = 1000000 * t;
        s.positionM = Vec3(0.1 * static_cast<double>(t), -0.25, 1e-7);
        s.forceN = Vec3(0.0, 1.5, 0.0);
        s.computeNs = 12345;
        s.ioNs = 678;
        s.status = t == 2 ? DeviceStatus::Stalled : DeviceStatus::Ok;
        s.buttons = 1;
        rec.push(s);
    }
    rec.close();
}

} // namespace

TEST_CASE("hapto trace export writes one CSV row per sample") {
    test::TempDir dir;
    writeSmallTrace(dir / "left.trace");
    const auto r = test::runHapto("trace export " + (dir / "left.trace").string() + " -o " +
                                  (dir / "left.csv").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK(test::readFile(dir / "left.csv") ==
          "tick,time_ns,x_m,y_m,z_m,fx_n,fy_n,fz_n,compute_ns,io_ns,status,buttons\n"
          "100,0,0,-0.25,1e-07,0,1.5,0,12345,678,ok,1\n"
          "101,1000000,0.1,-0.25,1e-07,0,1.5,0,12345,678,ok,1\n"
          "102,2000000,0.2,-0.25,1e-07,0,1.5,0,12345,678,stalled,1\n");
}

TEST_CASE("hapto trace export writes to standard output without -o") {
    test::TempDir dir;
    writeSmallTrace(dir / "left.trace");
    const auto r = test::runHapto("trace export " + (dir / "left.trace").string());
    REQUIRE(r.exitCode == 0);
    CHECK_THAT(r.output, Catch::StartsWith("tick,time_ns,"));
    CHECK_THAT(r.output, Catch::Contains("102,2000000,0.2,"));
}

TEST_CASE("hapto trace info describes a trace") {
    test::TempDir dir;
    writeSmallTrace(dir / "left.trace");
    const auto r = test::runHapto("trace info " + (dir / "left.trace").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK_THAT(r.output, Catch::Contains("left (sim)"));
    CHECK_THAT(r.output, Catch::Contains("samples:  3"));
}

TEST_CASE("hapto trace export refuses a bad trace with exit code 2") {
    test::TempDir dir;
    writeSmallTrace(dir / "left.trace");
    std::filesystem::resize_file(dir / "left.trace", 200);
    const auto r = test::runHapto("trace export " + (dir / "left.trace").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("left.trace: byte 200: truncated"));
    const auto missing = test::runHapto("trace export " + (dir / "none.trace").string());
    CHECK(missing.exitCode == 2);
}
