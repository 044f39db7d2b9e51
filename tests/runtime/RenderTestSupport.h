#pragma once
/// Small helpers for the renderer tests: a scene with every slot as a candidate, and strokes.

#include "hapto/runtime/GodObjectRenderer.h"

#include <catch2/catch.hpp>

#include <cstdint>
#include <numeric>
#include <vector>

namespace hapto::test {

/// A scene plus a slot list naming every object (the list outlives the candidate views).
struct RenderRig {
    Scene scene;
    std::vector<std::uint32_t> slots;

    explicit RenderRig(std::vector<SceneObject> objects)
        : scene(Aabb{Vec3(-1.0), Vec3(1.0)}, std::move(objects)), slots(scene.size()) {
        std::iota(slots.begin(), slots.end(), 0u);
    }
    explicit RenderRig(Scene s) : scene(std::move(s)), slots(scene.size()) {
        std::iota(slots.begin(), slots.end(), 0u);
    }
    RenderRig(const RenderRig&) = delete;
    RenderRig& operator=(const RenderRig&) = delete;

    /// Every slot, as one span.
    CandidateSet all() const {
        CandidateSet c;
        c.add(slots);
        return c;
    }
};

/// Moves the device in `steps` equal ticks from `from` to `to` (1 kHz); returns the last output.
inline RenderOutput stroke(GodObjectRenderer& r, const RenderRig& rig, const Vec3& from,
                           const Vec3& to, int steps) {
    RenderOutput out;
    const CandidateSet c = rig.all();
    for (int i = 1; i <= steps; ++i) {
        const Vec3 p = from + (to - from) * (static_cast<double>(i) / steps);
        out = r.update(rig.scene, c, p, (to - from) * (1000.0 / steps), 1e-3);
    }
    return out;
}

/// Requires two ticks' outputs to be the same, bit for bit: status, proxy, force, and each
/// contact's item and normal.
inline void requireSameOutput(const RenderOutput& got, const RenderOutput& want) {
    REQUIRE(got.status == want.status);
    REQUIRE(got.proxy == want.proxy);
    REQUIRE(got.force == want.force);
    REQUIRE(got.contactCount == want.contactCount);
    for (std::uint32_t c = 0; c < got.contactCount; ++c) {
        REQUIRE(got.contacts[c].slot == want.contacts[c].slot);
        REQUIRE(got.contacts[c].normal == want.contacts[c].normal);
    }
}

/// Resets at `from` and strokes to `to`.
inline RenderOutput pressFrom(GodObjectRenderer& r, const RenderRig& rig, const Vec3& from,
                              const Vec3& to, int steps = 20) {
    r.reset(from);
    return stroke(r, rig, from, to, steps);
}

} // namespace hapto::test
