// The adversarial hand motions of `hapto bench tick --motion` (TickMotion.h has the design
// note).

#include "hapto/experiments/TickMotion.h"

#include "hapto/core/Random.h"
#include "hapto/experiments/HandWalk.h"
#include "hapto/experiments/TickBench.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/MassProperties.h"
#include "hapto/scenes/MeshGenerators.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace hapto::experiments {
namespace {

constexpr std::array<std::string_view, kTickMotions.size()> kNames{
    "rest", "walk", "trapped", "sweep", "graze", "sphere", "slabs", "body"};
/// One tick (s): the bench's 1 kHz servo.
constexpr double kTickS = 1e-3;
/// How far above a surface the scripted hands start, coming in from free space (m).
constexpr double kApproachM = 0.003;
/// Free space around the lattice's cubes inside its bounds (m).
constexpr double kLatticeRoomM = 0.005;
/// How far inside the dynamic box's top the hand rests (m).
constexpr double kBodyPressM = 0.001;
/// The resting hand comes down at this speed (m/s).
constexpr double kRestDescentMPerS = 0.1;

/// A path sampled every `stepM` of arc length along a polyline, up to `limit` points.
class PathBuilder {
public:
    PathBuilder(const Vec3& start, double stepM, std::size_t limit)
        : mAt(start), mStepM(stepM), mLimit(limit) {
        mPoints.reserve(limit);
        mPoints.push_back(start);
    }
    /// Goes on in a straight line to `to`, a point every stepM of the polyline's length.
    void lineTo(const Vec3& to) {
        const double length = glm::length(to - mAt);
        if (length <= 0.0) {
            return;
        }
        double s = mStepM - mCarry; // the arc length along this segment of the next point
        while (s <= length && !full()) {
            mPoints.push_back(mAt + (s / length) * (to - mAt));
            s += mStepM;
        }
        mCarry = length - (s - mStepM);
        mAt = to;
    }
    /// Ends exactly at the polyline's end so far (a point there unless the last one is), the
    /// next point a whole step further on.
    void arrive() {
        if (!full() && mPoints.back() != mAt) {
            mPoints.push_back(mAt);
        }
        mCarry = 0.0;
    }
    bool full() const { return mPoints.size() >= mLimit; }
    std::size_t size() const { return mPoints.size(); }
    /// Holds the last point to the limit.
    std::vector<Vec3> finish() {
        while (!full()) {
            mPoints.push_back(mPoints.back());
        }
        return std::move(mPoints);
    }

private:
    std::vector<Vec3> mPoints;
    Vec3 mAt;
    double mStepM;
    double mCarry = 0.0; // length walked since the last point
    std::size_t mLimit;
};

IndexSpec motionIndex() {
    return IndexSpec::parse("octree:8:0.001");
}

/// The edge of the random-cube scene's work cube for `objects` cubes (m).
double cubesWorkspaceM(std::size_t objects) {
    return 0.25 * std::cbrt(static_cast<double>(objects) / 1e6);
}

int latticePerSide(std::size_t objects) {
    return std::max(2, static_cast<int>(std::lround(std::cbrt(static_cast<double>(objects)))));
}

/// Where the lattice's cube i along an axis starts (m): its lowest coordinate.
double latticeCubeMin(int perSide, int i) {
    const double pitch = kMotionCubeM + kMotionLatticeGapM;
    return i * pitch - 0.5 * (perSide - 1) * pitch - 0.5 * kMotionCubeM;
}

void restCase(MotionCase& c, const MotionOptions& o) {
    int k = 0;
    c.scene = makeMotionLattice(o.objects, &k);
    const double middle = latticeCubeMin(k, k / 2) + 0.5 * kMotionCubeM;
    const double top = latticeCubeMin(k, k - 1) + kMotionCubeM;
    const Vec3 rest(middle, top - kRestDepthM, middle);
    PathBuilder p(rest + Vec3(0.0, kApproachM, 0.0), kRestDescentMPerS * kTickS, o.ticks);
    p.lineTo(rest);
    p.arrive();
    c.approachTicks = p.size();
    c.path = p.finish();
    c.pathText = "comes down onto the top face of the top layer's middle cube at 0.1 m/s and "
                 "rests 0.5 mm inside it";
}

void grazeCase(MotionCase& c, const MotionOptions& o) {
    int k = 0;
    c.scene = makeMotionLattice(o.objects, &k);
    const double y = latticeCubeMin(k, k - 1) + kMotionCubeM - kGrazeDepthM;
    // The lines where the top layer's cubes meet: boundary b lies between cubes b-1 and b.
    const auto line = [&](int b) { return latticeCubeMin(k, b); };
    const double xLow = line(1), xHigh = line(k - 1);
    const Vec3 start(xLow, y, line(1));
    PathBuilder p(start + Vec3(0.0, kApproachM, 0.0), kSlideSpeedMPerS * kTickS, o.ticks);
    p.lineTo(start);
    p.arrive();
    c.approachTicks = p.size();
    // Along the line between two rows of cubes, then along the line between the last two
    // columns to the next rows' line, and back: lines 1, 2, ..., K-1, K-2, ..., 1, ...
    int row = 1, step = 1;
    bool high = false;
    while (!p.full()) {
        high = !high;
        p.lineTo(Vec3(high ? xHigh : xLow, y, line(row)));
        if (k > 2 && (row + step < 1 || row + step > k - 1)) {
            step = -step;
        }
        row = k > 2 ? row + step : row;
        p.lineTo(Vec3(high ? xHigh : xLow, y, line(row)));
    }
    c.path = p.finish();
    c.pathText = "along the lines where the top layer's cubes meet, 0.1 mm below their top "
                 "faces, at 0.5 m/s: over a shared edge all the way, across a vertex of four "
                 "cubes every 2 mm";
}

void cubesCase(MotionCase& c, const MotionOptions& o) {
    c.scene = makeMotionCubes(o.objects, o.seed);
    const Aabb& b = c.scene.bounds();
    if (c.motion == TickMotion::Walk) {
        c.walkIn = b;
        c.pushMm = 2.0;
        c.pathText = "the bench's seeded walk (<= 0.5 m/s) over the whole work cube, held back "
                     "to 2 mm from the proxy";
    } else if (c.motion == TickMotion::Trapped) {
        // The central half of the work cube: at least a quarter of it from every face.
        c.walkIn = walkBox(b, 0.5 * (b.max.x - b.min.x));
        c.path = makeHandWalk(c.walkIn, o.seed, o.ticks);
        c.pathText = "the bench's seeded walk (<= 0.5 m/s) in the work cube's central half, "
                     "never held back (the proxy is left behind, trapped)";
    } else {
        Random random(o.seed);
        const Aabb in{b.min + Vec3(kMotionCubeM), b.max - Vec3(kMotionCubeM)};
        const auto any = [&] {
            return Vec3(random.uniform(in.min.x, in.max.x), random.uniform(in.min.y, in.max.y),
                        random.uniform(in.min.z, in.max.z));
        };
        PathBuilder p(any(), kFastSpeedMPerS * kTickS, o.ticks);
        while (!p.full()) {
            p.lineTo(any());
        }
        c.path = p.finish();
        c.pathText = "straight lines between seeded points of the work cube at 1 m/s (1 mm a "
                     "tick), never held back";
    }
}

void sphereCase(MotionCase& c, const MotionOptions& o) {
    MeshOptions m;
    m.shape = MeshShape::Sphere;
    m.triangles = std::clamp(o.objects, kMinGeneratedTriangles, kMaxGeneratedTriangles);
    m.size = kSphereDiameterM;
    c.scene = makeMeshScene(m);
    c.sceneText = "a geodesic sphere of " + std::to_string(generatedTriangleCount(m)) +
                  " triangles, 10 cm across";
    const double r = 0.5 * kSphereDiameterM - kSphereDepthM;
    const double step = kSlideSpeedMPerS * kTickS;
    Random random(o.seed);
    const auto unit = [&] {
        const Vec3 v(random.normal(), random.normal(), random.normal());
        return v / glm::length(v);
    };
    Vec3 u = unit();
    PathBuilder p(u * (r + kSphereDepthM + kApproachM), step, o.ticks);
    p.lineTo(u * r);
    p.arrive();
    c.approachTicks = p.size();
    std::vector<Vec3> path = p.finish();
    // Great-circle arcs of 5 to 20 cm, each in a seeded direction, 0.5 mm of arc a tick.
    const double turn = step / r;
    for (std::size_t at = c.approachTicks; at < path.size();) {
        const Vec3 t = unit();
        const Vec3 axis = glm::normalize(glm::cross(u, t));
        const auto arc = static_cast<std::size_t>(random.uniform(0.05, 0.2) / step);
        for (std::size_t n = 0; n < arc && at < path.size(); ++n, ++at) {
            u = glm::normalize(u * std::cos(turn) + glm::cross(axis, u) * std::sin(turn));
            path[at] = u * r;
        }
    }
    c.path = std::move(path);
    c.pathText = "slides 1 mm inside the sphere's surface at 0.5 m/s along seeded great-circle "
                 "arcs of 5-20 cm";
}

void slabsCase(MotionCase& c, const MotionOptions& o) {
    c.scene = makeSlabStack();
    const double half = 0.5 * ((kSlabCount - 1) * kSlabPitchM + kSlabThicknessM);
    Random random(o.seed);
    const auto across = [&](double y) {
        return Vec3(random.uniform(-0.03, 0.03), y, random.uniform(-0.03, 0.03));
    };
    const double above = half + kApproachM;
    const Vec3 start = across(above);
    PathBuilder p(start, kFastSpeedMPerS * kTickS, o.ticks);
    // Down through the stack and up again, each crossing at a new place 1-5 mm along.
    bool down = true;
    Vec3 at = start;
    while (!p.full()) {
        const double angle = random.uniform(0.0, 6.283185307179586);
        const double shift = random.uniform(0.001, 0.005);
        at = Vec3(std::clamp(at.x + shift * std::cos(angle), -0.04, 0.04), down ? -above : above,
                  std::clamp(at.z + shift * std::sin(angle), -0.04, 0.04));
        p.lineTo(at);
        down = !down;
    }
    c.path = p.finish();
    c.pathText = "down through the stack and up again at 1 m/s, from 3 mm above to 3 mm below, "
                 "never held back";
}

void bodyCase(MotionCase& c, const MotionOptions& o) {
    c.scene = makeDynamicSlab();
    const double top = c.scene.object(0).aabb().max.y;
    const Vec3 rest(0.0, top - kBodyPressM, 0.0);
    PathBuilder p(rest + Vec3(0.0, kApproachM, 0.0), kRestDescentMPerS * kTickS, o.ticks);
    p.lineTo(rest);
    p.arrive();
    c.approachTicks = p.size();
    c.path = p.finish();
    const double w = 2.0 * 3.141592653589793 / kBodySwingPeriodS;
    c.bodyPoses.resize(o.ticks);
    for (std::size_t k = 0; k < o.ticks; ++k) {
        const double t = static_cast<double>(k) * kTickS;
        BodyPose& pose = c.bodyPoses[k];
        pose.center = Vec3(kBodySwingM * std::sin(w * t), 0.0, 0.0);
        pose.centerOfMass = pose.center;
        pose.velocity = Vec3(kBodySwingM * w * std::cos(w * t), 0.0, 0.0);
    }
    c.sceneText = "a dynamic box of 10 x 2 x 10 cm, 100 g, alone";
    c.pathText = "comes down onto the box's top at 0.1 m/s and rests 1 mm inside it while the "
                 "box swings 2 cm either way under it once a second (its pose published before "
                 "each tick)";
}

} // namespace

