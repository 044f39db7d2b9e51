/// The haptic tick (see HapticTick.h for the sequence), and its side of the coupling to the
/// dynamic bodies.
///
/// Dynamic bodies (placeDynamic, splitReaction, handBack): the tick places them for the
/// renderer and hands the reaction of their contact force back to them.
///
/// Placing. Each tick reads every dynamic body's latest pose from the BodyPoseTable (a seqlock
/// read, no lock) and extrapolates it to the tick's time along its velocities (the centre of
/// mass by v t, the rotation by the exact rotation of a constant omega over t); at most
/// kMaxExtrapolationS either way, so a stalled dynamics thread leaves its bodies where they
/// were last seen rather than flying off. A body whose bounding sphere comes within the tick's
/// reach of the device point or the proxy (their distance, twice over for a friction lag, plus
/// 1 mm) is placed in the tick's DynamicBodySet and its slot becomes a candidate span: brute
/// force over the bodies, as the moving objects are, fine for the few bodies a scene holds.
///
/// The reaction (Newton's third law). The part of the force sent to the hand that the contacts
/// exert, felt = sent - (external + effects + hook), is split among the <= 3 contact planes
/// exactly: its normal part by solving G lambda = N^T felt (G the normals' Gram matrix; a
/// normal dependent on the others gets no share), and the rest (the friction, tangent to every
/// plane) in proportion to the planes' normal loads, as Coulomb friction is. The shares sum to
/// felt. handBack() adds -share x dt at the contact point (the proxy, on the body's skin) to
/// the share's body: linear, and about the centre of mass of the pose read. The table sums in
/// fixed point, so the impulses a body receives equal minus the force the hand was sent times
/// dt, tick by tick, to the 1e-12 N s quantum. A tick whose force is not sent (a miss rule's
/// zero, a failed write, a stop) hands nothing back. Nothing here allocates, locks or throws.

#include "hapto/runtime/HapticTick.h"

#include "hapto/core/Finite.h"
#include "hapto/runtime/Realtime.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace hapto {

namespace {

/// Walks every segment of the renderer's visited paths (where the proxy went in its last
/// update) leaf by leaf, with `walker` (a copy of the proxy's cursor, moved along the way, so
/// every leaf on it is located once). At each leaf not in `listed()` it
/// calls `onMissed(missed)`, which lists that leaf and returns true to walk on from where the
/// segment enters it, or returns false to stop there. Returns true when every leaf on the way
/// was listed, false when it stopped. [servo]
template <ForceAlgorithm Algorithm, class Listed, class OnMissed>
bool walkPaths(Cursor walker, const Algorithm& renderer, Listed&& listed,
               OnMissed&& onMissed) noexcept {
    for (int which = 0; which < 2; ++which) {
        const std::span<const Vec3> path = renderer.visitedPath(which);
        // The listed leaf box the last segment ended in: a segment inside it (a box is
        // convex) needs no walk.
        Aabb box{Vec3(1.0), Vec3(-1.0)};
        for (std::size_t i = 1; i < path.size(); ++i) {
            if (path[i] == path[i - 1] || (box.contains(path[i - 1]) && box.contains(path[i]))) {
                continue;
            }
            Vec3 a = path[i - 1];
            for (;;) {
                const SegmentWalk missed = walker.walkToFirstLeafNotIn(a, path[i], listed());
                box = missed.endBox;
                if (missed.covered()) {
                    break;
                }
                if (!onMissed(missed)) {
                    return false;
                }
                a += missed.t * (path[i] - a); // inside the leaf just listed
            }
        }
    }
    return true;
}

/// Tells the renderer that its next update() solves this tick again over more candidate
/// spans, when it can use that (GodObjectRenderer::extendNextUpdate). [servo]
template <ForceAlgorithm Algorithm> void solveAgainNext(Algorithm& renderer) noexcept {
    if constexpr (requires { renderer.extendNextUpdate(); }) {
        renderer.extendNextUpdate();
    }
}

} // namespace

