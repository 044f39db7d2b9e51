// The scene and trace documents the page reads.

#include "hapto/view/ViewDocuments.h"

#include "hapto/scenes/MeshGenerators.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <utility>

using namespace hapto;

TEST_CASE("the scene document carries every object's shape, centre, size and rotation") {
    const Quat turn = glm::angleAxis(0.5, Vec3(0, 0, 1));
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)},
                      {makeBox(7, Vec3(0.1, 0.2, 0.3), Vec3(0.01, 0.02, 0.03), turn),
                       makeSphere(9, Vec3(-0.1, 0, 0), 0.05)});
    const auto doc = nlohmann::json::parse(
        viewSceneJson(scene, {{"left", 1000}, {"right", 2000}}, ViewMode::Live));
    CHECK(doc["mode"] == "live");
    CHECK(doc["bounds"]["min"] == nlohmann::json::array({-1.0, -1.0, -1.0}));
    REQUIRE(doc["objects"].size() == 2);
    const auto& box = doc["objects"][0];
    CHECK(box["id"] == 7);
    CHECK(box["shape"] == "box");
    CHECK(box["center"] == nlohmann::json::array({0.1, 0.2, 0.3}));
    CHECK(box["halfExtents"] == nlohmann::json::array({0.01, 0.02, 0.03}));
    CHECK(box["rotation"][0].get<double>() == Approx(turn.w));
    CHECK(box["rotation"][3].get<double>() == Approx(turn.z));
    CHECK(doc["objects"][1]["shape"] == "sphere");
    CHECK(doc["objects"][1]["halfExtents"][0] == 0.05);
    CHECK(doc["devices"][1]["name"] == "right");
    CHECK(doc["devices"][1]["rateHz"] == 2000);
    CHECK(nlohmann::json::parse(viewSceneJson(scene, {}, ViewMode::Trace))["mode"] == "trace");
}

TEST_CASE("the trace document: world-frame points and forces, contacts, frames at the rate asked") {
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)},
                      {makeBox(3, Vec3(0.0), Vec3(0.01)), makeSphere(4, Vec3(0.5, 0, 0), 0.01)});
    ViewTrace t;
    t.header.name = "left";
    t.header.rateHz = 1000;
    t.transform.translation = Vec3(0.0, 0.0, -0.05);
    // 1 s at 1 kHz: the point walks along z from -0.05 through the box (world frame).
    for (std::uint64_t i = 0; i < 1000; ++i) {
        TraceSample s;
        s.tick = i;
        s.timeNs = i * 1'000'000;
        s.positionM = Vec3(0, 0, 0.0001 * static_cast<double>(i)); // device frame
        s.forceN = Vec3(0, 0, i >= 400 && i <= 600 ? -1.0 : 0.0);
        s.computeNs = i == 500 ? 1'500'000 : 100'000; // one tick overruns its period
        s.missedDeadline = i == 500;                  // and the servo marked it
        t.samples.push_back(s);
    }
    const auto doc = nlohmann::json::parse(viewTraceJson(scene, {t}, 50.0));
    CHECK(doc["durationS"].get<double>() == Approx(0.999));
    const auto& frames = doc["devices"][0]["frames"];
    CHECK(doc["devices"][0]["name"] == "left");
    CHECK(frames.size() == 51); // one per 20 ms, and the last tick
    bool sawContact = false;
    for (const auto& f : frames) {
        const double t_s = f["t"];
        const double z = f["point"][2];
        CHECK(z == Approx(-0.05 + 0.1 * t_s).margin(1e-9)); // placed in the world
        const bool inside = std::abs(z) <= 0.01;
        CHECK(f["contacts"].size() == (inside ? 1u : 0u));
        if (inside) {
            CHECK(f["contacts"][0] == 3);
            sawContact = true;
        }
        CHECK(f["ticks"].get<std::uint64_t>() == static_cast<std::uint64_t>(t_s * 1000 + 0.5) + 1);
        CHECK(f["misses"].get<std::uint64_t>() == (t_s >= 0.5 ? 1u : 0u));
    }
    CHECK(sawContact);
    CHECK(frames[25]["forceN"] == 1.0); // t = 0.5 s
    CHECK(frames[25]["force"][2] == -1.0);
    CHECK(frames[10]["loadP50"].get<double>() == Approx(0.1).epsilon(0.04));
}

