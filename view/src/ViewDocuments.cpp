// The scene and trace documents the page reads once (ViewDocuments.h).

#include "hapto/view/ViewDocuments.h"

#include "ViewJson.h"

#include "hapto/scenes/TriangleMesh.h"
#include "hapto/view/LoadWindow.h"

#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

namespace hapto {
namespace {

using detail::quat;
using detail::vec;

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

// A mesh as the page takes it: flat vertices (m, its own frame) and flat triangles.
struct PageMesh {
    std::vector<double> vertices;
    std::vector<std::uint32_t> triangles;
};

// The mesh's triangles as one flat list of vertex indices, three per triangle.
std::vector<std::uint32_t> flatTriangles(const TriangleMesh& mesh) {
    std::vector<std::uint32_t> flat;
    flat.reserve(3 * mesh.triangles().size());
    for (const TriangleIndices& t : mesh.triangles()) {
        flat.insert(flat.end(), t.begin(), t.end());
    }
    return flat;
}

// The whole mesh, exactly as held.
PageMesh wholeMesh(const TriangleMesh& mesh) {
    PageMesh out;
    out.vertices.reserve(3 * mesh.vertices().size());
    for (const Vec3& v : mesh.vertices()) {
        out.vertices.insert(out.vertices.end(), {v.x, v.y, v.z});
    }
    out.triangles = flatTriangles(mesh);
    return out;
}

// The mesh simplified by meshoptimizer to at most `budget` triangles, over the vertices it
// keeps (their original positions, renumbered); empty when it cannot be brought that low.
// meshopt_simplify collapses edges while keeping the surface's look; where the mesh's borders
// or seams stop it above the budget, meshopt_simplifySloppy (a vertex grid) takes over.
// meshoptimizer 0.18 checks each collapse against the triangle just before it, not the original
// surface (simplifier.cpp, hasTriangleFlip: "does triangle ABC flip when C is replaced with
// D?", a sign test), so after many collapses some triangles face inwards (5 % of them, 2 %
// of the area, for a 10^6-triangle sphere brought to 2 x 10^5), drawn as dark specks; each
// kept triangle is therefore turned, if need be, to face the way the original surface faces
// at its corners (the vertex normals: the sum of the area-weighted normals of the faces there).
PageMesh simplifiedMesh(const TriangleMesh& mesh, std::uint64_t budget) {
    if (budget == 0) {
        return {};
    }
    static_assert(std::is_same_v<std::uint32_t, unsigned int>, "meshoptimizer's index type");
    const std::vector<std::uint32_t> indices = flatTriangles(mesh);
    std::vector<float> positions;
    positions.reserve(3 * mesh.vertices().size());
    for (const Vec3& v : mesh.vertices()) {
        positions.insert(positions.end(), {static_cast<float>(v.x), static_cast<float>(v.y),
                                           static_cast<float>(v.z)});
    }
    const std::size_t target = 3 * static_cast<std::size_t>(budget);
    // Any error is allowed (1 = the mesh's whole extent): the count is what limits.
    constexpr float kAnyError = 1.0f;
    std::vector<unsigned int> kept(indices.size());
    std::size_t count =
        meshopt_simplify(kept.data(), indices.data(), indices.size(), positions.data(),
                         mesh.vertices().size(), 3 * sizeof(float), target, kAnyError, 0, nullptr);
    if (count > target) {
        count = meshopt_simplifySloppy(kept.data(), indices.data(), indices.size(),
                                       positions.data(), mesh.vertices().size(), 3 * sizeof(float),
                                       target, kAnyError, nullptr);
    }
    PageMesh out;
    if (count == 0 || count > target) {
        return out;
    }
    std::vector<Vec3> normals(mesh.vertices().size(), Vec3(0.0));
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const auto [p, q, r] = mesh.corners(t);
        const Vec3 n = glm::cross(q - p, r - p);
        for (const std::uint32_t v : mesh.triangles()[t]) {
            normals[v] += n;
        }
    }
    for (std::size_t i = 0; i < count; i += 3) {
        const Vec3& a = mesh.vertices()[kept[i]];
        const Vec3 n =
            glm::cross(mesh.vertices()[kept[i + 1]] - a, mesh.vertices()[kept[i + 2]] - a);
        if (glm::dot(n, normals[kept[i]] + normals[kept[i + 1]] + normals[kept[i + 2]]) < 0.0) {
            std::swap(kept[i + 1], kept[i + 2]);
        }
    }
    constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
    std::vector<std::uint32_t> renumber(mesh.vertices().size(), kUnused);
    out.triangles.reserve(count);
    for (std::size_t i = 0; i < count; ++i) {
        std::uint32_t& to = renumber[kept[i]];
        if (to == kUnused) {
            to = static_cast<std::uint32_t>(out.vertices.size() / 3);
            const Vec3& v = mesh.vertices()[kept[i]];
            out.vertices.insert(out.vertices.end(), {v.x, v.y, v.z});
        }
        out.triangles.push_back(to);
    }
    return out;
}

// The misses of a trace, as the runtime counted them. A trace whose header has
// kTraceHeaderMarksMisses marks each tick that missed its deadline, and those marks are counted
// as they are. Older traces do not: over them the runtime's missed-deadline rule (ServoStep.cpp,
// ServoStep::advanceDeadline) is replayed. Such a trace records each tick's wake-up (timeNs, since
// the session started) and its wake-up-to-force-written time (computeNs), not its deadline, so the
// deadlines are rebuilt the way the servo moves them: one period on after each tick and, when the
// force came after that (a miss), to the first slot after the force. The servo's first deadline is
// one period after its thread started (about 2 ms into the session) and its slots keep that phase,
// which the trace holds only through the wake-ups: each comes at or after its deadline, by the
// wake-up's lateness. So the chain starts at the first tick's wake-up and moves back when the trace
// shows it is later than the servo's:
//   - a tick that wakes before the deadline the chain gives it moves the chain back to its
//     wake-up (the servo never ticks before its deadline);
//   - after a miss, a tick that wakes a period or more after the chain's slot while that slot
//     came less than a quarter period after the missed force shows the servo's slot came just
//     before the force, so the servo skipped one more: the chain moves back to the force.
//     A tick after a miss whose own wake-up was a period late is told from it only by that
//     quarter period;
//   - after ticks the recorder dropped (a gap in the tick numbers, their times lost) the
//     deadline is the chain's last slot at or before the wake-up.
// The trace leaves the phase open by the wake-ups' lateness (it never holds a deadline), so a
// force written within that much of a slot can be counted otherwise than the runtime did; a
// restart after a fault (new slots, not recorded) looks like a late tick. Recordings of 2-3 s at
// 1-2 kHz (0 to 24 misses a device) gave the report's counts exactly; overloaded ones, without
// real-time scheduling (5-10 kHz, or 30 s with 4 % of the ticks missed), 0 to 2 % fewer.
class MissCounter {
public:
    MissCounter(std::uint64_t periodNs, bool marked) : mPeriodNs(periodNs), mMarked(marked) {}

