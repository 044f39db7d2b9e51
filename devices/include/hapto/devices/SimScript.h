#pragma once
/// The motion plan of a simulated hand: timed world-frame targets, planned once at open().

#include "hapto/devices/DeviceConfig.h"
#include "hapto/scenes/Scene.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace hapto {

/// What a scripted hand is doing. Grasp scripts go Approach, Reach, Squeeze, Lift, Carry,
/// PutDown, Release, Done; a grasp of a dynamic body (BodyProperties::dynamic) goes on after
/// Release with Reach, Squeeze, Lift (GraspTimes::kDropHeightM), Drop, Done; touch goes Approach,
/// Press, Hold; slide Approach, Press, Slide; free and walk are always Move.
enum class ScriptPhase : std::uint8_t {
    Move,     ///< free, walk: moving between waypoints.
    Approach, ///< Travelling to a stand-off point 2 cm off the chosen surface.
    Press,    ///< touch, slide: moving in until pressing with the configured force.
    Hold,     ///< touch: pressing still.
    Slide,    ///< slide: pressing while moving back and forth along the surface.
    Reach,    ///< grasp: from the stand-off point to the object's side.
    Squeeze,  ///< grasp: pressing into the side (the other hand presses the opposite side).
    Lift,     ///< grasp: lifting the object by SimConfig::lift.
    Carry,    ///< grasp: carrying it by SimConfig::carry.
    PutDown,  ///< grasp: lowering it back by -lift.
    Release,  ///< grasp: backing off to the stand-off point.
    Done,     ///< grasp: released, holding still.
    Drop,     ///< grasp of a dynamic body: opening the hands with it lifted, so it falls.
};

/// Lower-case name of a phase ("approach", "put-down", ...). [any thread]
std::string_view scriptPhaseName(ScriptPhase phase);

/// One knot of a plan: at `timeS` the target is `target`; the stretch leading to it is `phase`.
struct ScriptKeyframe {
    double timeS = 0.0;                    ///< Time since open (s).
    Vec3 target{0.0};                      ///< Hand target, world (m).
    ScriptPhase phase = ScriptPhase::Move; ///< Phase of the stretch ending here.
    bool smooth = true;                    ///< Minimum-jerk from the previous knot (else linear).
    /// The stretch ending here holds a press (touch's hold, slide's slides, a grasp from the
    /// squeeze's hold to the put-down): the target is already pressed in, and the hand moves it
    /// further in or out until it feels SimConfig::pressForceN (SimDevice).
    bool pressing = false;
};

/// Where a plan has the hand at one time (SimScript::targetAt).
struct ScriptSample {
    Vec3 target{0.0};                      ///< Hand target, world (m).
    ScriptPhase phase = ScriptPhase::Move; ///< Phase of the stretch the time is in.
    bool pressing = false;                 ///< That stretch holds a press (ScriptKeyframe).
};

/// Fixed grasp timetable (s since open), the same for both hands so they squeeze, lift and
/// release together without sharing state.
struct GraspTimes {
    static constexpr double kApproachEnd = 3.0; ///< Both hands at their stand-off points.
    static constexpr double kReachEnd = 3.5;    ///< Touching the sides.
    static constexpr double kSqueezeEnd = 4.5;  ///< Pressing (0.5 s in, 0.5 s holding).
    static constexpr double kLiftEnd = 5.5;     ///< Lifted.
    static constexpr double kCarryEnd = 7.0;    ///< Carried.
    static constexpr double kPutDownEnd = 8.0;  ///< Put down.
    static constexpr double kReleaseEnd = 8.5;  ///< Backed off; Done from here on (static).
    // A dynamic body, set down on what is under it, is then grasped again and dropped:
    static constexpr double kRegraspEnd = 9.0;    ///< Touching its sides again.
    static constexpr double kResqueezeEnd = 10.0; ///< Pressing again (0.5 s in, 0.5 s holding).
    static constexpr double kDropLiftEnd = 10.75; ///< Lifted by kDropHeightM.
    static constexpr double kDropEnd = 10.9;      ///< Hands opened to the stand-off; Done.
    static constexpr double kDropHeightM = 0.04;  ///< The second lift, the drop's height (m).
};

/// A plan: keyframes, evaluated by time with a caller-held cursor, looping from `loopStart`
/// (plans that loop end where their loop starts). Built on the control thread; evaluation
/// allocates nothing.
class SimScript {
public:
    /// Plans `config.script` for a hand starting at `startWorld` (m) in `scene`, with `seed`
    /// for the random scripts. Throws InputError when `config.object` is not in the scene.
    /// Cost: free O(N + W K) for N objects, W waypoints, K objects near the start; walk O(W);
    /// touch, slide, grasp O(N). [control]
    static SimScript plan(const SimConfig& config, const Scene& scene, const Vec3& startWorld);

    /// A plan from explicit keyframes (first at time 0); loops from keyframe `loopStart` when
    /// set. [control]
    SimScript(std::vector<ScriptKeyframe> keyframes, std::optional<std::size_t> loopStart);

    /// Target (m, world), phase and press at `timeS`; `cursor` starts at 0 and is only ever
    /// handed back to this function (it makes evaluation O(1) for increasing times). [servo]
    ScriptSample targetAt(double timeS, std::size_t& cursor) const;

    /// The knots. [any thread]
    std::span<const ScriptKeyframe> keyframes() const { return mKeyframes; }
    /// Index of the keyframe the loop restarts from, if the plan loops. [any thread]
    std::optional<std::size_t> loopStart() const { return mLoopStart; }
    /// The object touched, slid on or grasped, if any. [any thread]
    std::optional<ObjectId> object() const { return mObject; }
    /// Outward surface normal (world) where touch/slide press or grasp squeezes. [any thread]
    const Vec3& contactNormal() const { return mContactNormal; }

private:
    std::vector<ScriptKeyframe> mKeyframes;
    std::optional<std::size_t> mLoopStart;
    std::optional<ObjectId> mObject;
    Vec3 mContactNormal{0.0};
};

/// A simulated stylus orientation at `timeS` (s): `start` turned at the constant angular
/// velocity `spinRadPerS` (rad/s, device frame) for `timeS`, i.e. a rotation of
/// |spin| * timeS about spin's direction applied after `start`; `start` itself for no spin.
/// Allocates nothing. [servo]
Quat scriptedOrientation(const Quat& start, const Vec3& spinRadPerS, double timeS) noexcept;

} // namespace hapto
