// The hands' torsional friction (soft-finger contact) on a body: Dynamics::applyHandTorsion.
//
// Design note. A hand touches a body at a point, and a point transmits no moment; a real
// fingertip or tool tip presses a patch that resists spin about the contact normal up to a
// Coulomb moment mu |Fn| r (the soft-finger contact, Mason and Salisbury, "Robot Hands and the
// Mechanics of Manipulation", MIT Press 1985; Bullet's spinning friction, a torque limit
// proportional to the normal impulse). The servo ticks sum, per body, the budget
// mu |Fn| r dt n n^T over the hands' sent ticks (runtime/BodyCoupling.h); n n^T does not
// depend on the normal's sign, so two hands pressing from opposite sides add their budgets
// about their common axis. Here the budget B (N m s) is spent once per step: about each
// principal axis e_j of B, with budget beta_j (its eigenvalue), an angular impulse lambda_j e_j
// with |lambda_j| <= beta_j that stops the body's spin about e_j, solved by projected
// Gauss-Seidel over the axes (they couple through the inverse inertia). Why it is stable and
// passive: the step knows the inertia, so each update is the exact stop
// -(w.e) / (e.I^-1 e), or a fraction in [0, 1] of it when the clamp binds; the kinetic energy
// changes by -(s - s^2/2) (w.e)^2 / (e.I^-1 e) <= 0 for that fraction s, at any mass (a
// viscous torque from the servo would overshoot for a light body). The impulse joins the
// step's pending angular impulse, so applyPendingImpulses counts it as the hands' work
// (negative). For one axis, or opposed hands, this is exact Coulomb torsional friction;
// hands on non-parallel normals share their budgets through B's principal axes, an
// approximation that keeps the total budget (trace B) and the passivity.
// Invariants: no allocation, lock or throw; deterministic (fixed sweeps and passes).

#include "DynamicsImpl.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace hapto {

namespace {

/// Jacobi sweeps for the 3x3 eigenproblem: a symmetric 3x3 converges quadratically, so 8
/// sweeps leave off-diagonals at rounding.
constexpr int kJacobiSweeps = 8;
/// Gauss-Seidel passes over the (at most 3) axes.
constexpr int kPasses = 4;

/// B's eigenvalues `values` and unit eigenvectors `axes` (cyclic Jacobi rotations; e.g.
/// Golub and Van Loan, Matrix Computations, 4th ed., sec. 8.5).
void symmetricEigen(const Mat3& b, std::array<double, 3>& values, std::array<Vec3, 3>& axes) {
    double a[3][3];
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            a[r][c] = 0.5 * (b[c][r] + b[r][c]); // symmetrised against rounding
        }
    }
    for (int sweep = 0; sweep < kJacobiSweeps; ++sweep) {
        for (int p = 0; p < 2; ++p) {
            for (int q = p + 1; q < 3; ++q) {
                if (std::abs(a[p][q]) <= 1e-300) {
                    continue;
                }
                const double tau = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t = (tau >= 0.0 ? 1.0 : -1.0) / (std::abs(tau) + std::hypot(1.0, tau));
                const double c = 1.0 / std::sqrt(1.0 + t * t);
                const double s = t * c;
                for (int k = 0; k < 3; ++k) { // A <- A J (columns p, q)
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) { // A <- J^T A (rows p, q)
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; ++k) { // V <- V J
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (int j = 0; j < 3; ++j) {
        values[j] = a[j][j];
        axes[j] = Vec3(v[0][j], v[1][j], v[2][j]);
    }
}

} // namespace

void Dynamics::applyHandTorsion(std::size_t i, const Mat3& budgetNms) noexcept {
    if (i >= mBodies.size() || budgetNms == Mat3(0.0)) {
        return;
    }
    dyn::BodyWork& w = mImpl->work[i];
    std::array<double, 3> beta{};
    std::array<Vec3, 3> axes{};
    symmetricEigen(budgetNms, beta, axes);
    // The spin once the step's pending hand impulses are applied (applyPendingImpulses).
    Vec3 spin = mBodies[i].angularVelocity + w.invInertiaWorld * w.pendingAngular;
    std::array<double, 3> lambda{};
    Vec3 total(0.0);
    for (int pass = 0; pass < kPasses; ++pass) {
        for (int j = 0; j < 3; ++j) {
            const Vec3 iE = w.invInertiaWorld * axes[j];
            const double mass = glm::dot(axes[j], iE);
            if (!(beta[j] > 0.0) || !(mass > 0.0)) {
                continue;
            }
            const double next =
                std::clamp(lambda[j] - glm::dot(spin, axes[j]) / mass, -beta[j], beta[j]);
            const double d = next - lambda[j];
            lambda[j] = next;
            spin += iE * d;
            total += axes[j] * d;
        }
    }
    if (std::isfinite(total.x) && std::isfinite(total.y) && std::isfinite(total.z)) {
        w.pendingAngular += total;
    }
}

} // namespace hapto
