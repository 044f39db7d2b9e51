#include "hapto/devices/SimDevice.h"

#include "hapto/core/Finite.h"

#include "hapto/io/InputError.h"

#include <algorithm>
#include <cmath>

namespace hapto {
namespace {

constexpr double kSimDefaultMaxForceN = 10.0;
constexpr std::uint64_t kNoiseStream = 0x5EED0F5E45011AAull; // noise apart from planning

const SimConfig& simOf(const DeviceConfig& config) {
    const auto* sim = std::get_if<SimConfig>(&config.params);
    if (config.kind != DeviceKind::Sim || !sim) {
        throw InputError("device '" + config.name +
                         "': a simulated device needs kind \"sim\" (got \"" +
                         std::string(name(config.kind)) + "\")");
    }
    return *sim;
}

double quantise(double v, double quantum) {
    return quantum > 0.0 ? std::round(v / quantum) * quantum : v;
}

} // namespace

SimDevice::SimDevice(const DeviceConfig& config, const Scene& scene)
    : mConfig(config), mSim(simOf(config)), mScene(&scene), mDtS(1.0 / config.rateHz),
      mMaxForceN(config.maxForceN > 0.0 ? config.maxForceN : kSimDefaultMaxForceN),
      mHand(mSim.handMassKg, mSim.handStiffness, mSim.handDampingRatio),
      mNoise(mSim.seed ^ kNoiseStream) {
    if (mSim.object && !scene.slotOf(*mSim.object)) {
        throw InputError("device '" + config.name + "': sim.object " +
                         std::to_string(*mSim.object) + " is not in the scene");
    }
}

DeviceCapabilities SimDevice::capabilities() const {
    DeviceCapabilities c;
    c.model = "simulated hand (" + std::string(hapto::name(mSim.script)) + ")";
    Aabb box = Aabb::empty();
    const Aabb& b = mScene->bounds();
    for (int i = 0; i < 8; ++i) {
        const Vec3 corner((i & 1) ? b.max.x : b.min.x, (i & 2) ? b.max.y : b.min.y,
                          (i & 4) ? b.max.z : b.min.z);
        box.expand(mConfig.transform.positionToDevice(corner));
    }
    box.expand(mSim.start);
    box.min -= Vec3(0.05);
    box.max += Vec3(0.05);
    c.workspace = box;
    c.maxForceN = mMaxForceN;
    c.maxStiffness = 2000.0;
    c.nominalRateHz = mConfig.rateHz;
    c.buttonCount = 1;
    return c;
}

DeviceStatus SimDevice::open() {
    try {
        mScript = SimScript::plan(mSim, *mScene, mConfig.transform.positionToWorld(mSim.start));
    } catch (const std::exception& e) {
        mError = "device '" + mConfig.name + "': " + e.what();
        mOpen = false;
        return DeviceStatus::Error;
    }
    mHand.reset(mSim.start);
    mNoise = Random(mSim.seed ^ kNoiseStream);
    mCursor = 0;
    mTick = 0;
    mForceN = Vec3(0.0);
    mTargetWorld = mConfig.transform.positionToWorld(mSim.start);
    mPressNormal = mConfig.transform.forceToDevice(mScript->contactNormal());
    mPressExtraM = 0.0;
    mPhase = mScript->keyframes().size() > 1 ? mScript->keyframes()[1].phase
                                             : mScript->keyframes()[0].phase;
    mPublishedPhase.store(mPhase, std::memory_order_relaxed);
    mError.clear();
    mOpen = true;
    return DeviceStatus::Ok;
}

void SimDevice::close() {
    mForceN = Vec3(0.0);
    mOpen = false;
}

DeviceStatus SimDevice::read(DeviceState& state) noexcept {
    if (!mOpen) {
        return DeviceStatus::NotOpen;
    }
    advance();
    const Vec3& p = mHand.position();
    for (int i = 0; i < 3; ++i) {
        const double noise = mSim.noiseM > 0.0 ? mNoise.uniform(-mSim.noiseM, mSim.noiseM) : 0.0;
        state.position[i] = quantise(p[i] + noise, mSim.resolutionM);
    }
    state.velocity = mHand.velocity();
    state.hasVelocity = true;
    // A scripted stylus, when the configuration gives one: a constant or turning orientation.
    const bool stylus = mSim.orientation.has_value() || mSim.spinRadPerS != Vec3(0.0);
    state.hasOrientation = stylus;
    state.hasAngularVelocity = stylus;
    if (stylus) {
        state.orientation = scriptedOrientation(mSim.orientation.value_or(Quat{1, 0, 0, 0}),
                                                mSim.spinRadPerS, timeS());
        state.angularVelocity = mSim.spinRadPerS;
    }
    const bool holding = mPhase == ScriptPhase::Squeeze || mPhase == ScriptPhase::Lift ||
                         mPhase == ScriptPhase::Carry || mPhase == ScriptPhase::PutDown;
    state.buttons = holding ? 1u : 0u;
    state.sequence = mTick;
    return DeviceStatus::Ok;
}

void SimDevice::periodsSkipped(std::uint64_t periods) noexcept {
    if (!mOpen) {
        return;
    }
    const std::uint64_t stepped = std::min(periods, kMaxSkippedSteps);
    mTick += periods - stepped;
    for (std::uint64_t i = 0; i < stepped; ++i) {
        advance();
    }
}

void SimDevice::advance() noexcept {
    ++mTick;
    const ScriptSample sample = mScript->targetAt(timeS(), mCursor);
    mTargetWorld = sample.target;
    mPhase = sample.phase;
    mPublishedPhase.store(mPhase, std::memory_order_relaxed);
    adjustPress(sample.pressing);
    mHand.step(mConfig.transform.positionToDevice(mTargetWorld) - mPressNormal * mPressExtraM,
               mForceN, mDtS);
}

void SimDevice::adjustPress(bool pressing) noexcept {
    const double felt = glm::dot(mForceN, mPressNormal); // the surface pushing the hand out
    if (pressing && felt > 0.0) {
        mPressExtraM += mDtS * (mSim.pressForceN - felt) / (mSim.handStiffness * kPressTimeS);
    } else if (!pressing) {
        mPressExtraM -= mPressExtraM * std::min(1.0, mDtS / kPressTimeS);
    }
    mPressExtraM = std::clamp(mPressExtraM, 0.0, kMaxPressExtraM);
}

DeviceStatus SimDevice::write(const Vec3& forceN) noexcept {
    if (!mOpen) {
        return DeviceStatus::NotOpen;
    }
    if (!finite(forceN)) {
        mForceN = Vec3(0.0);
        return DeviceStatus::BadData;
    }
    const double magnitude = glm::length(forceN);
    mForceN = magnitude > mMaxForceN ? forceN * (mMaxForceN / magnitude) : forceN;
    return DeviceStatus::Ok;
}

} // namespace hapto