std::string_view tickMotionName(TickMotion motion) {
    return kNames[static_cast<std::size_t>(motion)];
}

std::optional<TickMotion> parseTickMotion(std::string_view name) {
    for (std::size_t i = 0; i < kNames.size(); ++i) {
        if (kNames[i] == name) {
            return kTickMotions[i];
        }
    }
    return std::nullopt;
}

std::string tickMotionNames() {
    std::string out;
    for (const std::string_view n : kNames) {
        out += (out.empty() ? "" : ", ") + std::string(n);
    }
    return out;
}

Scene makeMotionLattice(std::size_t objects, int* perSide) {
    LatticeOptions l;
    l.perSide = latticePerSide(objects);
    l.cubeSize = kMotionCubeM;
    l.gap = kMotionLatticeGapM;
    if (perSide != nullptr) {
        *perSide = l.perSide;
    }
    // The touching cubes' bounds are the lattice itself; the hands come in from above it.
    const Scene lattice = makeLatticeScene(l);
    const Vec3 room(kLatticeRoomM);
    return Scene(Aabb{lattice.bounds().min - room, lattice.bounds().max + room},
                 std::vector<SceneObject>(lattice.objects().begin(), lattice.objects().end()));
}

Scene makeMotionCubes(std::size_t objects, std::uint64_t seed) {
    RandomOptions r;
    r.count = objects;
    r.seed = seed;
    r.workspace = cubesWorkspaceM(objects);
    r.cubeSize = kMotionCubeM;
    return makeRandomScene(r);
}

