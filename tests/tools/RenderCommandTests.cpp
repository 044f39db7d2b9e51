// `hapto render` end to end: a device point along a path through the haptic tick, pinned by
// analytic expectations (k d along the face normal; zero force and proxy == point outside),
// byte-identical reruns, and bad input refused with exit code 2.

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

using namespace hapto::test;

namespace {

constexpr double kSkinM = 1e-8; // GodObjectRenderer::kSkinM: the proxy rides this far outside

/// A 5 cm cube at the origin (faces at +-0.025 m) of stiffness k (N/m).
std::string cubeScene(double k) {
    std::ostringstream s;
    s.precision(17);
    s << R"({"format": "hapto-scene", "version": 1, "objects": [)"
      << R"({"id": 4, "shape": "box", "center": [0, 0, 0], "half_extents": [0.025, 0.025, 0.025],)"
      << R"( "stiffness": )" << k << "}]}";
    return s.str();
}

/// A path as CSV lines (header included) from points.
std::string pathCsv(const std::vector<std::array<double, 3>>& points) {
    std::ostringstream s;
    s.precision(17);
    s << "x,y,z\n";
    for (const auto& p : points) {
        s << p[0] << "," << p[1] << "," << p[2] << "\n";
    }
    return s.str();
}

struct Row {
    long tick;
    std::array<double, 3> point, proxy, force;
    int contacts;
    std::vector<std::string> text; // the fields as written
};

std::vector<Row> parse(const std::string& csv) {
    std::istringstream in(csv);
    std::string line;
    std::getline(in, line);
    REQUIRE(line == "tick,x,y,z,proxy_x,proxy_y,proxy_z,fx,fy,fz,contacts");
    std::vector<Row> rows;
    while (std::getline(in, line)) {
        Row r;
        std::istringstream fields(line);
        for (std::string f; std::getline(fields, f, ',');) {
            r.text.push_back(f);
        }
        REQUIRE(r.text.size() == 11);
        r.tick = std::stol(r.text[0]);
        for (int a = 0; a < 3; ++a) {
            r.point[a] = std::strtod(r.text[1 + a].c_str(), nullptr);
            r.proxy[a] = std::strtod(r.text[4 + a].c_str(), nullptr);
            r.force[a] = std::strtod(r.text[7 + a].c_str(), nullptr);
        }
        r.contacts = std::stoi(r.text[10]);
        rows.push_back(r);
    }
    return rows;
}

} // namespace

TEST_CASE("hapto render: pressing d into a box face of stiffness k gives k d along the face "
          "normal, outside, zero force and the proxy on the point") {
    const double k = GENERATE(300.0, 800.0, 2500.0);
    const int axis = GENERATE(0, 1, 2);
    const double sign = GENERATE(-1.0, 1.0);
    INFO("k " << k << " axis " << axis << " sign " << sign);
    TempDir dir;
    writeFile(dir / "cube.json", cubeScene(k));
    // From 2 cm outside the face straight in to 3 mm deep, 0.25 mm per tick, then held.
    std::vector<std::array<double, 3>> points;
    std::vector<double> depths; // how far behind the face each point is (m), < 0 outside
    for (int i = 0; i <= 112; ++i) {
        const double depth = std::min(0.003, -0.02 + 0.00025 * i);
        std::array<double, 3> p{0.004, -0.003, 0.002}; // off the face's centre, well inside it
        p[axis] = sign * (0.025 - depth);
        points.push_back(p);
        depths.push_back(depth);
    }
    writeFile(dir / "path.csv", pathCsv(points));
    const CommandResult r = runHapto("render --scene " + (dir / "cube.json").string() + " --path " +
                                     (dir / "path.csv").string());
    INFO(r.output.substr(0, 2000));
    REQUIRE(r.exitCode == 0);
    const std::vector<Row> rows = parse(r.output);
    REQUIRE(rows.size() == points.size());
    int pressed = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
        const Row& row = rows[i];
        INFO("tick " << i << " depth " << depths[i]);
        CHECK(row.tick == static_cast<long>(i));
        for (int a = 0; a < 3; ++a) {
            CHECK(row.point[a] == points[i][a]); // read back exactly
        }
        if (depths[i] < 0) {
            CHECK(row.contacts == 0);
            CHECK(row.text[7] == "0");
            CHECK(row.text[8] == "0");
            CHECK(row.text[9] == "0");
            // The proxy is the point, digit for digit.
            CHECK(row.text[4] == row.text[1]);
            CHECK(row.text[5] == row.text[2]);
            CHECK(row.text[6] == row.text[3]);
        } else if (depths[i] > 1e-6) {
            ++pressed;
            CHECK(row.contacts == 1);
            for (int a = 0; a < 3; ++a) {
                const double expected = a == axis ? sign * k * (depths[i] + kSkinM) : 0.0;
                CHECK(row.force[a] == Approx(expected).margin(1e-9 * k));
                const double proxy = a == axis ? sign * (0.025 + kSkinM) : points[i][a];
                CHECK(row.proxy[a] == Approx(proxy).margin(1e-12));
            }
        }
    }
    CHECK(pressed > 20);
}

