// The adversarial motions of `hapto bench tick --motion` (experiments/TickMotion.h): each path
// does what its name claims, over the scene it claims, and the work counts that explain a
// motion's ticks are there. Behaviour only: the ticks run back to back and nothing here
// depends on how fast they run.

#include "hapto/experiments/TickBench.h"
#include "hapto/experiments/TickMotion.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

using namespace hapto;
using namespace hapto::experiments;

namespace {

MotionOptions small(std::size_t ticks = 2000) {
    MotionOptions o;
    o.objects = 1000;
    o.ticks = ticks;
    o.seed = 7;
    return o;
}

/// Distances between consecutive points after the approach (m).
std::vector<double> stepsOf(const MotionCase& c) {
    std::vector<double> out;
    for (std::size_t i = c.approachTicks + 1; i < c.path.size(); ++i) {
        out.push_back(glm::length(c.path[i] - c.path[i - 1]));
    }
    return out;
}

double distanceToSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 ab = b - a;
    const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
    return glm::length(p - (a + t * ab));
}

/// Distance from p to the nearest of a box's twelve edges (m).
double distanceToEdges(const Vec3& p, const Aabb& box) {
    double best = std::numeric_limits<double>::max();
    for (int axis = 0; axis < 3; ++axis) {
        for (int corner = 0; corner < 4; ++corner) {
            Vec3 a, b;
            for (int k = 0, bit = 0; k < 3; ++k) {
                if (k == axis) {
                    a[k] = box.min[k];
                    b[k] = box.max[k];
                } else {
                    a[k] = b[k] = ((corner >> bit++) & 1) != 0 ? box.max[k] : box.min[k];
                }
            }
            best = std::min(best, distanceToSegment(p, a, b));
        }
    }
    return best;
}

bool inSomeObject(const Scene& scene, const Vec3& p) {
    return std::any_of(scene.objects().begin(), scene.objects().end(),
                       [&](const SceneObject& o) { return o.contains(p); });
}

/// What a run's ticks did, summed.
struct Work {
    std::uint64_t ticks = 0, contactTicks = 0, solves = 0, extraLeaves = 0, passes = 0,
                  facetsEntered = 0, candidates = 0;
    std::size_t counts = 0;
    std::size_t bodyContactTicks = 0; ///< Ticks in contact with a dynamic body placed.
    std::uint64_t workDiffered = 0;   ///< Ticks whose work differed between repeats.
};

/// One motion run hot over its own scene, as `bench tick --motion` runs it.
Work runMotion(TickMotion motion, std::size_t ticks, std::size_t repeats = 1) {
    const MotionCase c = makeMotionCase(motion, small(ticks));
    TickBenchSettings s;
    s.indices = {c.index};
    s.ticks = ticks;
    s.modes = {TickMode::Hot};
    s.path = c.path;
    s.walkIn = c.path.empty() ? c.walkIn : c.scene.bounds();
    s.pushMm = c.pushMm;
    s.bodyPoses = c.bodyPoses;
    s.repeats = repeats;
    const std::vector<TickTarget> targets = runTickBench(c.scene, s);
    const TickRun& r = *targets.front().runs.front();
    Work w{r.ticks,  r.contactTicks,  r.solves,     r.extraLeaves,
           r.passes, r.facetsEntered, r.candidates, r.counts.size()};
    for (const TickCounts& k : r.counts) {
        w.bodyContactTicks += k.bodies > 0 && k.contacts > 0 ? 1 : 0;
    }
    w.workDiffered = r.workDiffered;
    return w;
}

} // namespace

TEST_CASE("motion names round-trip and unknown ones are refused") {
    for (const TickMotion m : kTickMotions) {
        REQUIRE(parseTickMotion(tickMotionName(m)) == m);
    }
    CHECK_FALSE(parseTickMotion("spin").has_value());
    CHECK_FALSE(parseTickMotion("").has_value());
    CHECK(tickMotionNames() == "rest, walk, trapped, sweep, graze, sphere, slabs, body");
}

TEST_CASE("every motion's path has a point per tick and is the same for the same seed") {
    for (const TickMotion m : kTickMotions) {
        const MotionCase a = makeMotionCase(m, small(1500));
        const MotionCase b = makeMotionCase(m, small(1500));
        INFO(tickMotionName(m));
        if (m == TickMotion::Walk) {
            CHECK(a.path.empty());
            CHECK(a.pushMm == 2.0);
            continue;
        }
        REQUIRE(a.path.size() == 1500);
        CHECK(a.path == b.path);
        CHECK(a.pushMm == 0.0);
        CHECK(a.approachTicks < 100);
        for (const Vec3& p : a.path) {
            REQUIRE(a.scene.bounds().contains(p));
        }
    }
}