template <ForceAlgorithm Algorithm>
BasicHapticTick<Algorithm>::BasicHapticTick(const RendererConfig& renderer,
                                            const SafetyConfig& safety)
    : mRenderer(renderer), mSafety(safety), mMaxStepM(renderer.maxProxyStepM),
      mCoupling(renderer.torsionRadiusM) {
    if (!(std::isfinite(mMaxStepM) && mMaxStepM > 0.0)) {
        throw std::invalid_argument("HapticTick: maxProxyStepM must be a finite value > 0 m (got " +
                                    std::to_string(mMaxStepM) + ")");
    }
}

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
    // A proxy that the last tick left behind its device point (on a surface, or held back)
    // solves toward a goal at most mMaxStepM from where it starts: the device point, or
    // the point that far along the way to it. A proxy that was at its device point follows
    // the device freely (a jump in free space). The device's leaf is listed only when the goal
    // is the device point; otherwise the leaves of the proxy's way are walked as always.
    const Vec3 from = mRenderer.proxy();
    const double lag = glm::length(p - from);
    const bool stepped = mLeftBehind && lag > mMaxStepM;
    const Vec3 goal = stepped ? from + (mMaxStepM / lag) * (p - from) : p;
    mCandidates.clear();
    if (!stepped) {
        mCandidates.add(atDevice.candidates);
    }
    if (stepped || atProxy.leaf != atDevice.leaf || atProxy.outside != atDevice.outside) {
        mCandidates.add(atProxy.candidates);
    }
    mCandidates.add(snapshot.movingSlots());
    placeDynamic(snapshot, p, dtS);
    out.bodiesPlaced = static_cast<std::uint8_t>(mCoupling.bodies().count);
    out.locateSteps = atDevice.steps + atProxy.steps;
    out.outside = atDevice.outside;
    out.deviceLeaf = atDevice.leaf;

    // 3. Render, over every leaf the proxy's way crosses (see render()).
    ListedLeaves listed;
    listed.leaves[0] = stepped ? atProxy.leaf : atDevice.leaf;
    listed.leaves[1] = atProxy.leaf;
    listed.count = 2;
    const detail::TickAim aim{p, goal, v, dtS, from};
    listSlide(aim, listed, out);
    stamp(1);
    render(*snapshot.scene, aim, listed, out);
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
    if (mCoupling.bodies().count > 0 || snapshot.restingCount > 0) {
        mCoupling.split(snapshot, out.render,
                        out.forceN - (externalForceN + out.effectsN + out.hookN), out.reactionN);
    }
    // 6. The leaves ahead of the proxy, into the cache for the ticks to come (no output
    // depends on it; DESIGN, "The leaves ahead").
    mBoundIndex->streamAhead(mStream, mProxyCursor.leaf(), mRenderer.proxy(),
                             mRenderer.proxy() - from);
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
        mStream = {};
        mBoundIndex = index;
        mBoundVersion = snapshot.version;
    }
    if (mFresh) {
        mRenderer.reset(p);
        mLeftBehind = false;
        mFresh = false;
    }
}

template <ForceAlgorithm Algorithm>
void BasicHapticTick<Algorithm>::listSlide(const detail::TickAim& aim, ListedLeaves& listed,
                                           TickOutput& out) noexcept {
    const Vec3& from = aim.from;
    // The likely slide (from the start along last tick's contact plane to the goal's
    // projection on it) is known before solving, so its first kSlideLeaves leaves are listed
    // first: a slide over small leaves usually solves once. Not more: a proxy trapped far
    // behind the hand has a slide centimetres long that it will not go far along, and its
    // leaves would cost their walks and items and take the room the solved way needs.
    const Vec3 slide = mRenderer.inContact()
                           ? aim.goal - glm::dot(aim.goal - from, mSlideNormal) * mSlideNormal
                           : from;
    // One walker along the slide: after a leaf is listed it walks on from where the slide
    // enters that leaf, so each leaf is located once.
    Cursor walker = mProxyCursor;
    Vec3 a = from;
    while (listed.count < listed.leaves.size() && listed.count < 2 + kSlideLeaves &&
           mRenderer.inContact()) {
        const SegmentWalk missed = walker.walkToFirstLeafNotIn(a, slide, listed.known());
        if (missed.at.leaf == kNoLeaf || !mCandidates.add(missed.at.candidates)) {
            break;
        }
        listed.leaves[listed.count++] = missed.at.leaf;
        // Its item list asked for now: the walk on to the next leaf overlaps the near list's
        // miss on it (DESIGN, "The leaves ahead").
        prefetchItems(missed.at.candidates);
        ++out.extraLeaves;
        a += missed.t * (slide - a); // inside the leaf just listed
    }
}

