#include "hapto/runtime/HapticTick.h"

#include "hapto/core/Finite.h"
#include "hapto/runtime/Realtime.h"

#include <algorithm>
#include <array>

namespace hapto {

namespace {

/// The first leaf not in `listed` along any segment of the renderer's visited paths (where the
/// proxy went in its last update), if any; `walker` is the proxy's cursor. [servo]
template <ForceAlgorithm Algorithm>
SegmentWalk firstUnlistedOnPaths(const Cursor& walker, const Algorithm& renderer,
                                 std::span<const std::uint32_t> listed) noexcept {
    for (int which = 0; which < 2; ++which) {
        const std::span<const Vec3> path = renderer.visitedPath(which);
        // The listed leaf box the last segment ended in: a segment inside it (a box is
        // convex) needs no walk.
        Aabb box{Vec3(1.0), Vec3(-1.0)};
        for (std::size_t i = 1; i < path.size(); ++i) {
            if (path[i] == path[i - 1] || (box.contains(path[i - 1]) && box.contains(path[i]))) {
                continue;
            }
            const SegmentWalk missed = walker.firstLeafNotIn(path[i - 1], path[i], listed);
            box = missed.endBox;
            if (!missed.covered()) {
                return missed;
            }
        }
    }
    return {};
}

} // namespace

template <ForceAlgorithm Algorithm>
BasicHapticTick<Algorithm>::BasicHapticTick(const RendererConfig& renderer,
                                            const SafetyConfig& safety)
    : mRenderer(renderer), mSafety(safety) {}

template <ForceAlgorithm Algorithm> void BasicHapticTick<Algorithm>::stamp(std::size_t i) noexcept {
    if (mStamps != nullptr) {
        (*mStamps)[i] = rt::nowNs();
    }
}

template <ForceAlgorithm Algorithm> void BasicHapticTick<Algorithm>::reset() noexcept {
    mFresh = true;
    mSafety.reset();
}

template <ForceAlgorithm Algorithm>
TickOutput BasicHapticTick<Algorithm>::tick(const WorldSnapshot& snapshot, const Vec3& p,
                                            const Vec3& v, double dtS,
                                            const Vec3& externalForceN) noexcept {
    static constexpr DeviceState kNoSample{};
    return tick(snapshot, p, v, dtS, externalForceN, kNoSample);
}

template <ForceAlgorithm Algorithm>
TickOutput BasicHapticTick<Algorithm>::tick(const WorldSnapshot& snapshot, const Vec3& p,
                                            const Vec3& v, double dtS, const Vec3& externalForceN,
                                            const DeviceState& sample) noexcept {
    TickOutput out;
    bind(snapshot, p, out);

    // 1. Locate both cursors. 2. Candidates: the device's leaf, the proxy's when it is
    // another leaf (or one is outside the bounds), and every moving object.
    const LocateResult atDevice = mDeviceCursor.locate(p);
    const LocateResult atProxy = mProxyCursor.locate(mRenderer.proxy());
    stamp(0);
    mCandidates.clear();
    mCandidates.add(atDevice.candidates);
    if (atProxy.leaf != atDevice.leaf || atProxy.outside != atDevice.outside) {
        mCandidates.add(atProxy.candidates);
    }
    mCandidates.add(snapshot.movingSlots());
    out.locateSteps = atDevice.steps + atProxy.steps;
    out.outside = atDevice.outside;
    out.deviceLeaf = atDevice.leaf;

    // 3. Render, over every leaf the proxy's way crosses (see render()).
    ListedLeaves listed;
    listed.leaves[0] = atDevice.leaf;
    listed.leaves[1] = atProxy.leaf;
    listed.count = 2;
    const Vec3 from = mRenderer.proxy();
    listSlide(p, from, listed, out);
    stamp(1);
    render(*snapshot.scene, p, v, dtS, from, listed, out);
    stamp(2);

    // 4. Force effects at the device point, then the hook, and the external force. A hook
    // that returns NaN or infinity adds nothing (counted), like a renderer's non-finite output.
    out.effectsN = mEffects.forceN(p, v);
    if (mHook.fn) {
        const TickHookArgs args{
            sample,
            p,
            v,
            out.render.proxy,
            std::span<const Contact>(out.render.contacts.data(), out.render.contactCount),
            out.render.force,
            dtS};
        out.hookN = mHook.fn(mHook.context, args);
        if (!finite(out.hookN)) {
            out.hookN = Vec3(0.0);
            out.hookNonFinite = true;
        }
    }
    stamp(3);
    // 5. Safety.
    const Vec3 requested = out.render.force + externalForceN + out.effectsN + out.hookN;
    out.forceN = mSafety.filter(requested);
    stamp(4);
    return out;
}

template <ForceAlgorithm Algorithm>
void BasicHapticTick<Algorithm>::bind(const WorldSnapshot& snapshot, const Vec3& p,
                                      TickOutput& out) noexcept {
    // A new snapshot (or the first tick): the cursors re-bind to its index and forget their
    // leaves; a snapshot that only moved objects shares the index, but re-binding is cheap
    // and keeps "cursor leaf == fresh locate" without reasoning about which index it is.
    const SpatialIndex* index = snapshot.index.get();
    if (mFresh || snapshot.version != mBoundVersion || index != mBoundIndex) {
        out.newSnapshot = !mFresh;
        mDeviceCursor.reset(*index);
        mProxyCursor.reset(*index);
        mBoundIndex = index;
        mBoundVersion = snapshot.version;
    }
    if (mFresh) {
        mRenderer.reset(p);
        mFresh = false;
    }
}

template <ForceAlgorithm Algorithm>
void BasicHapticTick<Algorithm>::listSlide(const Vec3& p, const Vec3& from, ListedLeaves& listed,
                                           TickOutput& out) noexcept {
    // The likely slide (from the start along last tick's contact plane to the device point's
    // projection on it) is known before solving, so its leaves are listed first: a slide over
    // small leaves usually solves once.
    const Vec3 slide =
        mRenderer.inContact() ? p - glm::dot(p - from, mSlideNormal) * mSlideNormal : from;
    while (listed.count < listed.leaves.size() && mRenderer.inContact()) {
        const SegmentWalk missed = mProxyCursor.firstLeafNotIn(from, slide, listed.known());
        if (missed.at.leaf == kNoLeaf || !mCandidates.add(missed.at.candidates)) {
            break;
        }
        listed.leaves[listed.count++] = missed.at.leaf;
        ++out.extraLeaves;
    }
}

template <ForceAlgorithm Algorithm>
void BasicHapticTick<Algorithm>::render(const Scene& scene, const Vec3& p, const Vec3& v,
                                        double dtS, const Vec3& from, ListedLeaves& listed,
                                        TickOutput& out) noexcept {
    // The candidates cover where the device and the proxy are, not every place the proxy
    // visits this tick: a proxy sliding over fine triangles (a mesh whose leaves are smaller
    // than one tick's motion, with the device in an empty leaf under the surface) can slide
    // off the triangles it knows, over a leaf nobody listed, and through the surface. So the
    // way the proxy went is walked leaf by leaf: every segment of the renderer's visited paths
    // (its start, each solver pass's end); at the first leaf that was not a candidate the tick
    // is solved again from the same start with that leaf's items too, up to kExtraLeaves
    // times; then, if the way still leaves the listed leaves, the goal is pulled back.
    const typename Algorithm::State start = mRenderer.state(); // a plain copy: no allocation
    out.render = mRenderer.update(scene, mCandidates, p, v, dtS);
    out.solves = 1;
    std::uint32_t tested = out.render.objectsTested;
    for (;;) {
        const SegmentWalk missed = firstUnlistedOnPaths(mProxyCursor, mRenderer, listed.known());
        if (missed.covered()) {
            break;
        }
        if (missed.unknown || listed.count == listed.leaves.size() ||
            !mCandidates.add(missed.at.candidates)) {
            pullBack(scene, p, v, dtS, from, start, listed.known(), tested, out);
            break;
        }
        listed.leaves[listed.count++] = missed.at.leaf;
        mRenderer.restore(start);
        out.render = mRenderer.update(scene, mCandidates, p, v, dtS);
        tested += out.render.objectsTested;
        ++out.extraLeaves;
        ++out.solves;
    }
    out.render.objectsTested = tested;
    if (out.render.contactCount > 0) {
        mSlideNormal = out.render.contacts[0].normal;
    }
}

template <ForceAlgorithm Algorithm>
void BasicHapticTick<Algorithm>::pullBack(const Scene& scene, const Vec3& p, const Vec3& v,
                                          double dtS, const Vec3& from,
                                          const typename Algorithm::State& start,
                                          std::span<const std::uint32_t> known,
                                          std::uint32_t& tested, TickOutput& out) noexcept {
    // Out of room while the path still crosses a leaf no span lists (a very fast hand over
    // very small leaves, or a proxy trapped far behind a hand that pushed through), or a walk
    // that could not finish: the proxy must not move through space whose items the renderer
    // has not seen. Solve again with the proxy's motion held to a goal pulled back from the
    // device point toward the start, halving, then a nudge of kNudgeM, until the path stays in
    // listed leaves; the last try is the start itself (the proxy stays, no contact, no force).
    // The contacts and the force are the device point's: the hand pushing in feels the surface
    // as hard as ever, and the proxy never falls through it. The first goal is halfway to where
    // the straight way from the start to the device point leaves the listed leaves (halfway to
    // the device point when it does not): a proxy trapped centimetres behind then moves up to
    // half a leaf in one more solve, where halving from the device point would try goals
    // centimetres away, each crossing unlisted leaves again, and end on the nudge.
    const double away = glm::length(p - from);
    const Vec3 nudge = away > kNudgeM ? from + (kNudgeM / away) * (p - from) : p;
    Vec3 goal = p;
    const double firstHalf = 0.5 * mProxyCursor.firstLeafNotIn(from, p, known).t;
    bool covered = false;
    for (int k = 0; !covered && k < kPullBacks; ++k) {
        const double keep = k == 0 ? firstHalf : 0.5;
        goal = k + 2 < kPullBacks ? from + keep * (goal - from) : k + 1 < kPullBacks ? nudge : from;
        mRenderer.restore(start);
        out.render = mRenderer.update(scene, mCandidates, p, goal, v, dtS);
        tested += out.render.objectsTested;
        ++out.pullBacks;
        ++out.solves;
        covered = firstUnlistedOnPaths(mProxyCursor, mRenderer, known).covered();
    }
}

template class BasicHapticTick<GodObjectRenderer>;

static_assert(sizeof(HapticTick) == 12032, "update the size in HapticTick.h");
static_assert(alignof(HapticTick) == 64);

} // namespace hapto