Scene makeSlabStack() {
    std::vector<SceneObject> slabs;
    const Vec3 halfSlab(0.5 * kSlabEdgeM, 0.5 * kSlabThicknessM, 0.5 * kSlabEdgeM);
    for (int i = 0; i < kSlabCount; ++i) {
        const double y = (i - 0.5 * (kSlabCount - 1)) * kSlabPitchM;
        slabs.push_back(makeBox(static_cast<ObjectId>(i), Vec3(0.0, y, 0.0), halfSlab,
                                Quat(1, 0, 0, 0), generatedMaterial()));
    }
    const Vec3 room(0.5 * kSlabEdgeM + 0.01, 0.5 * kSlabCount * kSlabPitchM + 0.01,
                    0.5 * kSlabEdgeM + 0.01);
    return Scene(Aabb{-room, room}, std::move(slabs));
}

Scene makeDynamicSlab() {
    SceneObject box =
        makeBox(0, Vec3(0.0), Vec3(0.05, 0.01, 0.05), Quat(1, 0, 0, 0), generatedMaterial());
    box.body.dynamic = true;
    fillMassProperties(box, 0.1, std::nullopt, std::nullopt);
    Scene scene(Aabb{Vec3(-0.1), Vec3(0.1)}, {box});
    scene.setPhysics(ScenePhysics{});
    return scene;
}

