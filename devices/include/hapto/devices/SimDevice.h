#pragma once
/// A simulated hand on a simulated device (`"kind": "sim"`): scripted, seeded, force-feeling.

#include "hapto/core/Random.h"
#include "hapto/devices/Device.h"
#include "hapto/devices/DeviceConfig.h"
#include "hapto/devices/HandModel.h"
#include "hapto/devices/SimScript.h"
#include "hapto/scenes/Scene.h"

#include <atomic>
#include <optional>
#include <string>

namespace hapto {

/// A device held by a simulated hand. At open() the script (SimConfig::script) is planned
/// against the scene in the world frame. Every read() advances time by exactly 1 / rate (and
/// periodsSkipped() by the periods the servo could not run): the script's target, converted into
/// the device frame, pulls the HandModel, and the force last written acts on it, so a hand pressing
/// on a surface feels the surface push back. Readings are quantised to SimConfig::resolutionM after
/// uniform noise of at most SimConfig::noiseM per axis. Same configuration, scene, written
/// forces and skipped periods, same readings, bit for bit; devices share nothing, so any number can
/// run at once. Button 0 is held while a grasp squeezes and carries.
///
/// The press is force-controlled. The script puts a press's target F / k_hand past the surface
/// (SimConfig::pressForceN, handStiffness), all the press on an unyielding surface; on one of
/// stiffness k the hand, a spring in series with it, would feel only F k / (k + k_hand) there.
/// While a stretch holds the press (ScriptKeyframe::pressing) and the hand feels the surface,
/// its target moves further in along the contact normal at a rate proportional to the shortfall
/// of the felt normal force (an integral controller of time constant kPressTimeS: no overshoot,
/// within 1 % in about 0.4 s at 1 kHz for 300..30000 N/m), so the steady force is F for any
/// stiffness; outside a press the extra depth fades with the same time constant.
class SimDevice final : public Device {
public:
    /// Keeps a reference to `scene`, which must outlive open(). Throws InputError when the
    /// configuration is not of kind "sim" or names an object the scene lacks. [control]
    SimDevice(const DeviceConfig& config, const Scene& scene);

    std::string_view name() const override { return mConfig.name; }
    DeviceKind kind() const override { return DeviceKind::Sim; }
    /// Workspace: the scene bounds, in the device frame, grown by 5 cm; max force: the
    /// configured one, else 10 N. [control]
    DeviceCapabilities capabilities() const override;
    /// Plans the script and puts the hand at rest at SimConfig::start. [control]
    DeviceStatus open() override;
    /// Stops the device; read/write then return NotOpen. [control]
    void close() override;
    /// Advances one tick of 1 / rate and reports position and velocity (device frame). [servo]
    DeviceStatus read(DeviceState& state) noexcept override;
    /// Time runs on by `periods` ticks that nobody read (the servo missed its deadlines), the
    /// hand moving under the force last written: two hands stay in step with each other and
    /// with the clock however often either thread is late. The hand is stepped through the
    /// last kMaxSkippedSteps of them (bounded work); earlier ones move only the script's
    /// clock. The step mode calls it only when the times a test gives make a tick miss. [servo]
    void periodsSkipped(std::uint64_t periods) noexcept override;
    /// Most hand steps one periodsSkipped() call takes (64 ms of hand at 1 kHz).
    static constexpr std::uint64_t kMaxSkippedSteps = 64;
    /// Time constant of the press's force control (s): a shortfall dF moves the target in at
    /// dF / (handStiffness kPressTimeS) m/s.
    static constexpr double kPressTimeS = 0.03;
    /// Most the press moves the target past the planned depth (m): F / k of a 75 N/m surface
    /// at 1.5 N; a press that cannot reach its force (a clamped device) stops there.
    static constexpr double kMaxPressExtraM = 0.02;
    /// The force (N, device frame) acting on the hand from the next read() on, clamped to the
    /// max force; a non-finite force is refused with BadData and zero force is applied. [servo]
    DeviceStatus write(const Vec3& forceN) noexcept override;
    /// The last failure. [control]
    std::string errorMessage() const override { return mError; }

    /// The script's current phase. [servo]
    ScriptPhase phase() const { return mPhase; }
    /// The phase as of the last read(), published for another thread (a relaxed atomic the
    /// servo stores every tick): a control loop waiting for the script to end reads this.
    /// [any thread]
    ScriptPhase publishedPhase() const noexcept {
        return mPublishedPhase.load(std::memory_order_relaxed);
    }
    /// The script's current target, world frame (m), before the press's extra depth. [servo]
    const Vec3& targetWorld() const { return mTargetWorld; }
    /// How far the press has moved the target past the script's (m, device frame, along the
    /// contact normal into the surface), >= 0. [servo]
    double pressExtraM() const { return mPressExtraM; }
    /// The hand's exact position (before noise and quantisation), device frame (m). [servo]
    const Vec3& handPosition() const { return mHand.position(); }
    /// The hand's exact position in the world (m). [servo]
    Vec3 handPositionWorld() const { return mConfig.transform.positionToWorld(mHand.position()); }
    /// Ticks since open, skipped periods included. [servo]
    std::uint64_t tick() const { return mTick; }
    /// Simulated time since open (s): tick / rate, skipped periods included. [servo]
    double timeS() const { return static_cast<double>(mTick) * mDtS; }
    /// The plan, once open. [control]
    const std::optional<SimScript>& script() const { return mScript; }
    /// The hand model (mass, stiffness, damping). [any thread]
    const HandModel& hand() const { return mHand; }
    /// The simulation settings. [any thread]
    const SimConfig& simConfig() const { return mSim; }

private:
    /// One tick of simulated time: the script's target pulls the hand, the force acts. [servo]
    void advance() noexcept;
    /// The press's force control for one tick (see the class comment). [servo]
    void adjustPress(bool pressing) noexcept;

    DeviceConfig mConfig;
    SimConfig mSim;
    const Scene* mScene;
    double mDtS;
    double mMaxForceN;
    HandModel mHand;
    Random mNoise;
    std::optional<SimScript> mScript;
    std::size_t mCursor = 0;
    std::uint64_t mTick = 0;
    Vec3 mForceN{0.0};
    Vec3 mTargetWorld{0.0};
    Vec3 mPressNormal{0.0}; // the script's contact normal, device frame (unit, or zero)
    double mPressExtraM = 0.0;
    ScriptPhase mPhase = ScriptPhase::Move;
    std::atomic<ScriptPhase> mPublishedPhase{ScriptPhase::Move};
    bool mOpen = false;
    std::string mError;
};

} // namespace hapto