template <ForceAlgorithm Algorithm>
std::size_t BasicHapticTick<Algorithm>::listPaths(ListedLeaves& listed, bool& covered,
                                                  TickOutput& out) noexcept {
    // One walk over each segment: after a leaf is added the walk goes on from where the
    // segment enters it, so n leaves cost n steps along the way, not n walks from its start.
    std::size_t added = 0;
    covered = walkPaths(
        mProxyCursor, mRenderer, [&] { return listed.known(); },
        [&](const SegmentWalk& missed) {
            if (missed.unknown || listed.count == listed.leaves.size() ||
                !mCandidates.add(missed.at.candidates)) {
                return false;
            }
            listed.leaves[listed.count++] = missed.at.leaf;
            prefetchItems(missed.at.candidates); // as in listSlide
            ++out.extraLeaves;
            ++added;
            return true;
        });
    return added;
}

template <ForceAlgorithm Algorithm>
void BasicHapticTick<Algorithm>::render(const Scene& scene, const detail::TickAim& aim,
                                        ListedLeaves& listed, TickOutput& out) noexcept {
    const auto& [p, goal, v, dtS, from] = aim;
    // The candidates cover where the device and the proxy are, not every place the proxy
    // visits this tick: a proxy sliding over fine triangles (a mesh whose leaves are smaller
    // than one tick's motion, with the device in an empty leaf under the surface) can slide
    // off the triangles it knows, over a leaf nobody listed, and through the surface. So the
    // way the proxy went is walked leaf by leaf: every segment of the renderer's visited paths
    // (its start, each solver pass's end); when a leaf was not a candidate, the tick is solved
    // again from the same start with the items of every such leaf on the way too (the renderer
    // keeps its near list and reads only theirs), up to kExtraLeaves leaves in all; then, if
    // the way still leaves the listed leaves, the goal is pulled back.
    const typename Algorithm::State start = mRenderer.state(); // a plain copy: no allocation
    out.render = mRenderer.update(scene, mCandidates, p, goal, v, dtS);
    out.solves = 1;
    std::uint32_t tested = out.render.objectsTested;
    for (;;) {
        // Every leaf the paths cross that no span lists joins before solving again (as room
        // allows): the way solved again crosses most of them, so a proxy trapped far behind
        // a fast hand solves a few times, not once per leaf.
        bool covered = true;
        if (listPaths(listed, covered, out) == 0) {
            if (!covered) {
                pullBack(scene, aim, start, listed.known(), tested, out);
            }
            break;
        }
        mRenderer.restore(start);
        solveAgainNext(mRenderer);
        out.render = mRenderer.update(scene, mCandidates, p, goal, v, dtS);
        tested += out.render.objectsTested;
        ++out.solves;
    }
    out.render.objectsTested = tested;
    if (out.render.contactCount > 0) {
        mSlideNormal = out.render.contacts[0].normal;
    }
    mLeftBehind = out.render.proxy != p;
}