TEST_CASE("hapto render: the same input gives the same bytes, to a file or standard output",
          "[threads]") {
    TempDir dir;
    writeFile(dir / "cube.json", cubeScene(800.0));
    // A wavy stroke across the top face and over its edge, with friction's default state.
    std::vector<std::array<double, 3>> points;
    for (int i = 0; i < 400; ++i) {
        const double u = i / 399.0;
        points.push_back(
            {-0.03 + 0.07 * u, 0.0245 - 0.002 * std::sin(9.0 * u), 0.01 * std::cos(5.0 * u)});
    }
    writeFile(dir / "path.csv", pathCsv(points));
    const std::string args = "render --scene " + (dir / "cube.json").string() + " --path " +
                             (dir / "path.csv").string() + " --rate 2000 --index grid:4";
    REQUIRE(runHapto(args + " -o " + (dir / "a.csv").string()).exitCode == 0);
    REQUIRE(runHapto(args + " -o " + (dir / "b.csv").string()).exitCode == 0);
    const std::string a = readFile(dir / "a.csv");
    CHECK(a == readFile(dir / "b.csv"));
    const CommandResult out = runHapto(args);
    REQUIRE(out.exitCode == 0);
    CHECK(out.output == a);
    const std::vector<Row> rows = parse(a);
    REQUIRE(rows.size() == 400);
    CHECK(std::any_of(rows.begin(), rows.end(), [](const Row& r) { return r.contacts > 0; }));
    // The index only picks candidates: another one renders the same bytes.
    REQUIRE(runHapto("render --scene " + (dir / "cube.json").string() + " --path " +
                     (dir / "path.csv").string() + " --rate 2000 --index brute -o " +
                     (dir / "c.csv").string())
                .exitCode == 0);
    CHECK(readFile(dir / "c.csv") == a);
}

