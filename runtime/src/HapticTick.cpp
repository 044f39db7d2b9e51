#include "hapto/runtime/HapticTick.h"

#include "hapto/core/Finite.h"

namespace hapto {

static_assert(sizeof(HapticTick) == 3072, "update the size in HapticTick.h");
static_assert(alignof(HapticTick) == 64);

HapticTick::HapticTick(const RendererConfig& renderer, const SafetyConfig& safety)
    : mRenderer(renderer), mSafety(safety) {}

void HapticTick::reset() noexcept {
    mFresh = true;
    mSafety.reset();
}

TickOutput HapticTick::tick(const WorldSnapshot& snapshot, const Vec3& p, const Vec3& v, double dtS,
                            const Vec3& externalForceN) noexcept {
    static constexpr DeviceState kNoSample{};
    return tick(snapshot, p, v, dtS, externalForceN, kNoSample);
}

TickOutput HapticTick::tick(const WorldSnapshot& snapshot, const Vec3& p, const Vec3& v, double dtS,
                            const Vec3& externalForceN, const DeviceState& sample) noexcept {
    TickOutput out;
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

    // 1. Locate both cursors. 2. Candidates: the device's leaf, the proxy's when it is
    // another leaf (or one is outside the bounds), and every moving object.
    const LocateResult atDevice = mDeviceCursor.locate(p);
    const LocateResult atProxy = mProxyCursor.locate(mRenderer.proxy());
    mCandidates.clear();
    mCandidates.add(atDevice.candidates);
    if (atProxy.leaf != atDevice.leaf || atProxy.outside != atDevice.outside) {
        mCandidates.add(atProxy.candidates);
    }
    mCandidates.add(snapshot.movingSlots());
    out.locateSteps = atDevice.steps + atProxy.steps;
    out.outside = atDevice.outside;
    out.deviceLeaf = atDevice.leaf;

    // 3. Render.
    out.render = mRenderer.update(*snapshot.scene, mCandidates, p, v, dtS);

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
    // 5. Safety.
    const Vec3 requested = out.render.force + externalForceN + out.effectsN + out.hookN;
    out.forceN = mSafety.filter(requested);
    return out;
}

} // namespace hapto
