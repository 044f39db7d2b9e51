// The scene and trace documents the page reads once (ViewDocuments.h).

#include "hapto/view/ViewDocuments.h"

#include "hapto/scenes/TriangleMesh.h"
#include "hapto/view/LoadWindow.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <vector>

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

std::string viewSceneJson(const Scene& scene, const std::vector<ViewDevice>& devices, ViewMode mode,
                          std::uint64_t maxMeshTriangles) {
    nlohmann::json objects = nlohmann::json::array();
    nlohmann::json boxed = nlohmann::json::array();
    std::uint64_t sent = 0; // mesh triangles sent so far, in slot order
    for (const SceneObject& o : scene.objects()) {
        nlohmann::json object{{"id", o.id},
                              {"shape", std::string(shapeName(o.shape))},
                              {"center", vec(o.center)},
                              {"halfExtents", vec(o.halfExtents)},
                              {"rotation", quat(o.rotation)}};
        if (o.shape == Shape::Mesh && o.mesh) {
            const TriangleMesh& mesh = *o.mesh;
            object["triangleCount"] = mesh.triangleCount();
            if (sent + mesh.triangleCount() <= maxMeshTriangles) {
                sent += mesh.triangleCount();
                // Flat, in the object's own frame: x y z x y z ... and a b c a b c ...
                std::vector<double> vertices;
                vertices.reserve(3 * mesh.vertices().size());
                for (const Vec3& v : mesh.vertices()) {
                    vertices.insert(vertices.end(), {v.x, v.y, v.z});
                }
                std::vector<std::uint32_t> triangles;
                triangles.reserve(3 * mesh.triangles().size());
                for (const TriangleIndices& t : mesh.triangles()) {
                    triangles.insert(triangles.end(), t.begin(), t.end());
                }
                object["vertices"] = std::move(vertices);
                object["triangles"] = std::move(triangles);
            } else {
                // Over the cap: its local bounding box, drawn as a wireframe.
                object["localBounds"] = {{"min", vec(mesh.localBounds().min)},
                                         {"max", vec(mesh.localBounds().max)}};
                boxed.push_back(o.id);
            }
        }
        objects.push_back(std::move(object));
    }
    nlohmann::json devs = nlohmann::json::array();
    for (const ViewDevice& d : devices) {
        devs.push_back({{"name", d.name}, {"rateHz", d.rateHz}});
    }
    const nlohmann::json doc{
        {"mode", mode == ViewMode::Live ? "live" : "trace"},
        {"bounds", {{"min", vec(scene.bounds().min)}, {"max", vec(scene.bounds().max)}}},
        {"objects", objects},
        {"meshes", {{"maxTriangles", maxMeshTriangles}, {"trianglesSent", sent}, {"boxed", boxed}}},
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
            nlohmann::json frame{{"t", static_cast<double>(s.timeNs) * 1e-9},
                                 {"point", vec(point)},
                                 {"force", vec(force)},
                                 {"forceN", glm::length(force)},
                                 {"contacts", containing(scene, point)},
                                 {"ticks", s.tick + 1},
                                 {"misses", misses},
                                 {"loadP50", load.p50},
                                 {"loadP999", load.p999}};
            if (trace.header.version >= 2) {
                // Version 2 records the god-object proxy (device frame); version 1 has none.
                frame["proxy"] = vec(trace.transform.positionToWorld(s.proxyM));
            }
            frames.push_back(std::move(frame));
            durationS = std::max(durationS, static_cast<double>(s.timeNs) * 1e-9);
        }
        devices.push_back(
            {{"name", trace.header.name}, {"rateHz", trace.header.rateHz}, {"frames", frames}});
    }
    return nlohmann::json{{"durationS", durationS}, {"frameHz", frameHz}, {"devices", devices}}
        .dump();
}

} // namespace hapto
