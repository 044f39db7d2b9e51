#pragma once
/// Novint Falcon kinematics: encoder counts to arm angles, inverse and forward kinematics of the
/// delta mechanism, its Jacobian, and forces to motor command words.
//
// Design note. The Falcon is a three-legged parallel (delta) mechanism. Leg i is described in
// its own frame, the device frame turned by phi_i about z: u = x cos(phi) + y sin(phi) - r,
// v = -x sin(phi) + y cos(phi) - s, w = z. Its motor turns the upper arm (length a) by theta
// in the (u, w) plane; the parallelogram lower arm (length b, tilted by theta3 with
// b cos(theta3) = v + f) plus the offsets c, d, e close the loop, giving one equation per leg
//     g_i(p, theta_i) = (u + c - a cos theta)^2 + (w - a sin theta)^2 - (d + e + b sin theta3)^2 =
//     0.
// Inverse kinematics solves g_i = 0 for theta_i in closed form (a circle intersection).
// Forward kinematics solves the three g_i = 0 for p by damped Newton steps, each a 3x3 solve
// (Eigen) with dg/dp. The Jacobian dp/dtheta = -(dg/dp)^-1 diag(dg_i/dtheta_i) maps arm
// speeds to tip speeds, and its transpose maps a tip force to motor torques: tau = J^T F.
// Invariant: FK(IK(p)) == p inside the workspace. Cost: FK takes 3-6 Newton iterations from a
// warm start (a few hundred ns); nothing allocates or throws, failures are returned as values.
//
// Units: metres, radians, newtons, newton-metres. Positions here are in the mechanism frame
// (z along the grip axis, away from the device body), where the workspace centre sits at
// kWorkspaceOrigin; FalconDevice reports positions relative to that centre.

#include "hapto/core/Geometry.h"

#include <array>
#include <cstdint>
#include <optional>

namespace hapto::falcon {

/// Mechanism constants (m), from the public description of the Falcon's geometry.
struct FalconGeometry {
    double a = 0.060;    ///< Upper arm length (m).
    double b = 0.1025;   ///< Lower (parallelogram) arm length (m).
    double c = 0.01443;  ///< Effector-side radial offset (m).
    double d = 0.01125;  ///< Elbow offset (m).
    double e = 0.01125;  ///< Effector-side offset (m).
    double f = -0.025;   ///< Lateral offset of the lower arm (m).
    double r = 0.0400;   ///< Radial offset of the motor axis (m).
    double s = -0.02309; ///< Lateral offset of the motor axis (m).
};

/// Workspace centre in the mechanism frame (m).
inline constexpr double kWorkspaceOriginZ = 0.150;
/// Motor command word per newton-metre of joint torque (the firmware's scale): word = -tau * 1e4.
inline constexpr double kMotorWordPerNm = 1.0e4;
/// The default largest |motor word| (counts): the public headers cap motor values at 4096, and
/// a capture of the vendor driver's packets peaks at 4095 (not confirmed on hardware).
/// FalconConfig::motorWordLimit overrides it.
inline constexpr int kDefaultMotorWordLimit = 4096;
/// The largest |motor word| an int16 can carry symmetrically (counts).
inline constexpr int kMaxMotorWordLimit = 32767;

/// Three joint values, one per leg.
using Angles = std::array<double, 3>;
/// Three motor command words.
using MotorWords = std::array<std::int16_t, 3>;

/// The Falcon's kinematics. Immutable after construction; every method is const. [any thread]
class FalconKinematics {
public:
    /// Uses the standard Falcon geometry. [any thread]
    FalconKinematics() = default;
    /// Uses a custom geometry (for tests). [any thread]
    explicit FalconKinematics(const FalconGeometry& geometry) : mGeometry(geometry) {}

    /// The geometry in use. [any thread]
    const FalconGeometry& geometry() const { return mGeometry; }

    /// Arm angle (rad) for an encoder count: (pi*0.01425/1280)*enc/(pi*0.110/360) + 35 degrees.
    /// [any thread]
    static double encoderToAngle(std::int16_t count);
    /// Encoder count nearest to an arm angle (rad), saturated to int16. [any thread]
    static std::int16_t angleToEncoder(double angleRad);
    /// All three arm angles (rad). [any thread]
    static Angles encodersToAngles(const std::array<std::int16_t, 3>& counts);

    /// Arm angle (rad) of leg `leg` (0..2) for a tip position (m, mechanism frame); nullopt when
    /// out of reach. [any thread]
    std::optional<double> inverseLeg(int leg, const Vec3& position) const;
    /// Arm angles (rad) for a tip position (m, mechanism frame); nullopt when out of reach.
    /// [any thread]
    std::optional<Angles> inverse(const Vec3& position) const;

    /// Tip position (m, mechanism frame) for arm angles (rad), by damped Newton from `start`
    /// (m); nullopt when it does not converge or is not finite. [any thread]
    std::optional<Vec3> forward(const Angles& angles, const Vec3& start = defaultStart()) const;
    /// The Newton start used without a warm start (m): near the workspace centre. [any thread]
    static Vec3 defaultStart() { return Vec3(0.0, 0.0, 0.12); }

    /// Jacobian dp/dtheta (m/rad) at a consistent (position, angles) pair; column j is the tip
    /// velocity per unit speed of arm j. nullopt at a singular pose. [any thread]
    std::optional<Mat3> jacobian(const Vec3& position, const Angles& angles) const;

    /// Joint torques (Nm) for a tip force (N): tau = J^T F. [any thread]
    static Vec3 forceToTorque(const Mat3& jacobian, const Vec3& forceN);
    /// Motor words for joint torques (Nm): word = -tau * 1e4; if the largest |word| exceeds
    /// `wordLimit` (counts, clamped to 1..32767) all three are scaled down together so that it
    /// equals the limit, keeping the force's direction (never clamped one by one); then rounded.
    /// Any non-finite torque gives {0, 0, 0}. [any thread]
    static MotorWords torqueToMotorWords(const Vec3& torqueNm,
                                         int wordLimit = kDefaultMotorWordLimit);
    /// One torque (Nm) to a motor word: -tau * 1e4, rounded, clamped to int16, NaN -> 0.
    /// [any thread]
    static std::int16_t torqueToMotorWord(double torqueNm);

    /// Leg equation residuals g_i(p, theta_i) (m^2); zero on a consistent pose. [any thread]
    Vec3 residual(const Vec3& position, const Angles& angles) const;

private:
    /// dg/dp (rows = legs) and dg/dtheta (diagonal) at a pose.
    bool partials(const Vec3& p, const Angles& angles, Mat3& dgdp, Vec3& dgdtheta) const;

    FalconGeometry mGeometry;
};

} // namespace hapto::falcon