MotionCase makeMotionCase(TickMotion motion, const MotionOptions& o) {
    MotionCase c;
    c.motion = motion;
    c.index = motionIndex();
    switch (motion) {
    case TickMotion::Rest:
    case TickMotion::Graze:
        motion == TickMotion::Rest ? restCase(c, o) : grazeCase(c, o);
        c.sceneText = "a lattice of " + std::to_string(c.scene.size()) + " touching cubes of 2 mm";
        break;
    case TickMotion::Walk:
    case TickMotion::Trapped:
    case TickMotion::Sweep:
        cubesCase(c, o);
        c.sceneText = std::to_string(c.scene.size()) + " random cubes of 2 mm in a " +
                      std::to_string(cubesWorkspaceM(o.objects) * 100.0).substr(0, 5) +
                      " cm work cube (the density of 10^6 in 25 cm)";
        break;
    case TickMotion::Sphere:
        sphereCase(c, o);
        break;
    case TickMotion::Body:
        bodyCase(c, o);
        break;
    case TickMotion::Slabs:
        slabsCase(c, o);
        c.sceneText =
            std::to_string(kSlabCount) + " slabs of 10 x 10 cm, 0.5 mm thick, stacked 1 mm apart";
        break;
    }
    return c;
}

} // namespace hapto::experiments