template <ForceAlgorithm Algorithm>
void BasicHapticTick<Algorithm>::pullBack(const Scene& scene, const detail::TickAim& aim,
                                          const typename Algorithm::State& start,
                                          std::span<const std::uint32_t> known,
                                          std::uint32_t& tested, TickOutput& out) noexcept {
    const auto& [p, target, v, dtS, from] = aim;
    // Out of room while the path still crosses a leaf no span lists (a very fast hand over
    // very small leaves, or a proxy trapped behind a hand that pushed through), or a walk that
    // could not finish: the proxy must not move through space whose items the renderer has not
    // seen. Solve again with the proxy's motion held to a goal pulled back from the tick's aim
    // (the device point, or the step toward it) toward the start, halving, then a nudge of
    // kNudgeM, until the path stays in listed leaves; the last try is the start itself (the
    // proxy stays, no contact, no force). The contacts and the force are the device point's:
    // the hand pushing in feels the surface as hard as ever, and the proxy never falls through
    // it. The first goal is halfway to where the straight way from the start to the aim leaves
    // the listed leaves (halfway to the aim when it does not): the proxy then moves up to half
    // a leaf in one more solve, where halving from the aim would try goals that each cross
    // unlisted leaves again, and end on the nudge.
    const double away = glm::length(target - from);
    const Vec3 nudge = away > kNudgeM ? from + (kNudgeM / away) * (target - from) : target;
    Vec3 goal = target;
    const double firstHalf = 0.5 * mProxyCursor.firstLeafNotIn(from, target, known).t;
    bool covered = false;
    for (int k = 0; !covered && k < kPullBacks; ++k) {
        const double keep = k == 0 ? firstHalf : 0.5;
        goal = k + 2 < kPullBacks ? from + keep * (goal - from) : k + 1 < kPullBacks ? nudge : from;
        mRenderer.restore(start);
        solveAgainNext(mRenderer);
        out.render = mRenderer.update(scene, mCandidates, p, goal, v, dtS);
        tested += out.render.objectsTested;
        ++out.pullBacks;
        ++out.solves;
        covered = walkPaths(
            mProxyCursor, mRenderer, [&] { return known; },
            [](const SegmentWalk&) { return false; });
    }
}

namespace coupling {

/// Extrapolation limit, either way (s).
constexpr double kMaxExtrapolationS = 0.05;
/// Margin of the placing ball (m), as the renderer's near list gives objects.
constexpr double kPlaceMarginM = 1e-3;
/// A Gram pivot below this leaves its plane without a normal share.
constexpr double kPivotEps = 1e-12;
/// A patch whose rim turns slower than this on the body (m/s) sticks: the torsional limit
/// takes the static friction, else the dynamic one (DynamicsOptions::stickSpeedMPerS's value,
/// the rule the dynamics' own friction patches use).
constexpr double kStickSpeedMPerS = 1e-2;

/// q turned by a constant angular velocity w (rad/s, world) over t seconds.
Quat advance(const Quat& q, const Vec3& w, double t) noexcept {
    const double rate = glm::length(w);
    if (!(rate * std::abs(t) > 0.0)) {
        return q;
    }
    return glm::normalize(glm::angleAxis(rate * t, w / rate) * q);
}

/// The render copy `b` (size, shape, bounding radius) at `pose` advanced by t seconds.
RenderBody placedBody(RenderBody b, const BodyPose& pose, double t) noexcept {
    const Quat rotation = advance(pose.rotation, pose.angularVelocity, t);
    const Vec3 com = pose.centerOfMass + pose.velocity * t;
    // The object's centre keeps its place in the body's frame.
    b.center = com + rotation * (glm::conjugate(pose.rotation) * (pose.center - pose.centerOfMass));
    if (b.shape != Shape::Sphere) {
        b.axes = glm::mat3_cast(rotation);
        b.axisAligned = b.axes == Mat3(1.0);
    }
    return b;
}

/// Body `body` (slot `slot`) as published in `pose`, advanced by t seconds, into `e`; false
/// when the result is not finite.
bool place(const Scene& scene, std::uint32_t slot, std::uint32_t body, const BodyPose& pose,
           double t, double dtS, DynamicBodySet::Entry& e) noexcept {
    e.slot = slot;
    e.body = body;
    e.velocity = pose.velocity;
    e.angularVelocity = pose.angularVelocity;
    e.centerOfMass = pose.centerOfMass + pose.velocity * t;
    e.rotation = advance(pose.rotation, pose.angularVelocity, t);
    e.massKg = scene.object(slot).body.massKg;
    e.render = placedBody(scene.body(slot), pose, t);
    e.center = e.render.center;
    e.previous = placedBody(scene.body(slot), pose, t - (std::isfinite(dtS) ? dtS : 0.0));
    return finite(e.center) && finite(e.centerOfMass) && finite(e.render.axes[0]) &&
           finite(e.render.axes[1]) && finite(e.render.axes[2]);
}

/// True when the table's `pose` is the body asleep at the rest pose `rest` (bit for bit).
bool restsAt(const BodyRest& rest, const BodyPose& pose) noexcept {
    return pose.sleeping && pose.center == rest.center && pose.rotation == rest.rotation;
}

/// Solves the k x k system a x = b (k <= 3) by elimination with partial pivoting; an unknown
/// whose pivot vanishes (a dependent normal) is 0.
std::array<double, 3> solveSmall(std::array<std::array<double, 3>, 3> a, std::array<double, 3> b,
                                 std::size_t k) noexcept {
    std::array<double, 3> x{};
    std::array<bool, 3> used{};
    std::array<std::size_t, 3> pivotRow{};
    for (std::size_t col = 0; col < k; ++col) {
        std::size_t best = k;
        for (std::size_t r = 0; r < k; ++r) {
            if (!used[r] && (best == k || std::abs(a[r][col]) > std::abs(a[best][col]))) {
                best = r;
            }
        }
        pivotRow[col] = k;
        if (best == k || std::abs(a[best][col]) <= kPivotEps) {
            continue;
        }
        used[best] = true;
        pivotRow[col] = best;
        for (std::size_t r = 0; r < k; ++r) {
            if (r != best) {
                const double f = a[r][col] / a[best][col];
                for (std::size_t c = 0; c < k; ++c) {
                    a[r][c] -= f * a[best][c];
                }
                b[r] -= f * b[best];
            }
        }
    }
    for (std::size_t col = 0; col < k; ++col) {
        if (pivotRow[col] < k) {
            x[col] = b[pivotRow[col]] / a[pivotRow[col]][col];
        }
    }
    return x;
}

} // namespace coupling