namespace {

/// A tetrahedron of 4 triangles (CCW from outside), `size` m along each axis.
std::shared_ptr<const TriangleMesh> tetrahedron(double size) {
    return TriangleMesh::make({Vec3(0), Vec3(size, 0, 0), Vec3(0, size, 0), Vec3(0, 0, size)},
                              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}, MeshSource{}, "test");
}

} // namespace

TEST_CASE("the scene document carries each mesh's own vertices and triangles, placed by its pose, "
          "a mesh with no room left under the triangle cap comes as its local bounds") {
    const Quat turn = glm::angleAxis(0.7, Vec3(1, 0, 0));
    const auto small = tetrahedron(0.02);
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)},
                      {makeBox(1, Vec3(0.3, 0, 0), Vec3(0.01)),
                       makeMesh(5, Vec3(0.1, 0.2, 0.3), small, turn),
                       makeMesh(6, Vec3(-0.1, 0, 0), tetrahedron(0.04))});
    const auto doc = nlohmann::json::parse(viewSceneJson(scene, {}, ViewMode::Live));
    REQUIRE(doc["objects"].size() == 3);
    CHECK_FALSE(doc["objects"][0].contains("vertices")); // a box has none
    const auto& mesh = doc["objects"][1];
    CHECK(mesh["id"] == 5);
    CHECK(mesh["shape"] == "mesh");
    CHECK(mesh["center"] == nlohmann::json::array({0.1, 0.2, 0.3}));
    CHECK(mesh["rotation"][0].get<double>() == Approx(turn.w));
    CHECK(mesh["rotation"][1].get<double>() == Approx(turn.x));
    CHECK(mesh["triangleCount"] == 4);
    CHECK(mesh["trianglesShown"] == 4);
    // Flat, in the mesh's own frame, exactly as held.
    REQUIRE(mesh["vertices"].size() == 3 * small->vertices().size());
    for (std::size_t i = 0; i < small->vertices().size(); ++i) {
        for (int a = 0; a < 3; ++a) {
            CHECK(mesh["vertices"][3 * i + a].get<double>() == small->vertices()[i][a]);
        }
    }
    REQUIRE(mesh["triangles"].size() == 3 * small->triangles().size());
    for (std::size_t t = 0; t < small->triangles().size(); ++t) {
        for (int c = 0; c < 3; ++c) {
            CHECK(mesh["triangles"][3 * t + c].get<std::uint32_t>() == small->triangles()[t][c]);
        }
    }
    CHECK(doc["meshes"]["trianglesSent"] == 8);
    CHECK(doc["meshes"]["simplified"].empty());
    CHECK(doc["meshes"]["boxed"].empty());

    // A cap of 4 triangles: the first mesh (4) fits, the second (4 more) has no room left to be
    // simplified into and comes as its bounds.
    const auto capped = nlohmann::json::parse(viewSceneJson(scene, {}, ViewMode::Live, 4));
    CHECK(capped["objects"][1].contains("vertices"));
    const auto& boxed = capped["objects"][2];
    CHECK_FALSE(boxed.contains("vertices"));
    CHECK_FALSE(boxed.contains("triangles"));
    CHECK(boxed["triangleCount"] == 4);
    CHECK(boxed["localBounds"]["min"] == nlohmann::json::array({0.0, 0.0, 0.0}));
    CHECK(boxed["localBounds"]["max"] == nlohmann::json::array({0.04, 0.04, 0.04}));
    CHECK(capped["meshes"]["maxTriangles"] == 4);
    CHECK(capped["meshes"]["trianglesSent"] == 4);
    CHECK(capped["meshes"]["simplified"].empty());
    CHECK(capped["meshes"]["boxed"] == nlohmann::json::array({6}));
    CHECK(kViewMaxMeshTriangles == 200'000);
}

