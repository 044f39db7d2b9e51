// The checks on scene format version 3's fields (dynamic bodies and the scene's physics), one
// home for both JSON loaders (SceneFile.cpp, SceneJsonFast.cpp). Design note: a loader reads the
// fields into BodyFields as plain values; applyBodyFields checks them in one fixed order (the
// dynamic flag, mass or density, restitution, velocities, inertia) and only then computes the
// mass properties, so a file with several bad values is refused for the same one whichever loader
// reads it. Inertia is accepted as 3 principal moments (the diagonal in the object's own axes) or
// a full 3x3 tensor, which must be exactly symmetric and positive definite; either way its
// principal moments must obey the triangle inequality (I1 + I2 >= I3), which every real mass
// distribution does (each moment is an integral of a sum of two squared coordinates).

#include "hapto/scenes/MassProperties.h"

#include "SceneFileChecks.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

namespace hapto::detail {
namespace {

using json::Path;
using json::show;
using json::Source;

/// Relative slack of the triangle inequality, for tensors computed in floating point (a thin
/// plate's Izz is Ixx + Iyy up to rounding).
constexpr double kTriangleSlack = 1e-9;

/// The eigenvalues of a symmetric 3x3 matrix, ascending (the trigonometric closed form; O. K.
/// Smith, "Eigenvalues of a symmetric 3x3 matrix", Comm. ACM 4(4), 1961).
std::array<double, 3> eigenvalues(const Mat3& a) {
    const double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    if (p1 == 0.0) {
        std::array<double, 3> d = {a[0][0], a[1][1], a[2][2]};
        std::sort(d.begin(), d.end());
        return d;
    }
    const double p2 = (a[0][0] - q) * (a[0][0] - q) + (a[1][1] - q) * (a[1][1] - q) +
                      (a[2][2] - q) * (a[2][2] - q) + 2.0 * p1;
    const double p = std::sqrt(p2 / 6.0);
    const Mat3 b = (a - Mat3(q)) * (1.0 / p);
    const double r = std::clamp(glm::determinant(b) / 2.0, -1.0, 1.0);
    const double phi = std::acos(r) / 3.0;
    const double hi = q + 2.0 * p * std::cos(phi);
    const double lo = q + 2.0 * p * std::cos(phi + 2.0 * std::numbers::pi / 3.0);
    return {lo, 3.0 * q - hi - lo, hi};
}

void checkTriangleInequality(const Source& s, std::array<double, 3> m, const Path& path) {
    std::sort(m.begin(), m.end());
    if (m[0] + m[1] < m[2] * (1.0 - kTriangleSlack)) {
        s.fail(path, "the principal moments of inertia " + show(m[0]) + ", " + show(m[1]) +
                         " and " + show(m[2]) +
                         " kg m^2 break the triangle inequality (the two smaller must sum to at "
                         "least the largest, as for every real body)");
    }
}

/// The inertia tensor (kg m^2) from its checked fields.
Mat3 checkInertia(const Source& s, const std::array<double, 9>& v, bool principal,
                  const Path& path) {
    Mat3 m(0.0);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            m[c][r] = v[static_cast<std::size_t>(r * 3 + c)];
        }
    }
    for (std::size_t i = 0; i < 3; ++i) {
        const int k = static_cast<int>(i);
        json::checkRange(s, m[k][k], principal ? path[i] : path[i][i], 0.0, json::kUnbounded, true,
                         "a moment of inertia (kg m^2)");
    }
    if (principal) {
        checkTriangleInequality(s, {m[0][0], m[1][1], m[2][2]}, path);
        return m;
    }
    for (std::size_t r = 0; r < 3; ++r) {
        for (std::size_t c = r + 1; c < 3; ++c) {
            const double a = v[r * 3 + c], b = v[c * 3 + r];
            if (a != b) {
                s.fail(path[r][c], "the inertia tensor must be symmetric: [" + std::to_string(r) +
                                       "][" + std::to_string(c) + "] is " + show(a) + " but [" +
                                       std::to_string(c) + "][" + std::to_string(r) + "] is " +
                                       show(b));
            }
        }
    }
    const double minor2 = m[0][0] * m[1][1] - m[0][1] * m[0][1];
    if (!(minor2 > 0.0) || !(glm::determinant(m) > 0.0)) {
        s.fail(path, "the inertia tensor must be positive definite (every leading minor > 0)");
    }
    checkTriangleInequality(s, eigenvalues(m), path);
    return m;
}