TEST_CASE("the trapped hand walks inside the dense cubes' central half") {
    const MotionCase c = makeMotionCase(TickMotion::Trapped, small());
    const Aabb& b = c.scene.bounds();
    const Vec3 quarter = 0.25 * (b.max - b.min);
    std::size_t inside = 0;
    for (const Vec3& p : c.path) {
        REQUIRE(glm::all(glm::greaterThanEqual(p, b.min + quarter - Vec3(1e-12))));
        REQUIRE(glm::all(glm::lessThanEqual(p, b.max - quarter + Vec3(1e-12))));
        inside += inSomeObject(c.scene, p) ? 1 : 0;
    }
    // 10^3 cubes of 2 mm in 2.5 cm fill half the space they are in: the hand is inside a cube
    // for much of its walk.
    CHECK(inside > c.path.size() / 4);
    CHECK(c.scene.size() == 1000);
}

TEST_CASE("the sweep moves at 1 m/s in straight lines") {
    const MotionCase c = makeMotionCase(TickMotion::Sweep, small());
    const std::vector<double> steps = stepsOf(c);
    std::size_t exact = 0;
    for (const double d : steps) {
        REQUIRE(d <= 1e-3 + 1e-12);
        exact += std::abs(d - 1e-3) < 1e-9 ? 1 : 0;
    }
    // Only the steps cutting a corner of the polyline are shorter: one in about 12 over the
    // 2.5 cm work cube of 10^3 cubes, one in about 100 over 10^6.
    CHECK(exact > steps.size() * 85 / 100);
}

TEST_CASE("the grazing hand runs 0.1 mm under the lattice's top on the lines where cubes meet") {
    const MotionCase c = makeMotionCase(TickMotion::Graze, small());
    double top = -1.0;
    for (const SceneObject& o : c.scene.objects()) {
        top = std::max(top, o.aabb().max.y);
    }
    std::vector<Aabb> topLayer;
    for (const SceneObject& o : c.scene.objects()) {
        if (o.aabb().max.y > top - 1e-9) {
            topLayer.push_back(o.aabb());
        }
    }
    REQUIRE(topLayer.size() == 100); // 10 x 10 of the 10^3 cubes
    std::size_t onVertices = 0;
    for (std::size_t i = c.approachTicks; i < c.path.size(); ++i) {
        const Vec3& p = c.path[i];
        REQUIRE(p.y == Approx(top - kGrazeDepthM).margin(1e-9));
        double nearest = std::numeric_limits<double>::max();
        std::size_t touching = 0;
        for (const Aabb& box : topLayer) {
            nearest = std::min(nearest, distanceToEdges(p, box));
            // Within the generator's 1 um rounding of the centres.
            touching += Aabb{box.min - Vec3(2e-6), box.max + Vec3(2e-6)}.contains(p) ? 1 : 0;
        }
        // On a shared edge (1 um: the generator rounds centres to 1 um).
        REQUIRE(nearest <= kGrazeDepthM + 2e-6);
        REQUIRE(touching >= 2);
        onVertices += touching >= 4 ? 1 : 0;
    }
    CHECK(onVertices > 0);
    for (const double d : stepsOf(c)) {
        REQUIRE(d <= 0.5e-3 + 1e-12);
    }
}

TEST_CASE("the sphere's hand slides 1 mm inside its surface at 0.5 m/s") {
    const MotionCase c = makeMotionCase(TickMotion::Sphere, small());
    const double r = 0.5 * kSphereDiameterM - kSphereDepthM;
    for (std::size_t i = c.approachTicks; i < c.path.size(); ++i) {
        REQUIRE(glm::length(c.path[i]) == Approx(r).margin(1e-9));
    }
    for (std::size_t i = c.approachTicks + 1; i < c.path.size(); ++i) {
        REQUIRE(glm::length(c.path[i] - c.path[i - 1]) == Approx(0.5e-3).margin(1e-8));
    }
    CHECK(c.path.front().x * c.path.front().x + c.path.front().y * c.path.front().y +
              c.path.front().z * c.path.front().z >
          0.05 * 0.05); // it comes in from outside
}

TEST_CASE("the slab hand crosses the whole stack down and up at 1 m/s") {
    const MotionCase c = makeMotionCase(TickMotion::Slabs, small());
    REQUIRE(c.scene.size() == static_cast<std::uint32_t>(kSlabCount));
    double lowSlab = 1.0, highSlab = -1.0;
    for (const SceneObject& o : c.scene.objects()) {
        lowSlab = std::min(lowSlab, o.aabb().min.y);
        highSlab = std::max(highSlab, o.aabb().max.y);
        CHECK(o.aabb().max.y - o.aabb().min.y == Approx(kSlabThicknessM));
    }
    std::size_t crossings = 0;
    bool below = false;
    for (const Vec3& p : c.path) {
        if (!below && p.y < lowSlab) {
            below = true;
            ++crossings;
        } else if (below && p.y > highSlab) {
            below = false;
            ++crossings;
        }
    }
    CHECK(crossings >= 2000 / 30); // a crossing of 26 mm, 1-5 mm aslant, takes 26-27 ticks
    for (const double d : stepsOf(c)) {
        REQUIRE(d <= 1e-3 + 1e-12);
    }
}

