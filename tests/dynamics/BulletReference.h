#pragma once
/// Bullet 3.24 (double precision) as the reference for hapto's dynamics: the reference
/// scenarios (a drop onto a floor, a box on a ramp, a stack of three boxes) built once as hapto
/// Scenes, and two runners that step the same Scene in Bullet and in hapto::Dynamics and
/// record every dynamic body's trajectory, sample for sample.
///
/// Design note. The scenario is the hapto Scene; runBullet translates it object by object, so
/// both simulators see the same shapes, masses, inertias, poses, gravity and step. What Bullet
/// is made to mean (each choice is in runBullet, with its source):
/// - Collision margin: Bullet's default (CONVEX_DISTANCE_MARGIN, 4 cm,
///   BulletCollision/CollisionShapes/btCollisionMargin.h) is larger than our 5 cm boxes; every
///   box gets BulletSettings::marginM (0.1 mm). btBoxShape keeps its outer size when the margin
///   changes (btBoxShape::setMargin), and a btSphereShape's margin is its radius by
///   construction, so the shapes are exactly ours. Box-box and sphere-box pairs go to Bullet's
///   dedicated algorithms (btBoxBoxDetector, btSphereBoxCollisionAlgorithm), not GJK.
/// - Step: one internal step of 1 / ScenePhysics::rateHz per call (stepSimulation(dt, 0)),
///   semi-implicit Euler like hapto's; 10 solver iterations; split impulse for every
///   penetration (threshold 0; Bullet's -4 cm default would use Baumgarte, which adds energy);
///   no sleeping (DISABLE_DEACTIVATION), so drift is measured rather than frozen.
/// - Friction and restitution: Bullet multiplies the two objects' coefficients
///   (calculateCombinedFriction/-Restitution in btManifoldResult.cpp); hapto takes the pair's
///   smaller friction and larger restitution. A contact-added callback
///   (gContactAddedCallback, the hook Bullet offers for material combiners) applies hapto's
///   rule instead. Bullet has one friction coefficient per object (no static/dynamic pair): it
///   gets the dynamic one, and the ramp scenarios are chosen so that the static one does not
///   change the outcome (hold: mu_d > tan theta too; slide: mu_s < tan theta).
/// - Contact breaking threshold: Bullet keeps a contact point while it is closer than a
///   fraction (gContactBreakingThreshold, 0.02) of the shape's bounding radius
///   (btCollisionShape::getContactBreakingThreshold): 0.5-0.9 mm here. That brings a contact in
///   before the bodies touch, and Bullet's solver then takes gap / dt off the bounce (a sphere
///   with e = 0.5 left the floor at 0.30 m/s instead of 0.70), and it drops and re-adds a
///   sliding box's points every 0.9 mm of slide (the drift test of
///   btPersistentManifold::refreshContactPoints), which yawed the box on the ramp and cost 9 %
///   of its displacement in 1 s. The fraction is 0.001 here (25-45 um): the bounce is exact
///   and the slide within 1 % of g (sin - mu cos) t^2 / 2.
/// Cost: a scenario of a few bodies for a few thousand steps runs in milliseconds.

#include "hapto/dynamics/Dynamics.h"
#include "hapto/scenes/Scene.h"

#include <memory>
#include <vector>

namespace hapto::reference {

/// One body's state after a step (or at the start: time 0).
struct BodySample {
    double timeS = 0.0;           ///< Simulated time (s).
    Vec3 position{0.0};           ///< Centre of mass (m, world).
    Quat orientation{1, 0, 0, 0}; ///< Rotation (unit).
    Vec3 velocity{0.0};           ///< Of the centre of mass (m/s).
    Vec3 angularVelocity{0.0};    ///< (rad/s, world).
};

/// One dynamic body's trajectory: the start and the state after every step.
struct Trajectory {
    ObjectId id = 0;                 ///< The scene object's id.
    std::vector<BodySample> samples; ///< steps + 1 samples, time ascending.
};

/// What Bullet is told beyond the scene.
struct BulletSettings {
    double marginM = 1e-4;     ///< Collision margin of every box (m): 0.1 mm, our slop.
    int solverIterations = 10; ///< Sequential-impulse iterations (hapto's default too).
    double positionErp = 0.2;  ///< Split-impulse position correction per step (hapto's too).
    /// Bullet's contact breaking threshold as a fraction of each shape's bounding radius
    /// (gContactBreakingThreshold; Bullet's default 0.02). 0.001: 25-45 um for our bodies.
    double contactBreakingFactor = 0.001;
};

/// Steps `scene`'s dynamic bodies `steps` times in Bullet (double precision) and returns their
/// trajectories in slot order. Boxes and spheres only, diagonal inertia only (throws
/// std::invalid_argument naming the object otherwise). Not thread-safe: it sets two Bullet
/// globals (the contact-added callback, the breaking threshold) while it runs. [control]
std::vector<Trajectory> runBullet(const Scene& scene, int steps,
                                  const BulletSettings& settings = {});

/// Steps `scene`'s dynamic bodies `steps` times in hapto::Dynamics (over the scene's default
/// index) and returns their trajectories in slot order. [control]
std::vector<Trajectory> runHapto(std::shared_ptr<const Scene> scene, int steps,
                                 const DynamicsOptions& options = {});

/// The floor of every scenario: a static 2 m x 0.1 m x 2 m box whose top is y = 0.
inline constexpr double kFloorTopY = 0.0;
/// The dynamic boxes' edge (m) and mass (kg): 5 cm, 100 g (800 kg/m^3, a hardwood).
inline constexpr double kBoxEdgeM = 0.05, kBoxMassKg = 0.1;
/// The dynamic sphere's radius (m) and mass (kg).
inline constexpr double kSphereRadiusM = 0.025, kSphereMassKg = 0.05;

/// A body of `shape` (Box or Sphere) whose lowest point starts `heightM` above the floor, at
/// rest, with restitution `restitution`; floor and body have mu_s = mu_d = 0.5. [any thread]
Scene dropScene(Shape shape, double heightM, double restitution = 0.0);

/// A ramp: a static 1.2 m x 4 cm x 0.4 m box tilted by `angleRad` about +z (its uphill
/// direction is (cos, sin, 0)), and a 5 cm box at rest on it, 0.4 m uphill of its centre,
/// turned with it. Ramp and box have the friction given. [any thread]
Scene rampScene(double angleRad, double staticFriction, double dynamicFriction);
/// The ramp's downhill unit direction for `angleRad`. [any thread]
Vec3 rampDownhill(double angleRad);

/// Three 5 cm boxes stacked exactly on the floor at x = z = 0, at rest, mu 0.5. [any thread]
Scene stackScene();

} // namespace hapto::reference