TEST_CASE("hapto render refuses bad input with exit code 2, says where, and writes nothing") {
    TempDir dir;
    writeFile(dir / "cube.json", cubeScene(800.0));
    writeFile(dir / "path.csv", "x,y,z\n0,0.03,0\n0,0.02,0\n");
    writeFile(dir / "out.csv", "an older output\n");
    const std::string scene = " --scene " + (dir / "cube.json").string();
    const std::string path = " --path " + (dir / "path.csv").string();
    const auto refused = [&](const std::string& args, const std::string& says) {
        const CommandResult r = runHapto("render" + args);
        INFO(args << "\n" << r.output);
        CHECK(r.exitCode == 2);
        CHECK_THAT(r.output, Catch::Contains(says));
    };
    SECTION("a bad path line: file and line") {
        for (const char* bad :
             {"0,0.02\n", "0,0.02,zero\n", "nan,0,0\n", "0,inf,0\n", "1,2,3,4\n"}) {
            writeFile(dir / "bad.csv", std::string("x,y,z\n0,0.03,0\n") + bad);
            refused(scene + " --path " + (dir / "bad.csv").string(), "bad.csv:3:");
        }
    }
    SECTION("an empty path") {
        writeFile(dir / "empty.csv", "x,y,z\n");
        refused(scene + " --path " + (dir / "empty.csv").string(), "no points");
    }
    SECTION("missing files") {
        refused(scene + " --path " + (dir / "missing.csv").string(), "missing.csv");
        refused(" --scene " + (dir / "missing.json").string() + path, "missing.json");
    }
    SECTION("a bad scene, index or rate") {
        writeFile(dir / "broken.json",
                  R"({"format": "hapto-scene", "version": 1, "objects": [{}]})");
        refused(" --scene " + (dir / "broken.json").string() + path, "objects[0]");
        refused(scene + path + " --index octree:0:0.005", "octree");
        refused(scene + path + " --rate 50", "--rate");
        refused(scene + path + " --rate nan", "--rate");
    }
    SECTION("an output that is an input") {
        refused(scene + path + " -o " + (dir / "path.csv").string(), "--path");
        refused(scene + path + " -o " + (dir / "cube.json").string(), "--scene");
        CHECK(readFile(dir / "path.csv") == "x,y,z\n0,0.03,0\n0,0.02,0\n");
    }
    SECTION("an output in a missing folder") {
        refused(scene + path + " -o " + (dir / "no/such/out.csv").string(), "-o");
    }
    // Nothing was written: the older output is as it was, no temporary is left.
    CHECK(readFile(dir / "out.csv") == "an older output\n");
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        CHECK(entry.path().filename().string().find(".tmp-") == std::string::npos);
    }
}

namespace {

/// Runs `hapto render` over a scene text and a path, and returns its rows.
std::vector<Row> renderRows(const TempDir& dir, const std::string& name, const std::string& scene,
                            const std::vector<std::array<double, 3>>& points) {
    writeFile(dir / (name + ".json"), scene);
    writeFile(dir / (name + ".csv"), pathCsv(points));
    const CommandResult r = runHapto("render --scene " + (dir / (name + ".json")).string() +
                                     " --path " + (dir / (name + ".csv")).string());
    INFO(r.output.substr(0, 2000));
    REQUIRE(r.exitCode == 0);
    std::vector<Row> rows = parse(r.output);
    REQUIRE(rows.size() == points.size());
    return rows;
}

/// A version 2 scene with one inline mesh object (id 4) of stiffness k at `center`.
std::string meshScene(double k, const std::string& center, const std::string& vertices,
                      const std::string& triangles) {
    std::ostringstream s;
    s.precision(17);
    s << R"({"format": "hapto-scene", "version": 2, "objects": [)"
      << R"({"id": 4, "shape": "mesh", "center": )" << center << R"(, "vertices": )" << vertices
      << R"(, "triangles": )" << triangles << R"(, "stiffness": )" << k << "}]}";
    return s.str();
}

} // namespace

