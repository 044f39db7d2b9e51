#include "hapto/devices/FalconKinematics.h"

#include "hapto/core/Finite.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hapto::falcon {
namespace {

constexpr double kPi = 3.14159265358979323846;
/// Leg directions about z (rad): {pi/2, -pi/6, -5pi/6}, each + pi/12.
constexpr std::array<double, 3> kLegPhi{kPi / 2 + kPi / 12, -kPi / 6 + kPi / 12,
                                        -5 * kPi / 6 + kPi / 12};
/// Degrees of arm rotation per encoder count: the encoder's 320 lines x 4 on a 14.25 mm
/// capstan driving a 110 mm sector.
constexpr double kDegPerCount = (kPi * 0.01425 / (320.0 * 4.0)) / (kPi * 0.110 / 360.0);
constexpr double kAngleOffsetDeg = 35.0;
constexpr double kDegToRad = kPi / 180.0;

/// Newton: at most this many iterations, steps capped at this length (m), converged below
/// this step length (m).
constexpr int kMaxNewtonIterations = 40;
constexpr double kMaxNewtonStepM = 0.01;
constexpr double kNewtonToleranceM = 1e-11;

/// One leg's view of a tip position.
struct LegCoords {
    double u, v, w, cosPhi, sinPhi;
};

LegCoords legCoords(const FalconGeometry& g, int leg, const Vec3& p) {
    const double cp = std::cos(kLegPhi[static_cast<std::size_t>(leg)]);
    const double sp = std::sin(kLegPhi[static_cast<std::size_t>(leg)]);
    return {cp * p.x + sp * p.y - g.r, -sp * p.x + cp * p.y - g.s, p.z, cp, sp};
}

/// One leg's terms of its closure equation g_i = A^2 + B^2 - L^2 at a tip position and a motor
/// angle (t, rad), shared by the residual and its partial derivatives; s2 is the squared length
/// of the parallelogram's projection (L = d + e + sqrt(s2), reachable when s2 >= 0).
struct LegTerms {
    LegCoords l;
    double t, A, B, vf, s2;
};

LegTerms legTerms(const FalconGeometry& g, int leg, const Vec3& p, double t) {
    const LegCoords l = legCoords(g, leg, p);
    const double A = l.u + g.c - g.a * std::cos(t);
    const double B = l.w - g.a * std::sin(t);
    const double vf = l.v + g.f;
    return {l, t, A, B, vf, g.b * g.b - vf * vf};
}

Eigen::Matrix3d toEigen(const Mat3& m) {
    Eigen::Matrix3d e;
    for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) {
            e(r, c) = m[c][r];
        }
    }
    return e;
}

} // namespace

double FalconKinematics::encoderToAngle(std::int16_t count) {
    return (kDegPerCount * static_cast<double>(count) + kAngleOffsetDeg) * kDegToRad;
}

std::int16_t FalconKinematics::angleToEncoder(double angleRad) {
    const double counts = std::round((angleRad / kDegToRad - kAngleOffsetDeg) / kDegPerCount);
    if (!(counts > -32768.0)) {
        return std::numeric_limits<std::int16_t>::min();
    }
    if (counts > 32767.0) {
        return std::numeric_limits<std::int16_t>::max();
    }
    return static_cast<std::int16_t>(counts);
}

Angles FalconKinematics::encodersToAngles(const std::array<std::int16_t, 3>& counts) {
    return {encoderToAngle(counts[0]), encoderToAngle(counts[1]), encoderToAngle(counts[2])};
}

std::optional<double> FalconKinematics::inverseLeg(int leg, const Vec3& position) const {
    if (leg < 0 || leg > 2) {
        return std::nullopt;
    }
    const FalconGeometry& g = mGeometry;
    const LegCoords l = legCoords(g, leg, position);
    const double vf = l.v + g.f;
    const double s2 = g.b * g.b - vf * vf;
    if (!(s2 > 0.0)) {
        return std::nullopt;
    }
    const double reach = g.d + g.e + std::sqrt(s2); // elbow-to-effector distance in (u, w)
    const double qu = l.u + g.c;
    const double rho = std::hypot(qu, l.w);
    if (!(rho > 0.0)) {
        return std::nullopt;
    }
    // |Q - a(cos t, sin t)| = reach  <=>  cos(t - alpha) = (rho^2 + a^2 - reach^2) / (2 a rho).
    const double k = (rho * rho + g.a * g.a - reach * reach) / (2.0 * g.a * rho);
    if (!(k >= -1.0 && k <= 1.0)) {
        return std::nullopt;
    }
    // Of the two elbow positions, the Falcon's elbows bend outwards: the smaller angle.
    return std::atan2(l.w, qu) - std::acos(k);
}

std::optional<Angles> FalconKinematics::inverse(const Vec3& position) const {
    Angles out{};
    for (int i = 0; i < 3; ++i) {
        const auto t = inverseLeg(i, position);
        if (!t) {
            return std::nullopt;
        }
        out[static_cast<std::size_t>(i)] = *t;
    }
    return out;
}

Vec3 FalconKinematics::residual(const Vec3& p, const Angles& angles) const {
    const FalconGeometry& g = mGeometry;
    Vec3 out(0.0);
    for (int i = 0; i < 3; ++i) {
        const LegTerms k = legTerms(g, i, p, angles[static_cast<std::size_t>(i)]);
        const double L = g.d + g.e + std::sqrt(std::max(0.0, k.s2));
        out[i] = k.A * k.A + k.B * k.B - L * L;
    }
    return out;
}

