#pragma once
/// The haptic tick, once: locate (device and proxy cursors) -> candidates -> render -> force
/// effects -> safety filter, for one device, real-time safe.

#include "hapto/devices/Device.h"
#include "hapto/index/Cursor.h"
#include "hapto/runtime/BodyCoupling.h"
#include "hapto/runtime/CandidateSet.h"
#include "hapto/runtime/Effects.h"
#include "hapto/runtime/ForceAlgorithm.h"
#include "hapto/runtime/ForceSafety.h"
#include "hapto/runtime/GodObjectRenderer.h"
#include "hapto/runtime/TickHook.h"
#include "hapto/runtime/World.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace hapto {

/// What one tick computed (world frame).
struct TickOutput {
    /// The renderer's result: proxy, contacts, objects tested, status, and its force (N)
    /// before effects, the external force and the safety filter.
    RenderOutput render;
    /// The force to send (N): render force + external force + effects + hook, through the
    /// safety filter.
    Vec3 forceN{0.0};
    Vec3 effectsN{0.0};         ///< The force effects' sum this tick (N), before the safety filter.
    Vec3 hookN{0.0};            ///< The hook's force this tick (N; zero when it was not finite).
    bool hookNonFinite = false; ///< The hook returned a non-finite force (replaced by zero).
    std::uint32_t locateSteps = 0;          ///< Cursor steps, both cursors.
    bool outside = false;                   ///< The device point is outside the index's bounds.
    std::uint32_t deviceLeaf = 0xFFFFFFFFu; ///< The device point's leaf (kNoLeaf outside).
    std::uint8_t extraLeaves = 0; ///< Leaves beyond the device's and the proxy's that the tick
                                  ///< listed: the slide's, before solving, and those the
                                  ///< solved proxy reached, solved again with them
                                  ///< (HapticTick::kExtraLeaves at most).
    /// Times the goal was pulled back toward the proxy's start because the proxy's path still
    /// crossed a leaf no span listed after kExtraLeaves (HapticTick::kPullBacks at most; the
    /// contacts and force stay the device point's; only the last, which keeps the proxy where
    /// it was, has no contact and no force).
    std::uint8_t pullBacks = 0;
    /// Times the renderer solved this tick: 1, plus one per time the solved proxy reached
    /// leaves no span listed (all of them join before it solves again), plus one per pull-back.
    std::uint8_t solves = 0;
    bool newSnapshot = false; ///< The snapshot differs from the previous tick's (cursors re-bound).
    /// The part of the force to send that dynamic bodies exert on the hand (N, world): what
    /// handBack() gives back to them, as impulse -reactionN x dtS (summed over the bodies).
    Vec3 reactionN{0.0};
    std::uint8_t bodiesPlaced = 0; ///< Dynamic bodies placed near the tool this tick.
};

namespace detail {
/// Leaves the proxy may slide into in one tick, solved again with their items
/// (CandidateSet has a span for each: device, proxy, moving, and these).
inline constexpr std::size_t kTickExtraLeaves = CandidateSet::kMaxSpans - 3;
/// Of those, the most the tick lists before solving, along the likely slide (listSlide() in
/// HapticTick.cpp): a slide over small leaves then solves once, and room is left for the
/// leaves the solved way reaches.
inline constexpr std::size_t kTickSlideLeaves = 4;
/// Goals pulled back when the proxy's path crosses more unlisted leaves than kTickExtraLeaves
/// (pullBack() in HapticTick.cpp): three halvings toward the proxy's start, kTickNudgeM from
/// it, the start itself; contacts and force stay the device point's, as hard as a full tick's.
inline constexpr int kTickPullBacks = 5;
/// The last pull-back but one moves the proxy at most this far (m): enough to meet the
/// surfaces it rests on that the device point is behind, so the tick keeps their contact and
/// force; 1 µm is inside the proxy's leaf unless it sits on the leaf's face.
inline constexpr double kTickNudgeM = 1e-6;

/// Where a tick's proxy starts and aims (m, m/s, s, world): the force is the device point's,
/// the solve goes toward `goal` (the device point, or the proxy's step toward it).
struct TickAim {
    Vec3 device{0.0};   ///< The device point.
    Vec3 goal{0.0};     ///< What the proxy solves toward.
    Vec3 velocity{0.0}; ///< The device point's velocity.
    double dtS = 0.0;   ///< Since the last tick.
    Vec3 from{0.0};     ///< The proxy at the tick's start.
};

/// The leaves a tick's candidate spans list (N at most): the device's, the proxy's, then the
/// extra ones, in the order their spans were added.
template <std::size_t N> struct ListedLeaves {
    std::array<std::uint32_t, N> leaves{}; ///< The leaves listed; the first `count` are set.
    std::size_t count = 0;                 ///< How many leaves are listed.
    /// The leaves listed so far. [servo]
    std::span<const std::uint32_t> known() const noexcept {
        return std::span<const std::uint32_t>(leaves.data(), count);
    }
};
} // namespace detail