TEST_CASE("hapto render: a flat two-triangle mesh square feels like the box face it replaces, "
          "within 1e-9 N along the same path") {
    const double k = GENERATE(300.0, 2500.0);
    INFO("k " << k);
    TempDir dir;
    // The cube's top face (y = 0.025, x and z in [-0.025, 0.025]) as two triangles, CCW seen from
    // +y, sharing the diagonal x = z; an open, one-sided mesh.
    const std::string square = meshScene(
        k, "[0, 0.025, 0]",
        "[[-0.025, 0, -0.025], [-0.025, 0, 0.025], [0.025, 0, 0.025], [0.025, 0, -0.025]]",
        "[[0, 1, 2], [0, 2, 3]]");
    // Down from 1 cm above the face to 2 mm deep, a slide across the shared diagonal at that
    // depth, then 3 mm deep and held: all well inside the face.
    std::vector<std::array<double, 3>> points;
    for (int i = 0; i <= 48; ++i) {
        points.push_back({-0.012, 0.025 + std::max(-0.002, 0.01 - 0.00025 * i), -0.006});
    }
    for (int i = 1; i <= 120; ++i) {
        const double u = i / 120.0;
        points.push_back(
            {-0.012 + 0.026 * u, 0.023 - 0.0005 * std::sin(6.0 * u), -0.006 + 0.014 * u});
    }
    for (int i = 1; i <= 30; ++i) {
        points.push_back({0.014, 0.025 - 0.002 - 0.001 * std::min(1.0, i / 10.0), 0.008});
    }
    const std::vector<Row> box = renderRows(dir, "box", cubeScene(k), points);
    const std::vector<Row> mesh = renderRows(dir, "square", square, points);
    int pressed = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        INFO("tick " << i);
        CHECK(mesh[i].contacts == box[i].contacts);
        for (int a = 0; a < 3; ++a) {
            CHECK(mesh[i].force[a] == Approx(box[i].force[a]).margin(1e-9));
            CHECK(mesh[i].proxy[a] == Approx(box[i].proxy[a]).margin(1e-12));
        }
        if (box[i].contacts > 0) {
            ++pressed;
            const double depth = 0.025 - points[i][1];
            CHECK(mesh[i].force[1] == Approx(k * (depth + kSkinM)).margin(1e-9 * k));
        }
    }
    CHECK(pressed > 150); // the slide and the hold, not only a few ticks
}

TEST_CASE("hapto render: a closed cube mesh pressed into an edge holds: no pop-through, the "
          "force is k times the depth along the path, pointing back out of the edge") {
    const double k = GENERATE(500.0, 2000.0);
    INFO("k " << k);
    TempDir dir;
    // A 5 cm cube at the origin as 12 triangles, CCW seen from outside.
    const std::string cube =
        meshScene(k, "[0, 0, 0]",
                  "[[-0.025, -0.025, -0.025], [0.025, -0.025, -0.025], [0.025, 0.025, -0.025], "
                  "[-0.025, 0.025, -0.025], [-0.025, -0.025, 0.025], [0.025, -0.025, 0.025], "
                  "[0.025, 0.025, 0.025], [-0.025, 0.025, 0.025]]",
                  "[[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [3, 7, 6], "
                  "[3, 6, 2], [0, 4, 7], [0, 7, 3], [1, 2, 6], [1, 6, 5]]");
    // Along the bisector of the edge between the +x and +y faces, at z = 0.004: from 2 cm out
    // to 8 mm in (s < 0 is inside), 0.25 mm per tick, then held for 40 ticks.
    const double r2 = std::sqrt(0.5);
    std::vector<std::array<double, 3>> points;
    std::vector<double> along;
    for (int i = 0; i <= 112 + 40; ++i) {
        const double s = std::max(-0.008, 0.02 - 0.00025 * i);
        points.push_back({0.025 + r2 * s, 0.025 + r2 * s, 0.004});
        along.push_back(s);
    }
    const std::vector<Row> rows = renderRows(dir, "cube", cube, points);
    int held = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
        INFO("tick " << i << " s " << along[i]);
        const Row& row = rows[i];
        const double magnitude =
            std::sqrt(row.force[0] * row.force[0] + row.force[1] * row.force[1] +
                      row.force[2] * row.force[2]);
        if (along[i] > 1e-6) {
            CHECK(row.contacts == 0);
            CHECK(magnitude == 0.0);
        } else if (along[i] < -1e-6) {
            ++held;
            CHECK(row.contacts >= 1);
            // k times the depth past the edge (the skin adds at most 2e-8 m), out along the
            // bisector: the proxy stays on the edge, not pushed through either face.
            CHECK(magnitude == Approx(k * -along[i]).margin(3e-8 * k));
            CHECK(row.force[0] == Approx(r2 * magnitude).margin(3e-8 * k));
            CHECK(row.force[1] == Approx(r2 * magnitude).margin(3e-8 * k));
            CHECK(row.force[2] == Approx(0.0).margin(1e-9 * k));
            CHECK(row.proxy[0] == Approx(0.025).margin(3e-8));
            CHECK(row.proxy[1] == Approx(0.025).margin(3e-8));
        }
    }
    CHECK(held > 60);
}