TEST_CASE("meshes past the triangle cap come simplified to even shares of what is left, over "
          "their own vertices, still spanning their size") {
    MeshOptions big;
    big.triangles = 5000;
    big.size = 0.1;
    MeshOptions smaller = big;
    smaller.triangles = 3000;
    smaller.shape = MeshShape::Torus;
    const auto a = generateMesh(big);
    const auto b = generateMesh(smaller);
    const auto small = tetrahedron(0.02);
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)},
                      {makeMesh(1, Vec3(0.2, 0, 0), a), makeMesh(2, Vec3(-0.2, 0, 0), b),
                       makeMesh(3, Vec3(0, 0.2, 0), small)});
    constexpr std::uint64_t kCap = 2004;
    const auto doc = nlohmann::json::parse(viewSceneJson(scene, {}, ViewMode::Live, kCap));
    // The tetrahedron fits whole (4); the two others share the remaining 2000, the smaller one
    // first: at most 1000 for it, at most what it left for the bigger one.
    const auto& tet = doc["objects"][2];
    CHECK(tet["trianglesShown"] == 4);
    CHECK(tet["triangles"].size() == 12);
    CHECK(doc["meshes"]["simplified"] == nlohmann::json::array({1, 2}));
    CHECK(doc["meshes"]["boxed"].empty());
    const std::uint64_t shownB = doc["objects"][1]["trianglesShown"];
    const std::uint64_t shownA = doc["objects"][0]["trianglesShown"];
    CHECK(shownB <= 1000);
    CHECK(shownA <= kCap - 4 - shownB);
    CHECK(doc["meshes"]["trianglesSent"] == 4 + shownA + shownB);
    for (const auto& [object, mesh] :
         {std::pair{doc["objects"][0], a}, std::pair{doc["objects"][1], b}}) {
        const std::uint64_t shown = object["trianglesShown"];
        CHECK(object["triangleCount"] == mesh->triangleCount());
        // meshoptimizer comes close to the share it is given, far below the mesh.
        CHECK(shown >= 500);
        CHECK(shown < mesh->triangleCount());
        REQUIRE(object["triangles"].size() == 3 * shown);
        const std::size_t vertexCount = object["vertices"].size() / 3;
        REQUIRE(object["vertices"].size() == 3 * vertexCount);
        for (const auto& i : object["triangles"]) {
            CHECK(i.get<std::size_t>() < vertexCount);
        }
        // Every vertex sent is one of the mesh's own (exactly), and together they still span
        // at least 90 % of the mesh's extent on every axis.
        Aabb spanned = Aabb::empty();
        for (std::size_t v = 0; v < vertexCount; ++v) {
            const Vec3 p(object["vertices"][3 * v], object["vertices"][3 * v + 1],
                         object["vertices"][3 * v + 2]);
            CHECK(std::find(mesh->vertices().begin(), mesh->vertices().end(), p) !=
                  mesh->vertices().end());
            spanned.expand(p);
        }
        const Vec3 full = mesh->localBounds().max - mesh->localBounds().min;
        const Vec3 kept = spanned.max - spanned.min;
        for (int axis = 0; axis < 3; ++axis) {
            CHECK(kept[axis] >= 0.9 * full[axis]);
        }
    }
}

TEST_CASE("a simplified mesh faces the way the original surface does") {
    MeshOptions fine; // about 10^5 triangles, brought to 2 x 10^4
    fine.triangles = 100000;
    fine.size = 0.1;
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)}, {makeMesh(1, Vec3(0.0), generateMesh(fine))});
    const auto doc = nlohmann::json::parse(viewSceneJson(scene, {}, ViewMode::Live, 20000));
    const auto& sphere = doc["objects"][0];
    REQUIRE(doc["meshes"]["simplified"] == nlohmann::json::array({1}));
    // Its triangles turned inwards (the normal against the centroid's direction from the
    // sphere's centre) cover under 0.05 % of its area; meshoptimizer's own output has 0.44 %
    // of it turned inwards here (ViewDocuments.cpp).
    const std::vector<double> v = sphere["vertices"];
    const std::vector<std::uint32_t> t = sphere["triangles"];
    const auto corner = [&](std::uint32_t i) { return Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]); };
    double area = 0.0, inwards = 0.0;
    for (std::size_t k = 0; k < t.size(); k += 3) {
        const Vec3 p = corner(t[k]), q = corner(t[k + 1]), r = corner(t[k + 2]);
        const Vec3 n = glm::cross(q - p, r - p);
        area += glm::length(n);
        if (glm::dot(n, p + q + r) < 0.0) {
            inwards += glm::length(n);
        }
    }
    CHECK(t.size() / 3 > 10000);
    CHECK(inwards < 5e-4 * area);
}