template <ForceAlgorithm Algorithm>
void BasicHapticTick<Algorithm>::placeDynamic(const WorldSnapshot& snapshot, const Vec3& p,
                                              double dtS) noexcept {
    const Vec3 proxy = mRenderer.proxy();
    const double reach = 2.0 * glm::length(proxy - p) + coupling::kPlaceMarginM;
    const DynamicBodySet* placed =
        mCoupling.place(snapshot, p, proxy, reach, dtS) ? &mCoupling.bodies() : nullptr;
    if (placed != nullptr) {
        mCandidates.add(placed->slotSpan());
    }
    if constexpr (requires { mRenderer.useDynamicBodies(placed); }) {
        mRenderer.useDynamicBodies(placed);
    }
}

template class BasicHapticTick<GodObjectRenderer>;

BodyCoupling::BodyCoupling(double torsionRadiusM) : mTorsionRadiusM(torsionRadiusM) {
    if (!(torsionRadiusM >= 0.0 && torsionRadiusM <= kMaxTorsionRadiusM)) {
        throw std::invalid_argument("the torsional radius (m) must be in 0.." +
                                    std::to_string(kMaxTorsionRadiusM) + " (got " +
                                    std::to_string(torsionRadiusM) + ")");
    }
}

bool BodyCoupling::place(const WorldSnapshot& snapshot, const Vec3& p, const Vec3& proxy,
                         double reachM, double dtS) noexcept {
    mPlaced.clear();
    mShareCount = 0;
    const std::span<const std::uint32_t> slots = snapshot.dynamicSlots();
    if (mTable == nullptr || slots.empty()) {
        return false;
    }
    mPlaced.active = true;
    const Scene& scene = *snapshot.scene;
    const std::size_t n = std::min(slots.size(), mTable->size());
    for (std::size_t i = 0; i < n && mPlaced.count < DynamicBodySet::kMaxBodies; ++i) {
        const BodyPose pose = mTable->read(i);
        // A body the snapshot indexed at rest: rendered from the index (a static object of the
        // snapshot's scene) while the table shows it asleep at that pose; awake or elsewhere,
        // its index copy is stale, so it is placed from the table wherever it is (the placed
        // pose then stands for every item of it: bodyAt).
        const bool indexed = i < snapshot.rest.size() && snapshot.rest[i].indexed;
        if (indexed && coupling::restsAt(snapshot.rest[i], pose)) {
            continue;
        }
        const double t =
            std::clamp((static_cast<double>(mNowNs) - static_cast<double>(pose.timeNs)) * 1e-9,
                       -coupling::kMaxExtrapolationS, coupling::kMaxExtrapolationS);
        DynamicBodySet::Entry& e = mPlaced.entries[mPlaced.count];
        if (slots[i] >= scene.size() ||
            !coupling::place(scene, slots[i], static_cast<std::uint32_t>(i), pose, t, dtS, e)) {
            continue;
        }
        const double near = e.render.radius + reachM;
        const double d2 = std::min(glm::dot(e.center - p, e.center - p),
                                   glm::dot(e.center - proxy, e.center - proxy));
        if (indexed || d2 <= near * near) {
            mPlaced.slots[mPlaced.count++] = slots[i];
        }
    }
    return true;
}