bool FalconKinematics::partials(const Vec3& p, const Angles& angles, Mat3& dgdp,
                                Vec3& dgdtheta) const {
    const FalconGeometry& g = mGeometry;
    for (int i = 0; i < 3; ++i) {
        const LegTerms k = legTerms(g, i, p, angles[static_cast<std::size_t>(i)]);
        if (!(k.s2 > 0.0)) {
            return false;
        }
        const double s = std::sqrt(k.s2);
        const double L = g.d + g.e + s;
        const double dgdu = 2.0 * k.A;
        const double dgdv = 2.0 * L * k.vf / s; // -2L * dS/dv, dS/dv = -vf / s
        const double dgdw = 2.0 * k.B;
        // Row i of dg/dp (GLM is column-major: m[col][row]).
        dgdp[0][i] = dgdu * k.l.cosPhi - dgdv * k.l.sinPhi;
        dgdp[1][i] = dgdu * k.l.sinPhi + dgdv * k.l.cosPhi;
        dgdp[2][i] = dgdw;
        dgdtheta[i] = 2.0 * g.a * (k.A * std::sin(k.t) - k.B * std::cos(k.t));
    }
    return true;
}

std::optional<Vec3> FalconKinematics::forward(const Angles& angles, const Vec3& start) const {
    for (double t : angles) {
        if (!std::isfinite(t)) {
            return std::nullopt;
        }
    }
    Vec3 p = finite(start) ? start : defaultStart();
    for (int iter = 0; iter < kMaxNewtonIterations; ++iter) {
        Mat3 dgdp(0.0);
        Vec3 dgdt(0.0);
        if (!partials(p, angles, dgdp, dgdt)) {
            return std::nullopt;
        }
        const Vec3 res = residual(p, angles);
        const Eigen::Matrix3d m = toEigen(dgdp);
        const Eigen::PartialPivLU<Eigen::Matrix3d> lu(m);
        if (!(std::abs(m.determinant()) > 1e-15)) {
            return std::nullopt;
        }
        const Eigen::Vector3d step = lu.solve(-Eigen::Vector3d(res.x, res.y, res.z));
        double len = step.norm();
        if (!std::isfinite(len)) {
            return std::nullopt;
        }
        const double damp = len > kMaxNewtonStepM ? kMaxNewtonStepM / len : 1.0;
        p += damp * Vec3(step.x(), step.y(), step.z());
        if (len < kNewtonToleranceM) {
            return p;
        }
    }
    return std::nullopt;
}

std::optional<Mat3> FalconKinematics::jacobian(const Vec3& position, const Angles& angles) const {
    Mat3 dgdp(0.0);
    Vec3 dgdt(0.0);
    if (!partials(position, angles, dgdp, dgdt)) {
        return std::nullopt;
    }
    const Eigen::Matrix3d m = toEigen(dgdp);
    if (!(std::abs(m.determinant()) > 1e-15)) {
        return std::nullopt;
    }
    // dg/dp dp + diag(dg/dtheta) dtheta = 0  =>  dp/dtheta = -(dg/dp)^-1 diag(dg/dtheta).
    const Eigen::Matrix3d rhs =
        -Eigen::Vector3d(dgdt.x, dgdt.y, dgdt.z).asDiagonal().toDenseMatrix();
    const Eigen::Matrix3d j = m.partialPivLu().solve(rhs);
    Mat3 out(0.0);
    for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) {
            if (!std::isfinite(j(r, c))) {
                return std::nullopt;
            }
            out[c][r] = j(r, c);
        }
    }
    return out;
}

Vec3 FalconKinematics::forceToTorque(const Mat3& jacobian, const Vec3& forceN) {
    // tau_j = (column j of J) . F
    return Vec3(glm::dot(jacobian[0], forceN), glm::dot(jacobian[1], forceN),
                glm::dot(jacobian[2], forceN));
}

std::int16_t FalconKinematics::torqueToMotorWord(double torqueNm) {
    const double w = std::round(-torqueNm * kMotorWordPerNm);
    if (std::isnan(w)) {
        return 0;
    }
    if (w >= 32767.0) {
        return std::numeric_limits<std::int16_t>::max();
    }
    if (w <= -32768.0) {
        return std::numeric_limits<std::int16_t>::min();
    }
    return static_cast<std::int16_t>(w);
}

MotorWords FalconKinematics::torqueToMotorWords(const Vec3& torqueNm, int wordLimit) {
    if (!finite(torqueNm)) {
        return {0, 0, 0};
    }
    // Scale the three words together (libnifalcon src/kinematic/FalconKinematicStamper.cpp,
    // getForces, scales all torques by the largest for the same reason: clamping one motor alone
    // turns the force). The limit is a word limit: the public headers cap motor values at 4096.
    const double limit = static_cast<double>(std::clamp(wordLimit, 1, kMaxMotorWordLimit));
    const Vec3 words = -torqueNm * kMotorWordPerNm;
    const double largest =
        std::max(std::abs(words.x), std::max(std::abs(words.y), std::abs(words.z)));
    const double scale = largest > limit ? limit / largest : 1.0;
    return {torqueToMotorWord(torqueNm.x * scale), torqueToMotorWord(torqueNm.y * scale),
            torqueToMotorWord(torqueNm.z * scale)};
}

} // namespace hapto::falcon
