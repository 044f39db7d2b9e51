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
        // Version 2's fields, each a different number so a swapped column shows; a field
        // without its flag is stored as its default (identity orientation, zero spin).
        s.proxyM = Vec3(0.5, -0.125, 0.0);
        s.velocityMps = Vec3(0.25, 0.0, -2.0);
        s.orientation = Quat(0.0, 1.0, 0.0, 0.0);
        s.angularVelocity = Vec3(3.0, -4.0, 0.75);
        s.contactCount = static_cast<std::uint32_t>(t);
        s.hasVelocity = true;
        s.hasOrientation = t != 0;
        s.hasAngularVelocity = t == 2;
        s.missedDeadline = t == 1;
        rec.push(s);
    }
    rec.close();
}

} // namespace

TEST_CASE("hapto trace export writes one CSV row per sample, every column of version 2") {
    test::TempDir dir;
    writeSmallTrace(dir / "left.trace");
    const auto r = test::runHapto("trace export " + (dir / "left.trace").string() + " -o " +
                                  (dir / "left.csv").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK(test::readFile(dir / "left.csv") ==
          "tick,time_ns,x_m,y_m,z_m,fx_n,fy_n,fz_n,compute_ns,io_ns,status,buttons,"
          "proxy_x_m,proxy_y_m,proxy_z_m,vx_mps,vy_mps,vz_mps,qw,qx,qy,qz,"
          "wx_radps,wy_radps,wz_radps,contacts,"
          "has_velocity,has_orientation,has_angular_velocity,missed_deadline\n"
          "100,0,0,-0.25,1e-07,0,1.5,0,12345,678,ok,1,"
          "0.5,-0.125,0,0.25,0,-2,1,0,0,0,0,0,0,0,1,0,0,0\n"
          "101,1000000,0.1,-0.25,1e-07,0,1.5,0,12345,678,ok,1,"
          "0.5,-0.125,0,0.25,0,-2,0,1,0,0,0,0,0,1,1,1,0,1\n"
          "102,2000000,0.2,-0.25,1e-07,0,1.5,0,12345,678,stalled,1,"
          "0.5,-0.125,0,0.25,0,-2,0,1,0,0,3,-4,0.75,2,1,1,1,0\n");
}

TEST_CASE("hapto trace export writes a version 1 trace's columns, no more") {
    // Written by the version 1 recorder (a fuzz corpus entry): three ticks of "left" (sim).
    const std::filesystem::path v1 =
        std::filesystem::path(HAPTO_SOURCE_DIR) / "tools/fuzz/corpus/trace_file/three-ticks.trace";
    const auto r = test::runHapto("trace export " + v1.string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK(r.output == "tick,time_ns,x_m,y_m,z_m,fx_n,fy_n,fz_n,compute_ns,io_ns,status,buttons\n"
                      "0,0,0,0,-0.02,0,1,0,3000,500,ok,1\n"
                      "1,1000000,0.01,0,-0.02,0,1,0,3000,500,ok,1\n"
                      "2,2000000,0.02,0,-0.02,0,1,0,3000,500,ok,1\n");
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
    CHECK_THAT(r.output, Catch::Contains("format:   version 2"));
    CHECK_THAT(r.output, Catch::Contains("tool tip: [0, 0, 0] m"));
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

namespace {

// A version 2 trace of `name`: 400 ticks at 1 kHz, in contact from tick 100 to 199 (a force
// pushing back along +y, the proxy held at y = 0), compute time growing with the tick.
void writeContactTrace(const std::filesystem::path& p, const std::string& name, double sign) {
    TraceHeader h;
    h.name = name;
    h.kind = "sim";
    TraceRecorder rec(p, h);
    for (std::uint64_t t = 0; t < 400; ++t) {
        TraceSample s;
        s.tick = t;
        s.timeNs = 1'000'000 * t;
        const double y = 0.01 - 0.0001 * static_cast<double>(t);
        s.positionM = Vec3(sign * 0.02, y, 0.0);
        const bool contact = t >= 100 && t < 200;
        s.proxyM = Vec3(sign * 0.02, contact ? 0.0 : y, 0.0);
        s.contactCount = contact ? 1 : 0;
        s.forceN = contact ? Vec3(0.0, 300.0 * (0.0 - y), 0.0) : Vec3(0.0);
        s.computeNs = static_cast<std::uint32_t>(1000 + t);
        REQUIRE(rec.push(s));
    }
    rec.close();
}

bool startsWith(const std::string& s, const std::string& prefix) {
    return s.compare(0, prefix.size(), prefix) == 0;
}

} // namespace

TEST_CASE("hapto trace plot draws traces as PNG and SVG, a line per device, contact shaded",
          "[threads]") {
    test::TempDir dir;
    writeContactTrace(dir / "left.trace", "left", -1.0);
    writeContactTrace(dir / "right.trace", "right", 1.0);
    for (const std::string ext : {"png", "svg"}) {
        INFO(ext);
        const std::filesystem::path out = dir / ("run." + ext);
        const auto r = test::runHapto("trace plot " + (dir / "left.trace").string() + " " +
                                      (dir / "right.trace").string() + " -o " + out.string() +
                                      " --script " + (dir / "run.gp").string());
        INFO(r.output);
        REQUIRE(r.exitCode == 0);
        const std::string image = test::readFile(out);
        if (ext == "png") {
            CHECK(startsWith(image, "\x89PNG\r\n\x1a\n"));
        } else {
            CHECK_THAT(image, Catch::Contains("<svg"));
            CHECK_THAT(image, Catch::Contains("</svg>"));
        }
        const std::string gp = test::readFile(dir / "run.gp");
        // One panel per quantity, with units.
        for (const char* label :
             {"position (m)", "proxy (m)", "force (N)", "tick time (us)", "time (s)"}) {
            CHECK_THAT(gp, Catch::Contains(std::string("\"") + label + "\""));
        }
        // A line per device (and per component).
        for (const char* series : {"left x", "right z", "left |F|", "right |F|", "left Fy"}) {
            CHECK_THAT(gp, Catch::Contains(std::string("title \"") + series + "\""));
        }
        // The contact spans, one per device in its own colour: ticks 100..199 of each, 0.1 s to
        // 0.199 s, keyed by device.
        CHECK_THAT(gp, Catch::Contains("set object 1 rect from 0.1, graph 0 to 0.199, graph 1"));
        CHECK_THAT(gp, Catch::Contains("set object 2 rect from 0.1, graph 0 to 0.199, graph 1"));
        CHECK_THAT(gp, !Catch::Contains("set object 3 rect"));
        CHECK_THAT(gp, Catch::Contains("\"left in contact\""));
        CHECK_THAT(gp, Catch::Contains("\"right in contact\""));
        // Two colours, the palette's first two (tab10: blue, orange), not two shades of one.
        CHECK_THAT(gp, Catch::Contains("fillcolor rgb '#1f77b4'"));
        CHECK_THAT(gp, Catch::Contains("fillcolor rgb '#ff7f0e'"));
        // The data: tick 150 of "left" (y = -0.005 m, |F| = 1.5 N, 1.15 us).
        CHECK_THAT(gp, Catch::Contains("\n0.15 -0.005\n"));
        CHECK_THAT(gp, Catch::Contains("\n0.15 1.5\n"));
        CHECK_THAT(gp, Catch::Contains("\n0.15 1.15\n"));
        if (ext == "png") {
            CHECK_THAT(gp, Catch::Contains("set terminal pngcairo"));
            CHECK_THAT(gp, !Catch::Contains("set terminal svg"));
        } else {
            CHECK_THAT(gp, Catch::Contains("set terminal svg"));
        }
    }
    // Nothing but the outputs is left in the folder.
    std::size_t files = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) {
        ++files;
    }
    CHECK(files == 5); // two traces, run.png, run.svg, run.gp
}

TEST_CASE("hapto trace plot refuses a bad trace or output with exit code 2, writing nothing") {
    test::TempDir dir;
    writeContactTrace(dir / "left.trace", "left", -1.0);
    std::filesystem::copy_file(dir / "left.trace", dir / "bad.trace");
    std::filesystem::resize_file(dir / "bad.trace", 300);
    auto r = test::runHapto("trace plot " + (dir / "left.trace").string() + " " +
                            (dir / "bad.trace").string() + " -o " + (dir / "p.png").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("bad.trace: byte 300"));
    CHECK_FALSE(std::filesystem::exists(dir / "p.png"));
    r = test::runHapto("trace plot " + (dir / "left.trace").string() + " -o " +
                       (dir / "p.jpg").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains(".png or .svg"));
}

TEST_CASE("hapto report plot draws a run report per device", "[threads]") {
    test::TempDir dir;
    // On the step mode's clock: a report of the same shape, and no wall-clock session whose
    // watchdog a loaded machine could trip.
    const auto run = test::runHapto("run --duration 0.3 --stepped --quiet --report " +
                                    (dir / "report.json").string());
    INFO(run.output);
    REQUIRE(run.exitCode == 0);
    const auto r =
        test::runHapto("report plot " + (dir / "report.json").string() + " -o " +
                       (dir / "report.svg").string() + " --script " + (dir / "report.gp").string());
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    CHECK_THAT(test::readFile(dir / "report.svg"), Catch::Contains("<svg"));
    const std::string gp = test::readFile(dir / "report.gp");
    CHECK_THAT(gp, Catch::Contains("tick time (% of the period)"));
    CHECK_THAT(gp, Catch::Contains("lateness (us)"));
    // The devices by name along x, a line per statistic.
    CHECK_THAT(gp, Catch::Contains("set xtics (\"left\" 1, \"right\" 2)"));
    for (const char* series : {"p50", "p99.9", "max", "in contact", "missed deadlines"}) {
        CHECK_THAT(gp, Catch::Contains(std::string("title \"") + series + "\""));
    }
    const auto png = test::runHapto("report plot " + (dir / "report.json").string() + " -o " +
                                    (dir / "report.png").string());
    REQUIRE(png.exitCode == 0);
    CHECK(startsWith(test::readFile(dir / "report.png"), "\x89PNG\r\n\x1a\n"));
}

namespace {

/// `s` as one word for the shell that runs test::runHapto's command line.
std::string shellWord(const std::string& s) {
    std::string q = "'";
    for (const char c : s) {
        q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    }
    return q + "'";
}

/// A run report, as `hapto report plot` reads it, of devices named by the JSON strings given.
std::string reportOf(const std::vector<std::string>& jsonNames) {
    std::string devices;
    for (const std::string& name : jsonNames) {
        devices += (devices.empty() ? "" : ", ") + std::string(R"({"name": )") + name +
                   R"(, "ticks": 1000, "load": {"p50": 0.1, "p99": 0.2, "p999": 0.3, "max": 0.4},
                      "lateness_ns": {"p50": 1000, "p99": 2000, "max": 3000},
                      "contact_ticks": 10, "missed_deadlines": 1})";
    }
    return R"({"devices": [)" + devices + "]}";
}

/// A folder name with backquotes, $(...), quotes and a newline.
const std::string kHostileFolder = "d`touch PWNED-dir1`$(touch PWNED-dir2)'\"\\\nx";

} // namespace