/// Mass or density: exactly one when dynamic, none when static.
void checkMassFields(const Source& s, const BodyFields& f, const Path& path) {
    if (!f.dynamic.value_or(false)) {
        const std::pair<const char*, bool> given[] = {
            {"mass_kg", f.massKg.has_value()},
            {"density_kg_per_m3", f.densityKgPerM3.has_value()},
            {"inertia", f.inertia.has_value()},
            {"velocity", f.velocity.has_value()},
            {"angular_velocity", f.angularVelocity.has_value()}};
        for (const auto& [key, present] : given) {
            if (present) {
                s.fail(path / key, std::string("only a dynamic body has \"") + key +
                                       "\" (add \"dynamic\": true)");
            }
        }
        return;
    }
    if (f.massKg && f.densityKgPerM3) {
        s.fail(path, "give either \"mass_kg\" or \"density_kg_per_m3\", not both");
    }
    if (!f.massKg && !f.densityKgPerM3) {
        s.fail(path, "a dynamic body needs \"mass_kg\" (kg) or \"density_kg_per_m3\" (kg/m^3)");
    }
    if (f.massKg) {
        json::checkRange(s, *f.massKg, path / "mass_kg", 0.0, BodyProperties::kMaxMassKg, true,
                         "the mass (kg)");
    } else {
        json::checkRange(s, *f.densityKgPerM3, path / "density_kg_per_m3", 0.0,
                         BodyProperties::kMaxDensityKgPerM3, true, "the density (kg/m^3)");
    }
}

void checkSpeed(const Source& s, const Vec3& v, const Path& path, double limit, const char* what) {
    json::checkRange(s, glm::length(v), path, 0.0, limit, false, what);
}

} // namespace

void refuseBeforeVersion3(const Source& s, const Path& fieldPath, const char* key) {
    s.fail(fieldPath, std::string("\"") + key +
                          "\" needs \"version\": 3 (dynamic bodies and gravity are new in "
                          "version 3)");
}

void applyBodyFields(const Source& s, SceneObject& o, const BodyFields& f, const Path& path) {
    checkMassFields(s, f, path);
    if (f.restitution) {
        json::checkRange(s, *f.restitution, path / "restitution", 0.0, 1.0, false,
                         "the restitution");
        o.body.restitution = *f.restitution;
    }
    if (!f.dynamic.value_or(false)) {
        return;
    }
    o.body.dynamic = true;
    if (f.velocity) {
        checkSpeed(s, *f.velocity, path / "velocity", BodyProperties::kMaxSpeed, "the speed (m/s)");
        o.body.velocity = *f.velocity;
    }
    if (f.angularVelocity) {
        checkSpeed(s, *f.angularVelocity, path / "angular_velocity",
                   BodyProperties::kMaxAngularSpeed, "the angular speed (rad/s)");
        o.body.angularVelocity = *f.angularVelocity;
    }
    std::optional<Mat3> inertia;
    if (f.inertia) {
        inertia = checkInertia(s, *f.inertia, f.inertiaPrincipal, path / "inertia");
    }
    try {
        fillMassProperties(o, f.massKg, f.densityKgPerM3, inertia);
    } catch (const std::invalid_argument& e) {
        s.fail(path, std::string("a dynamic ") + std::string(shapeName(o.shape)) + ": " + e.what());
    }
}

ScenePhysics checkPhysics(const Source& s, const std::optional<Vec3>& gravity,
                          const std::optional<double>& rateHz, const Path& top) {
    ScenePhysics physics;
    if (gravity) {
        json::checkRange(s, glm::length(*gravity), top / "gravity", 0.0, ScenePhysics::kMaxGravity,
                         false, "|gravity| (m/s^2)");
        physics.gravity = *gravity;
    }
    if (rateHz) {
        const Path dp = top / "dynamics";
        const Path rp = dp / "rate_hz";
        json::checkRange(s, *rateHz, rp, ScenePhysics::kMinRateHz, ScenePhysics::kMaxRateHz, false,
                         "the dynamics rate (Hz)");
        physics.rateHz = *rateHz;
    }
    return physics;
}

} // namespace hapto::detail