/// The steady clock (ns, rt::nowNs) at the end of each of a tick's stages, in order: locate,
/// candidates (the slide's leaves listed before solving included), render (the walk over the
/// proxy's path, its re-solves and pull-backs included), effects (the hook included), safety.
/// `hapto bench tick` times the tick with them.
using TickStageStamps = std::array<std::uint64_t, 5>;

/// One device's haptic tick around a force algorithm (the seam: ForceAlgorithm.h; HapticTick
/// is the tick around the god-object renderer). Design note: the sequence every caller runs (the
/// servo step, ServoStep.h, which servo threads, the step mode, `hapto bench tick` and the
/// experiments run; and `hapto render`) lives here and nowhere else:
///   1. locate: the device point's cursor and the proxy's cursor each find their leaf (they
///      differ while the tool presses into a surface, the proxy resting on it);
///   2. candidates: the two leaves' object slots (the proxy's only when its leaf differs; the
///      device's only when the goal is the device point) and the snapshot's moving objects, as
///      spans (no copy);
///   3. render: the force algorithm (the god-object renderer) moves the proxy toward the goal
///      (the device point, or RendererConfig::maxProxyStepM toward it for a proxy the last
///      tick left behind: a proxy trapped centimetres behind a hand that pushed through reads
///      the leaves around it, not every leaf on the way to the hand)
///      and computes k (proxy - device), solved again with each leaf the proxy's way crossed
///      unlisted;
///   4. force effects and the hook: the device's EffectSet (springs, dampers, constant forces)
///      at the device point, then the application's per-tick hook, if any, are added to the
///      render force and the external force;
///   5. safety: ForceSafety clamps, rate-limits and sanitises the sum;
///   6. the leaves ahead: one step of the index's LeafStream along the proxy's way, which
///      prefetches the leaves the proxy is heading for (a hint: no output depends on it).
/// It holds the two cursors, the renderer, the safety filter and the candidate set, sized at
/// construction: tick() never allocates, locks, makes a syscall or throws. One instance per
/// device, used by one thread at a time. The caller owns the snapshot (it stays valid for the
/// tick) and the device side: reading, the frames, and what to do with the force.
///
/// Size: 21312 bytes, 64-byte aligned (checked by a static_assert in the source file), of
/// which 12416 are the renderer, 1288 the effect set (8 effects of 160 bytes) and 7024 the
/// coupling (BodyCoupling: the bodies placed for the tick, 16 entries, and their shares).
///
/// A template over the algorithm, instantiated in HapticTick.cpp for each one (today
/// GodObjectRenderer); a new algorithm adds its line there.
template <ForceAlgorithm Algorithm> class alignas(64) BasicHapticTick {
public:
    static constexpr std::size_t kExtraLeaves = detail::kTickExtraLeaves; ///< See there.
    static constexpr std::size_t kSlideLeaves = detail::kTickSlideLeaves; ///< See there.
    static constexpr int kPullBacks = detail::kTickPullBacks;             ///< See there.
    static constexpr double kNudgeM = detail::kTickNudgeM;                ///< See there (m).

    /// Checks both configurations (maxProxyStepM: finite, > 0), else invalid_argument. [control]
    explicit BasicHapticTick(const RendererConfig& renderer = {}, const SafetyConfig& safety = {});

    /// The next tick starts afresh: the proxy is put on that tick's device point with no
    /// contact, the cursors are bound to its snapshot, and the force grows from zero at the
    /// safety filter's rate. Counters are kept. [servo]
    void reset() noexcept;

    /// One tick for the device point `devicePointWorld` (m) moving at `velocityWorld` (m/s;
    /// not finite: estimated from the last point over dtS) against `snapshot`, `dtS` seconds
    /// after the last tick, with `externalForceN` (N, e.g. a carried object's weight), the
    /// effects' force and the hook's added before the safety filter. `sample` is the device's
    /// reading, handed to the hook. [servo]
    TickOutput tick(const WorldSnapshot& snapshot, const Vec3& devicePointWorld,
                    const Vec3& velocityWorld, double dtS, const Vec3& externalForceN,
                    const DeviceState& sample) noexcept;
    /// The same without a device reading (`hapto render`, the experiments): the hook, if any,
    /// sees a default DeviceState. [servo]
    TickOutput tick(const WorldSnapshot& snapshot, const Vec3& devicePointWorld,
                    const Vec3& velocityWorld, double dtS, const Vec3& externalForceN) noexcept;

    /// The dynamic bodies for the next tick(): their poses come from `table` (null: none),
    /// extrapolated to `t` (ns, the table's clock) (BodyCoupling). [servo]
    void placeBodies(BodyPoseTable* table, std::uint64_t t) noexcept { mCoupling.use(table, t); }
    /// The dynamic bodies the last tick placed. [servo]
    const DynamicBodySet& dynamicBodies() const noexcept { return mCoupling.bodies(); }
    /// The last tick's force was sent as computed: hands the touched dynamic bodies its
    /// reaction, once (BodyCoupling::handBack). False when the table refused one. [servo]
    bool handBack(double dtS) noexcept { return mCoupling.handBack(dtS); }

    /// Replaces the force effects from the next tick on (a copy, no allocation). [servo] (the
    /// thread that ticks; the Runtime's control side goes through Runtime::setEffects)
    void setEffects(const EffectSet& effects) noexcept { mEffects = effects; }
    /// The force effects. [servo]
    const EffectSet& effects() const noexcept { return mEffects; }
    /// Registers the per-tick hook (null fn: none), called from the next tick on; see
    /// TickHook.h for its rules. [control] before the first tick, or from the thread that
    /// ticks: it is a plain field, not synchronised.
    void setHook(const TickHook& hook) noexcept { mHook = hook; }

    using StageStamps = TickStageStamps; ///< The clock at each stage's end (TickStageStamps).
    /// From the next tick on, tick() writes the clock at each stage's end into `*stamps`;
    /// null (the default) reads no clock. [control] before the ticks it is for
    void timeStages(StageStamps* stamps) noexcept { mStamps = stamps; }

    /// The last force was not sent (a fault's zero): the next ramps up as after reset(). [servo]
    void zeroForce() noexcept { mSafety.reset(); }

    /// The proxy (m, world). [servo]
    const Vec3& proxy() const noexcept { return mRenderer.proxy(); }
    /// The force algorithm (the renderer's counters, configuration). [servo]
    const Algorithm& renderer() const noexcept { return mRenderer; }
    /// The safety filter; its counters() may be read from any thread. [any thread]
    const ForceSafety& safety() const noexcept { return mSafety; }

private:
    /// The leaves this tick's candidate spans list: the device's, the proxy's, the extra ones.
    using ListedLeaves = detail::ListedLeaves<2 + kExtraLeaves>;

    /// Writes the clock as stage `i`'s end when stages are timed. [servo]
    void stamp(std::size_t i) noexcept;
    /// Binds the cursors to a new snapshot's index, and the proxy to `p` on a fresh start.
    void bind(const WorldSnapshot& snapshot, const Vec3& p, TickOutput& out) noexcept;
    /// Lists the leaves of the likely slide (along the last contact plane) first.
    void listSlide(const detail::TickAim& aim, ListedLeaves& listed, TickOutput& out) noexcept;
    /// Lists the unlisted leaves the last paths cross (room allowing): how many; `covered`.
    std::size_t listPaths(ListedLeaves& listed, bool& covered, TickOutput& out) noexcept;
    /// Solves toward the goal, again with the unlisted leaves the way crosses; pulls back.
    void render(const Scene& scene, const detail::TickAim& aim, ListedLeaves& listed,
                TickOutput& out) noexcept;
    /// Solves toward goals pulled back from the goal toward the start (TickOutput::pullBacks).
    void pullBack(const Scene& scene, const detail::TickAim& aim,
                  const typename Algorithm::State& start, std::span<const std::uint32_t> known,
                  std::uint32_t& tested, TickOutput& out) noexcept;
    /// Places the dynamic bodies near `p` and the proxy for the renderer and the candidates.
    void placeDynamic(const WorldSnapshot& snapshot, const Vec3& p, double dtS) noexcept;

    Cursor mDeviceCursor; ///< The device point's leaf.
    Cursor mProxyCursor;  ///< The proxy's leaf.
    Algorithm mRenderer;  ///< The force algorithm.
    ForceSafety mSafety;
    CandidateSet mCandidates;                  ///< This tick's spans (views into the snapshot).
    LeafStream mStream;                        ///< The leaves ahead of the proxy, prefetched.
    EffectSet mEffects;                        ///< Springs, dampers, constant forces.
    TickHook mHook;                            ///< The application's per-tick hook, or none.
    const SpatialIndex* mBoundIndex = nullptr; ///< The index the cursors are bound to.
    Vec3 mSlideNormal{0.0}; ///< The last contact's first normal: the plane a proxy slides on.
    std::uint64_t mBoundVersion = 0; ///< The snapshot version they were bound for.
    StageStamps* mStamps = nullptr;  ///< Where tick() writes its stage ends, or none.
    bool mFresh = true;              ///< The next tick starts afresh (reset()).
    bool mLeftBehind = false;        ///< The last tick ended with the proxy off its device point.
    double mMaxStepM;                ///< RendererConfig::maxProxyStepM (m, world), as given.
    BodyCoupling mCoupling;          ///< The dynamic bodies placed, and their reaction.
};

static_assert(ForceAlgorithm<GodObjectRenderer>);
extern template class BasicHapticTick<GodObjectRenderer>;
/// The haptic tick around the god-object renderer: the one every caller runs today.
using HapticTick = BasicHapticTick<GodObjectRenderer>;

} // namespace hapto