TEST_CASE("hapto report plot draws hostile names and paths as text and runs none of them") {
    test::TempDir root;
    const std::filesystem::path dir = root / kHostileFolder;
    std::filesystem::create_directories(dir);
    test::writeFile(dir / "report.json",
                    reportOf({R"("x`touch PWNED1`y")", R"x("$(touch PWNED2)")x",
                              R"("a'b\"c\\ @out")", R"("'; system('touch PWNED3'); '")"}));
    const test::InFolder inRoot(root.path());
    const auto r = test::runHapto("report plot " + shellWord((dir / "report.json").string()) +
                                  " -o " + shellWord((dir / "report.svg").string()) + " --script " +
                                  shellWord((dir / "report.gp").string()));
    INFO(r.output);
    CHECK(r.exitCode == 0);
    const std::string svg = test::readFile(dir / "report.svg");
    CHECK_THAT(svg, Catch::Contains("x`touch PWNED1`y"));
    CHECK_THAT(svg, Catch::Contains("$(touch PWNED2)"));
    CHECK(test::pwned(root.path()).empty());
}

TEST_CASE("hapto report plot refuses a device name with a control character, naming it") {
    test::TempDir dir;
    for (const std::string name : {R"("left\nright")", R"("left\u0000x")", R"("\u001b[2J")"}) {
        INFO(name);
        test::writeFile(dir / "report.json", reportOf({R"("ok")", name}));
        const auto r = test::runHapto("report plot " + (dir / "report.json").string() + " -o " +
                                      (dir / "report.svg").string());
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains("report.json: devices[1].name: the device name must "
                                             "not contain control characters (got " +
                                             name + ")"));
        CHECK_FALSE(std::filesystem::exists(dir / "report.svg"));
    }
}

TEST_CASE("hapto trace plot draws hostile device names and paths as text and runs none",
          "[threads]") {
    test::TempDir root;
    const std::filesystem::path dir = root / kHostileFolder;
    std::filesystem::create_directories(dir);
    // A device-name header of printable ASCII that gnuplot would run in a double-quoted string.
    writeContactTrace(dir / "left.trace", "x`touch PWNED4`$(touch PWNED5)'\"\\@out", -1.0);
    writeContactTrace(dir / "right.trace", "'; system('touch PWNED6'); '", 1.0);
    const test::InFolder inRoot(root.path());
    for (const std::string ext : {".png", ".svg"}) {
        const auto r = test::runHapto("trace plot " + shellWord((dir / "left.trace").string()) +
                                      " " + shellWord((dir / "right.trace").string()) + " -o " +
                                      shellWord((dir / ("t" + ext)).string()));
        INFO(r.output);
        CHECK(r.exitCode == 0);
        CHECK(std::filesystem::file_size(dir / ("t" + ext)) > 0);
    }
    CHECK_THAT(test::readFile(dir / "t.svg"), Catch::Contains("x`touch PWNED4`$(touch PWNED5)"));
    // One trace: its path is in the title.
    const auto one = test::runHapto("trace plot " + shellWord((dir / "left.trace").string()) +
                                    " -o " + shellWord((dir / "one.svg").string()));
    INFO(one.output);
    CHECK(one.exitCode == 0);
    CHECK_THAT(test::readFile(dir / "one.svg"), Catch::Contains("touch PWNED-dir1"));
    CHECK(test::pwned(root.path()).empty());
}

TEST_CASE("hapto trace plot refuses a device name with a control character, naming the field") {
    test::TempDir dir;
    writeContactTrace(dir / "left.trace", "left\nright", -1.0);
    const auto r = test::runHapto("trace plot " + (dir / "left.trace").string() + " -o " +
                                  (dir / "t.svg").string());
    CHECK(r.exitCode == 2);
    CHECK_THAT(r.output, Catch::Contains("left.trace: byte 64: the name field"));
    CHECK_FALSE(std::filesystem::exists(dir / "t.svg"));
}