void BodyCoupling::split(const WorldSnapshot& snapshot, const RenderOutput& r, const Vec3& felt,
                         Vec3& reactionN) noexcept {
    const Scene& scene = *snapshot.scene;
    mShareCount = 0;
    const std::size_t k = std::min<std::size_t>(r.contactCount, 3);
    if (k == 0 || !finite(felt)) {
        return;
    }
    std::array<std::array<double, 3>, 3> gram{};
    std::array<double, 3> rhs{};
    for (std::size_t i = 0; i < k; ++i) {
        for (std::size_t j = 0; j < k; ++j) {
            gram[i][j] = glm::dot(r.contacts[i].normal, r.contacts[j].normal);
        }
        rhs[i] = glm::dot(r.contacts[i].normal, felt);
    }
    const std::array<double, 3> lambda = coupling::solveSmall(gram, rhs, k);
    Vec3 normalPart(0.0);
    double load = 0.0;
    for (std::size_t i = 0; i < k; ++i) {
        normalPart += lambda[i] * r.contacts[i].normal;
        load += std::max(lambda[i], 0.0);
    }
    const Vec3 tangent = felt - normalPart; // friction: tangent to every plane
    for (std::size_t i = 0; i < k; ++i) {
        const double weight = load > 0.0 ? std::max(lambda[i], 0.0) / load : 1.0 / double(k);
        const Vec3 share = lambda[i] * r.contacts[i].normal + weight * tangent;
        const std::uint32_t slot = scene.objectSlotOf(r.contacts[i].slot);
        const DynamicBodySet::Entry* e = mPlaced.find(slot);
        // A body rendered from the index (asleep at rest) takes its share as a placed one does:
        // the impulse wakes it in the next step, so no reaction is lost across the switch.
        const std::int64_t resting = e == nullptr ? snapshot.restingBodyAt(slot) : -1;
        if (e == nullptr && resting < 0) {
            continue;
        }
        const Vec3 n = r.contacts[i].normal;
        const Material& m = scene.object(slot).material;
        const double spin = e != nullptr ? std::abs(glm::dot(e->angularVelocity, n)) : 0.0;
        const double mu = spin * mTorsionRadiusM <= coupling::kStickSpeedMPerS ? m.staticFriction
                                                                               : m.dynamicFriction;
        const Vec3 com = e != nullptr
                             ? e->centerOfMass
                             : snapshot.rest[static_cast<std::size_t>(resting)].centerOfMass;
        const auto body = e != nullptr ? e->body : static_cast<std::uint32_t>(resting);
        mShares[mShareCount++] = {body, share, r.proxy - com, n,
                                  mu * std::max(lambda[i], 0.0) * mTorsionRadiusM};
        reactionN += share;
    }
}

bool BodyCoupling::handBack(double dtS) noexcept {
    bool ok = true;
    for (std::uint8_t i = 0; i < mShareCount && mTable != nullptr; ++i) {
        const Share& s = mShares[i];
        const Vec3 impulse = -s.forceN * dtS;
        ok = mTable->addImpulse(s.body, impulse, glm::cross(s.armM, impulse)) && ok;
        if (s.torsionNm > 0.0) {
            ok = mTable->addTorsion(s.body, s.normal, s.torsionNm * dtS) && ok;
        }
    }
    mShareCount = 0;
    return ok;
}

static_assert(sizeof(HapticTick) == 21312, "update the size in HapticTick.h");
static_assert(alignof(HapticTick) == 64);

} // namespace hapto