TEST_CASE("the trace document shows a version 2 trace's proxies in the world frame, a version 1 "
          "trace has none") {
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)}, {makeBox(3, Vec3(0.0), Vec3(0.01))});
    ViewTrace t;
    t.header.name = "right";
    t.header.rateHz = 1000;
    t.transform.translation = Vec3(0.0, 0.0, -0.05);
    // The point presses along z into the box's -z face (world z = -0.01); the proxy stays on it.
    for (std::uint64_t i = 0; i < 100; ++i) {
        TraceSample s;
        s.tick = i;
        s.timeNs = i * 1'000'000;
        s.positionM = Vec3(0.001, 0, 0.0006 * static_cast<double>(i));
        s.proxyM = Vec3(0.001, 0, std::min(s.positionM.z, 0.04));
        t.samples.push_back(s);
    }
    const auto doc = nlohmann::json::parse(viewTraceJson(scene, {t}, 100.0));
    const auto& frames = doc["devices"][0]["frames"];
    REQUIRE(frames.size() == 11);
    bool apart = false;
    for (const auto& f : frames) {
        REQUIRE(f.contains("proxy"));
        const double z = f["point"][2];
        CHECK(f["proxy"][0].get<double>() == Approx(0.001));
        CHECK(f["proxy"][2].get<double>() == Approx(std::min(z, -0.01)).margin(1e-12));
        apart = apart || f["proxy"][2].get<double>() < z - 1e-3;
    }
    CHECK(apart); // the proxy held back on the face while the point went in

    t.header.version = 1;
    const auto old = nlohmann::json::parse(viewTraceJson(scene, {t}, 100.0));
    for (const auto& f : old["devices"][0]["frames"]) {
        CHECK_FALSE(f.contains("proxy"));
    }
}

namespace {

/// One tick as the servo ran it: how late it woke after its deadline and how long it took from
/// waking to writing its force (ns).
struct ServoTick {
    std::uint64_t latenessNs = 2'000;
    std::uint64_t computeNs = 100'000;
};

/// The trace a 1 kHz servo records for `ticks` (ServoLoop.cpp): the first deadline
/// `firstDeadlineNs` into the session, each next one a period on, or past every slot a late
/// force overran. As a trace from before the miss marks (the view rebuilds the deadlines) unless
/// `marked`, when each missed tick carries its mark as the servo sets it.
ViewTrace servoTrace(const std::vector<ServoTick>& ticks, std::uint64_t firstDeadlineNs,
                     bool marked = false) {
    constexpr std::uint64_t kPeriodNs = 1'000'000;
    ViewTrace t;
    t.header.name = "left";
    t.header.rateHz = 1000;
    t.header.marksMisses = marked;
    std::uint64_t deadlineNs = firstDeadlineNs;
    for (std::uint64_t i = 0; i < ticks.size(); ++i) {
        TraceSample s;
        s.tick = i;
        s.timeNs = deadlineNs + ticks[i].latenessNs;
        s.computeNs = static_cast<std::uint32_t>(ticks[i].computeNs);
        const std::uint64_t doneNs = s.timeNs + s.computeNs;
        deadlineNs += kPeriodNs;
        s.missedDeadline = marked && doneNs > deadlineNs;
        t.samples.push_back(s);
        while (doneNs > deadlineNs) {
            deadlineNs += kPeriodNs;
        }
    }
    return t;
}

/// The misses each frame of the trace document's only device shows, with its tick count.
std::vector<std::pair<std::uint64_t, std::uint64_t>> ticksAndMisses(const ViewTrace& trace) {
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)}, {});
    const auto doc = nlohmann::json::parse(viewTraceJson(scene, {trace}, 60.0));
    std::vector<std::pair<std::uint64_t, std::uint64_t>> out;
    for (const auto& f : doc["devices"][0]["frames"]) {
        out.emplace_back(f["ticks"].get<std::uint64_t>(), f["misses"].get<std::uint64_t>());
    }
    return out;
}

} // namespace

