// The trace document's dynamic bodies (a bodies.trace replayed by `hapto view --trace`): each
// body's frames at the rate asked, placed by the object's centre, not its centre of mass.

#include "hapto/view/ViewDocuments.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

using namespace hapto;

TEST_CASE("the trace document places each recorded body by its object centre, frame by frame") {
    SceneObject box = makeBox(5, Vec3(0.0), Vec3(0.02));
    box.body.dynamic = true;
    box.body.massKg = 0.1;
    box.body.centerOfMassLocal = Vec3(0.01, 0.0, 0.0); // off centre, along its own x
    const Scene scene(Aabb{Vec3(-1.0), Vec3(1.0)}, {box});
    BodyTrace trace;
    trace.rateHz = 1000;
    trace.ids = {5};
    const Quat quarter = glm::angleAxis(glm::half_pi<double>(), Vec3(0, 0, 1)); // x -> y
    for (std::uint64_t k = 0; k <= 100; ++k) {                                  // 0.1 s at 1 kHz
        BodyTraceSample s;
        s.timeNs = k * 1'000'000;
        s.centerOfMass = Vec3(0.0, 0.1 - 0.001 * static_cast<double>(k), 0.0);
        s.rotation = quarter;
        trace.samples.push_back(s);
    }
    const auto doc = nlohmann::json::parse(viewTraceJson(scene, {}, 50.0, &trace));
    CHECK(doc["durationS"].get<double>() == Approx(0.1));
    REQUIRE(doc["bodies"].size() == 1);
    CHECK(doc["bodies"][0]["id"] == 5);
    const auto& frames = doc["bodies"][0]["frames"];
    REQUIRE(frames.size() == 6); // 0, 20, 40, 60, 80 and 100 ms
    for (std::size_t f = 0; f < frames.size(); ++f) {
        const double t = 0.02 * static_cast<double>(f);
        CHECK(frames[f]["t"].get<double>() == Approx(t));
        // The centre of mass sits 1 cm along the body's x, turned onto the world's y.
        CHECK(frames[f]["center"][0].get<double>() == Approx(0.0).margin(1e-12));
        CHECK(frames[f]["center"][1].get<double>() == Approx(0.1 - t - 0.01));
        CHECK(frames[f]["rotation"][0].get<double>() == Approx(quarter.w));
        CHECK(frames[f]["rotation"][3].get<double>() == Approx(quarter.z));
    }
    CHECK(!nlohmann::json::parse(viewTraceJson(scene, {}, 50.0)).contains("bodies"));
}
