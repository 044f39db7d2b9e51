// The scene and trace documents the page reads.

#include "hapto/view/ViewDocuments.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

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
        t.samples.push_back(s);
    }
    const auto doc = nlohmann::json::parse(viewTraceJson(scene, {t}, 50.0));
    CHECK(doc["durationS"].get<double>() == Approx(0.98));
    const auto& frames = doc["devices"][0]["frames"];
    CHECK(doc["devices"][0]["name"] == "left");
    CHECK(frames.size() == 50); // one per 20 ms
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