TEST_CASE("the trace document counts the misses the runtime counted: a force written after the "
          "next deadline, the deadlines running from the first tick, which comes 2 ms into the "
          "session") {
    std::vector<ServoTick> ticks(2000);
    ticks[0].latenessNs = 0;           // on its deadline (as in the step mode): the chain is exact
    ticks[500].computeNs = 1'500'000;  // overruns the next deadline: a miss
    ticks[900].latenessNs = 2'500'000; // woke 2.5 periods late: a miss
    ticks[1200].computeNs = 1'000'000 - 2'000;     // written on the next deadline: on time
    ticks[1300].computeNs = 1'000'000 - 2'000 + 1; // 1 ns after it: a miss
    const auto frames = ticksAndMisses(servoTrace(ticks, 2'100'000));
    REQUIRE(frames.size() >= 100);
    for (const auto& [count, misses] : frames) {
        const std::uint64_t expected = (count > 500) + (count > 900) + (count > 1300);
        CHECK(misses == expected);
    }
    // The last frame is the last tick: the totals the run's report gives.
    CHECK(frames.back() == std::pair<std::uint64_t, std::uint64_t>{2000, 3});
}

TEST_CASE("the trace document's misses: a first tick that woke late and ticks the recorder "
          "dropped do not move the deadlines") {
    std::vector<ServoTick> ticks(1000);
    ticks[0].latenessNs = 60'000;                      // later than any other wake-up
    ticks[300].computeNs = 1'000'000 - 2'000 + 20'000; // 20 us past the next deadline: a miss
    ViewTrace trace = servoTrace(ticks, 1'900'000);
    // Ticks 400 to 599 never reached the file (the recorder's ring was full).
    trace.samples.erase(trace.samples.begin() + 400, trace.samples.begin() + 600);
    const auto frames = ticksAndMisses(trace);
    REQUIRE(frames.size() >= 40);
    for (const auto& [count, misses] : frames) {
        CHECK(misses == (count > 300 ? 1u : 0u));
    }
    CHECK(frames.back() == std::pair<std::uint64_t, std::uint64_t>{1000, 1});
}

TEST_CASE("the trace document's misses: after a miss whose force came just after one of the "
          "servo's slots, the next tick is on time, and two late ticks in a row are two misses") {
    // Every wake-up 30 us late: the trace cannot place the slots closer than that.
    std::vector<ServoTick> ticks(1000, ServoTick{30'000, 100'000});
    // Starved: its force comes 10 us after a slot, so the servo skips that one too (a miss).
    ticks[300] = {3'000'000 - 20'000, 30'000};
    // Two late wake-ups in a row, each a miss.
    ticks[600].latenessNs = 2'500'000;
    ticks[601].latenessNs = 1'500'000;
    const auto frames = ticksAndMisses(servoTrace(ticks, 2'000'000));
    REQUIRE(frames.size() >= 40);
    for (const auto& [count, misses] : frames) {
        const std::uint64_t expected = (count > 300) + (count > 600) + (count > 601);
        CHECK(misses == expected);
    }
    CHECK(frames.back() == std::pair<std::uint64_t, std::uint64_t>{1000, 3});
}

TEST_CASE("the trace document counts a marked trace's misses as the servo marked them, whatever "
          "the wake-ups would suggest") {
    // Ticks whose deadlines the wake-ups cannot place: every one woke 1.5 periods late, two of
    // them also overran; the servo marked exactly the ticks whose force came after the deadline.
    std::vector<ServoTick> ticks(1000);
    for (ServoTick& t : ticks) {
        t.latenessNs = 1'500'000;
    }
    ticks[300].computeNs = 900'000;
    ticks[700].computeNs = 2'000'000;
    const ViewTrace marked = servoTrace(ticks, 2'000'000, true);
    std::uint64_t marks = 0;
    for (const TraceSample& s : marked.samples) {
        marks += s.missedDeadline ? 1 : 0;
    }
    REQUIRE(marks == 1000); // each woke 1.5 periods late: each missed
    CHECK(ticksAndMisses(marked).back() == std::pair<std::uint64_t, std::uint64_t>{1000, 1000});

    // The same trace with only its last two ticks marked: the marks, not the times, decide.
    ViewTrace few = marked;
    for (TraceSample& s : few.samples) {
        s.missedDeadline = s.tick >= 998;
    }
    CHECK(ticksAndMisses(few).back() == std::pair<std::uint64_t, std::uint64_t>{1000, 2});
}