    // Counts the tick if its force was written after the deadline after its own.
    void tick(const TraceSample& s) {
        if (mMarked) {
            mMisses += s.missedDeadline ? 1 : 0;
            return;
        }
        const std::uint64_t wakeNs = s.timeNs;
        if (!mStarted || wakeNs < mDeadlineNs) {
            mDeadlineNs = wakeNs;
        } else if (s.tick != mLastTick + 1) {
            mDeadlineNs += (wakeNs - mDeadlineNs) / mPeriodNs * mPeriodNs;
        } else if (mLastMissed && wakeNs - mDeadlineNs >= mPeriodNs &&
                   mDeadlineNs - mLastDoneNs < mPeriodNs / 4) {
            mDeadlineNs = mLastDoneNs + (wakeNs - mLastDoneNs) / mPeriodNs * mPeriodNs;
        }
        mStarted = true;
        mLastTick = s.tick;
        mLastDoneNs = wakeNs + s.computeNs;
        mDeadlineNs += mPeriodNs;
        mLastMissed = mLastDoneNs > mDeadlineNs;
        if (mLastMissed) {
            ++mMisses;
            mDeadlineNs += ((mLastDoneNs - mDeadlineNs) / mPeriodNs + 1) * mPeriodNs;
        }
    }
    std::uint64_t misses() const { return mMisses; }

private:
    std::uint64_t mPeriodNs;
    bool mMarked; // the trace marks its misses: count the marks
    bool mStarted = false;
    std::uint64_t mLastTick = 0;
    std::uint64_t mLastDoneNs = 0; // when the last tick wrote its force
    bool mLastMissed = false;
    std::uint64_t mDeadlineNs = 0; // the next tick's deadline, as the chain has it
    std::uint64_t mMisses = 0;
};

} // namespace