TEST_CASE("the body's poses swing it 2 cm either way once a second under a resting hand") {
    const MotionCase c = makeMotionCase(TickMotion::Body, small());
    REQUIRE(c.bodyPoses.size() == c.path.size());
    REQUIRE(c.scene.object(0).body.dynamic);
    double lo = 1.0, hi = -1.0;
    for (const BodyPose& p : c.bodyPoses) {
        lo = std::min(lo, p.center.x);
        hi = std::max(hi, p.center.x);
    }
    CHECK(lo == Approx(-kBodySwingM).margin(1e-6));
    CHECK(hi == Approx(kBodySwingM).margin(1e-6));
    CHECK(c.bodyPoses[1000].center.x == Approx(0.0).margin(1e-12)); // one period
    CHECK(c.path.back().y == Approx(0.01 - 0.001));
}

TEST_CASE("the resting hand comes down and rests 0.5 mm inside a top face") {
    const MotionCase c = makeMotionCase(TickMotion::Rest, small());
    const Vec3 rest = c.path.back();
    for (std::size_t i = c.approachTicks; i < c.path.size(); ++i) {
        REQUIRE(c.path[i] == rest);
    }
    REQUIRE(inSomeObject(c.scene, rest));
    CHECK_FALSE(inSomeObject(c.scene, rest + Vec3(0.0, kRestDepthM + 1e-6, 0.0)));
    CHECK(c.path.front().y == Approx(rest.y + 0.003));
}

TEST_CASE("each motion's ticks do the work that explains them", "[threads]") {
    constexpr std::size_t kTicks = 1500;
    SECTION("rest: in contact once down, one face, one solve") {
        const Work r = runMotion(TickMotion::Rest, kTicks);
        CHECK(r.contactTicks >= kTicks - 40);
        CHECK(r.solves == r.ticks);
        CHECK(r.facetsEntered == 1);
        CHECK(r.candidates > 0);
    }
    SECTION("trapped: extra leaves and re-solves") {
        const Work r = runMotion(TickMotion::Trapped, kTicks);
        CHECK(r.extraLeaves > 0);
        CHECK(r.solves > r.ticks);
        CHECK(r.contactTicks > kTicks / 2);
    }
    SECTION("sweep: leaves crossed in a tick and re-solves") {
        const Work r = runMotion(TickMotion::Sweep, kTicks);
        CHECK(r.extraLeaves > 0);
        CHECK(r.solves > r.ticks);
        CHECK(r.facetsEntered > 0);
    }
    SECTION("graze: in contact throughout, onto a new face every tile") {
        const Work r = runMotion(TickMotion::Graze, kTicks);
        CHECK(r.contactTicks >= kTicks - 40);
        CHECK(r.facetsEntered > kTicks / 8); // a tile every 4 ticks
    }
    SECTION("sphere: in contact throughout, onto new triangles") {
        const Work r = runMotion(TickMotion::Sphere, kTicks);
        CHECK(r.contactTicks >= kTicks - 20);
        CHECK(r.facetsEntered > 10);
        CHECK(r.passes > r.ticks);
    }
    SECTION("slabs: held on the top slab while the hand goes through them all") {
        const Work r = runMotion(TickMotion::Slabs, kTicks);
        CHECK(r.contactTicks > kTicks / 2);
        CHECK(r.candidates > 0);
    }
    SECTION("body: in contact with the swinging dynamic box once down") {
        const Work r = runMotion(TickMotion::Body, kTicks);
        CHECK(r.bodyContactTicks >= kTicks - 40);
    }
    SECTION("walk: the held-back walk is in contact some of the time") {
        const Work r = runMotion(TickMotion::Walk, kTicks);
        CHECK(r.contactTicks > 0);
        CHECK(r.counts == kTicks);
    }
}

TEST_CASE("every motion does the same work on every repeat, so each tick's own time is its own",
          "[threads]") {
    // bench tick --repeats keeps each tick's least time over the repeats; that is the tick's
    // own cost only if every repeat did the same work: the same walk or path, the same body
    // poses, the same forces holding the hand back.
    for (const TickMotion m : kTickMotions) {
        INFO(tickMotionName(m));
        const Work w = runMotion(m, 600, 2);
        CHECK(w.ticks == 600);
        CHECK(w.workDiffered == 0);
    }
}
