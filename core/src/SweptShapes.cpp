#include "hapto/core/SweptShapes.h"

#include <cmath>
#include <utility>

namespace hapto {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
} // namespace

SweptEntry sweepBoxLocal(const Vec3& halfExtents, const Vec3& from, const Vec3& delta, double skinM,
                         double shrinkM) noexcept {
    const Vec3& a = from;
    const Vec3& d = delta;
    double tIn = -kInf;
    double tOut = kInf;
    double sIn = -kInf;
    SweptEntry e;
    for (int i = 0; i < 3; ++i) {
        const double h = halfExtents[i] + skinM - shrinkM;
        const double hs = halfExtents[i] + skinM;
        if (std::abs(d[i]) < 1e-18) {
            if (std::abs(a[i]) >= h) {
                return {};
            }
            continue;
        }
        const double inv = 1.0 / d[i];
        double t1 = (-h - a[i]) * inv;
        double t2 = (h - a[i]) * inv;
        double s1 = (-hs - a[i]) * inv;
        if (t1 > t2) {
            std::swap(t1, t2);
            s1 = (hs - a[i]) * inv;
        }
        if (t1 > tIn) {
            tIn = t1;
            e.axis = i;
            e.sign = d[i] > 0 ? -1.0 : 1.0;
        }
        tOut = std::min(tOut, t2);
        sIn = std::max(sIn, s1);
    }
    // tIn < 0: the start is already inside (passed through); tIn >= tOut: no interior chord.
    if (e.axis < 0 || tIn < 0.0 || tIn >= 1.0 || tIn >= tOut) {
        return {};
    }
    e.found = true;
    e.t = tIn;
    e.tStop = std::clamp(sIn, 0.0, tIn);
    return e;
}

SweptEntry sweepSphere(const Vec3& center, double radius, const Vec3& from, const Vec3& to,
                       double skinM, double shrinkM) noexcept {
    const Vec3 f = from - center;
    const Vec3 d = to - from;
    const double a = glm::dot(d, d);
    if (a < 1e-36) {
        return {};
    }
    const double b = glm::dot(f, d); // half the linear coefficient
    const double r = radius + skinM - shrinkM;
    const double c = glm::dot(f, f) - r * r;
    if (c <= 0.0 || b >= 0.0) { // inside already, or moving away
        return {};
    }
    const double disc = b * b - a * c;
    if (disc <= 0.0) {
        return {};
    }
    const double t = c / (-b + std::sqrt(disc)); // the smaller root, in a stable form
    if (t < 0.0 || t >= 1.0) {
        return {};
    }
    SweptEntry e;
    e.found = true;
    e.t = t;
    const double rs = radius + skinM;
    const double cs = glm::dot(f, f) - rs * rs;
    if (cs > 0.0) {
        const double discS = b * b - a * cs;
        e.tStop = discS > 0.0 ? std::clamp(cs / (-b + std::sqrt(discS)), 0.0, t) : t;
    }
    return e;
}

} // namespace hapto