std::string viewSceneJson(const Scene& scene, const std::vector<ViewDevice>& devices, ViewMode mode,
                          std::uint64_t maxMeshTriangles) {
    // Meshes that fit the cap in slot order go whole; those that do not share what is left,
    // in ascending size, each at most an even share of the rest, simplified to it.
    const std::span<const SceneObject> all = scene.objects();
    std::vector<PageMesh> pageMeshes(all.size());
    std::vector<std::size_t> over; // slots of the meshes that did not fit whole
    std::uint64_t sent = 0;        // mesh triangles sent
    for (std::size_t i = 0; i < all.size(); ++i) {
        if (all[i].shape != Shape::Mesh || !all[i].mesh) {
            continue;
        }
        if (sent + all[i].mesh->triangleCount() <= maxMeshTriangles) {
            sent += all[i].mesh->triangleCount();
            pageMeshes[i] = wholeMesh(*all[i].mesh);
        } else {
            over.push_back(i);
        }
    }
    std::stable_sort(over.begin(), over.end(), [&](std::size_t a, std::size_t b) {
        return all[a].mesh->triangleCount() < all[b].mesh->triangleCount();
    });
    nlohmann::json simplified = nlohmann::json::array();
    for (std::size_t k = 0; k < over.size(); ++k) {
        const std::uint64_t share = (maxMeshTriangles - sent) / (over.size() - k);
        PageMesh m = simplifiedMesh(*all[over[k]].mesh, share);
        sent += m.triangles.size() / 3;
        pageMeshes[over[k]] = std::move(m);
    }

    nlohmann::json objects = nlohmann::json::array();
    nlohmann::json boxed = nlohmann::json::array();
    for (std::size_t i = 0; i < all.size(); ++i) {
        const SceneObject& o = all[i];
        nlohmann::json object{{"id", o.id},
                              {"shape", std::string(shapeName(o.shape))},
                              {"center", vec(o.center)},
                              {"halfExtents", vec(o.halfExtents)},
                              {"rotation", quat(o.rotation)}};
        if (o.shape == Shape::Mesh && o.mesh) {
            const TriangleMesh& mesh = *o.mesh;
            object["triangleCount"] = mesh.triangleCount();
            PageMesh& m = pageMeshes[i];
            if (!m.triangles.empty()) {
                object["trianglesShown"] = m.triangles.size() / 3;
                if (m.triangles.size() / 3 < mesh.triangleCount()) {
                    simplified.push_back(o.id);
                }
                // Flat, in the object's own frame: x y z x y z ... and a b c a b c ...
                object["vertices"] = std::move(m.vertices);
                object["triangles"] = std::move(m.triangles);
            } else {
                // Not even simplified within the cap: its local bounding box, as a wireframe.
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
        {"meshes",
         {{"maxTriangles", maxMeshTriangles},
          {"trianglesSent", sent},
          {"simplified", simplified},
          {"boxed", boxed}}},
        {"devices", devs}};
    return doc.dump();
}

namespace {

/// Each body's frames: at most one per frame time, and its last sample.
nlohmann::json bodyFramesJson(const Scene& scene, const BodyTrace& trace, double frameHz,
                              double& durationS) {
    const auto frameNs = static_cast<std::uint64_t>(1e9 / frameHz);
    nlohmann::json bodies = nlohmann::json::array();
    for (std::uint32_t b = 0; b < trace.ids.size(); ++b) {
        const auto slot = scene.slotOf(trace.ids[b]);
        const Vec3 comLocal = slot ? scene.object(*slot).body.centerOfMassLocal : Vec3(0.0);
        nlohmann::json frames = nlohmann::json::array();
        std::uint64_t nextFrameNs = 0;
        const BodyTraceSample* last = nullptr;
        const auto push = [&](const BodyTraceSample& s) {
            const Quat& q = s.rotation;
            frames.push_back({{"t", static_cast<double>(s.timeNs) * 1e-9},
                              {"center", vec(s.centerOfMass - glm::mat3_cast(q) * comLocal)},
                              {"rotation", {q.w, q.x, q.y, q.z}}});
            durationS = std::max(durationS, static_cast<double>(s.timeNs) * 1e-9);
        };
        for (const BodyTraceSample& s : trace.samples) {
            if (s.body != b) {
                continue;
            }
            last = &s;
            if (frames.empty() || s.timeNs >= nextFrameNs) {
                push(s);
                nextFrameNs = s.timeNs + frameNs;
                last = nullptr;
            }
        }
        if (last) {
            push(*last); // the player ends where the body ended
        }
        bodies.push_back({{"id", trace.ids[b]}, {"frames", frames}});
    }
    return bodies;
}

} // namespace

std::string viewTraceJson(const Scene& scene, const std::vector<ViewTrace>& traces, double frameHz,
                          const BodyTrace* bodyTrace) {
    nlohmann::json devices = nlohmann::json::array();
    double durationS = 0;
    for (const ViewTrace& trace : traces) {
        // The servo's period, rounded to the nanosecond as the runtime rounds it (Runtime.cpp).
        const auto periodNs = static_cast<std::uint64_t>(std::llround(1e9 / trace.header.rateHz));
        LoadHistogram compute;
        LoadWindow window(static_cast<double>(periodNs), 1'000'000'000,
                          static_cast<std::size_t>(frameHz) + 2);
        MissCounter misses(periodNs, trace.header.marksMisses);
        const auto frameNs = static_cast<std::uint64_t>(1e9 / frameHz);
        std::uint64_t nextFrameNs = 0;
        nlohmann::json frames = nlohmann::json::array();
        for (std::size_t i = 0; i < trace.samples.size(); ++i) {
            const TraceSample& s = trace.samples[i];
            compute.record(s.computeNs);
            misses.tick(s);
            // The first and the last tick are frames, so the player ends on the trace's totals.
            if (i > 0 && i + 1 < trace.samples.size() && s.timeNs < nextFrameNs) {
                continue;
            }
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
                                 {"misses", misses.misses()},
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
    nlohmann::json out{{"frameHz", frameHz}, {"devices", devices}};
    if (bodyTrace) {
        out["bodies"] = bodyFramesJson(scene, *bodyTrace, frameHz, durationS);
    }
    out["durationS"] = durationS;
    return out.dump();
}

} // namespace hapto
