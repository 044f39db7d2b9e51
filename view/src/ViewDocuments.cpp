// The scene and trace documents the page reads once (ViewDocuments.h).

#include "hapto/view/ViewDocuments.h"

#include "hapto/view/LoadWindow.h"

#include <nlohmann/json.hpp>

#include <cmath>

namespace hapto {
namespace {

nlohmann::json vec(const Vec3& v) {
    return nlohmann::json::array({v.x, v.y, v.z});
}

nlohmann::json quat(const Quat& q) {
    return nlohmann::json::array({q.w, q.x, q.y, q.z});
}

// Ids of the objects whose solid holds p, by brute force over their boxes first.
nlohmann::json containing(const Scene& scene, const Vec3& p) {
    nlohmann::json ids = nlohmann::json::array();
    for (const SceneObject& o : scene.objects()) {
        const Aabb box = o.aabb();
        if (glm::all(glm::greaterThanEqual(p, box.min)) &&
            glm::all(glm::lessThanEqual(p, box.max)) && o.contains(p)) {
            ids.push_back(o.id);
        }
    }
    return ids;
}

} // namespace

std::string viewSceneJson(const Scene& scene, const std::vector<ViewDevice>& devices,
                          ViewMode mode) {
    nlohmann::json objects = nlohmann::json::array();
    for (const SceneObject& o : scene.objects()) {
        objects.push_back({{"id", o.id},
                           {"shape", std::string(shapeName(o.shape))},
                           {"center", vec(o.center)},
                           {"halfExtents", vec(o.halfExtents)},
                           {"rotation", quat(o.rotation)}});
    }
    nlohmann::json devs = nlohmann::json::array();
    for (const ViewDevice& d : devices) {
        devs.push_back({{"name", d.name}, {"rateHz", d.rateHz}});
    }
    const nlohmann::json doc{
        {"mode", mode == ViewMode::Live ? "live" : "trace"},
        {"bounds", {{"min", vec(scene.bounds().min)}, {"max", vec(scene.bounds().max)}}},
        {"objects", objects},
        {"devices", devs}};
    return doc.dump();
}

std::string viewTraceJson(const Scene& scene, const std::vector<ViewTrace>& traces,
                          double frameHz) {
    nlohmann::json devices = nlohmann::json::array();
    double durationS = 0;
    for (const ViewTrace& trace : traces) {
        const double periodNs = 1e9 / trace.header.rateHz;
        LoadHistogram compute;
        LoadWindow window(periodNs, 1'000'000'000, static_cast<std::size_t>(frameHz) + 2);
        std::uint64_t misses = 0;
        const auto frameNs = static_cast<std::uint64_t>(1e9 / frameHz);
        bool first = true;
        std::uint64_t nextFrameNs = 0;
        nlohmann::json frames = nlohmann::json::array();
        for (const TraceSample& s : trace.samples) {
            compute.record(s.computeNs);
            // The deadline after this tick's is (tick + 1) periods from the start.
            const double writtenNs = static_cast<double>(s.timeNs) + s.computeNs;
            if (writtenNs > (static_cast<double>(s.tick) + 1.0) * periodNs) {
                ++misses;
            }
            if (!first && s.timeNs < nextFrameNs) {
                continue;
            }
            first = false;
            nextFrameNs = s.timeNs + frameNs;
            const WindowLoad load = window.sample(compute, s.timeNs);
            const Vec3 point = trace.transform.positionToWorld(s.positionM);
            const Vec3 force = trace.transform.forceToWorld(s.forceN);
            frames.push_back({{"t", static_cast<double>(s.timeNs) * 1e-9},
                              {"point", vec(point)},
                              {"force", vec(force)},
                              {"forceN", glm::length(force)},
                              {"contacts", containing(scene, point)},
                              {"ticks", s.tick + 1},
                              {"misses", misses},
                              {"loadP50", load.p50},
                              {"loadP999", load.p999}});
            durationS = std::max(durationS, static_cast<double>(s.timeNs) * 1e-9);
        }
        devices.push_back(
            {{"name", trace.header.name}, {"rateHz", trace.header.rateHz}, {"frames", frames}});
    }
    return nlohmann::json{{"durationS", durationS}, {"frameHz", frameHz}, {"devices", devices}}
        .dump();
}

} // namespace hapto
