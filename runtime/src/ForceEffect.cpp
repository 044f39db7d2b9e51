// The force-effect model's factories and its rules (checkForceEffect), applied by device files,
// EffectSet and Runtime::setEffects() alike.

#include "hapto/runtime/ForceEffect.h"

#include "hapto/io/JsonInput.h"

#include <cmath>

namespace hapto {

using json::show;

ForceEffect ForceEffect::springToPoint(const Vec3& anchor, double k) noexcept {
    ForceEffect e;
    e.type = EffectType::Spring;
    e.anchorM = anchor;
    e.stiffnessNPerM = k;
    return e;
}

ForceEffect ForceEffect::springToLine(const Vec3& anchor, const Vec3& direction,
                                      double k) noexcept {
    ForceEffect e = springToPoint(anchor, k);
    e.target = SpringTarget::Line;
    e.axis = direction / glm::length(direction);
    return e;
}

ForceEffect ForceEffect::springToPlane(const Vec3& anchor, const Vec3& normal, double k) noexcept {
    ForceEffect e = springToPoint(anchor, k);
    e.target = SpringTarget::Plane;
    e.axis = normal / glm::length(normal);
    return e;
}

ForceEffect ForceEffect::damper(double b, const EffectRegion& region) noexcept {
    ForceEffect e;
    e.type = EffectType::Damper;
    e.dampingNsPerM = b;
    e.region = region;
    return e;
}

ForceEffect ForceEffect::constant(const Vec3& forceN) noexcept {
    ForceEffect e;
    e.type = EffectType::Constant;
    e.forceN = forceN;
    return e;
}

std::optional<EffectProblem> checkForceEffect(const ForceEffect& e) {
    const auto inRange = [](double v, double lo, double hi) {
        return std::isfinite(v) && v >= lo && v <= hi;
    };
    const auto range = [](const char* what, double v, double lo, double hi) {
        return std::string(what) + " must be in " + show(lo) + ".." + show(hi) + " (got " +
               show(v) + ")";
    };
    // A point within the bound on lengths, every coordinate finite.
    const auto place = [](const Vec3& p) {
        return std::abs(p.x) <= kMaxEffectLengthM && std::abs(p.y) <= kMaxEffectLengthM &&
               std::abs(p.z) <= kMaxEffectLengthM; // false for NaN
    };
    const std::string bound = "each coordinate finite and within +-" + show(kMaxEffectLengthM);
    switch (e.type) {
    case EffectType::Spring:
        if (!place(e.anchorM)) {
            return EffectProblem{"anchor", "the anchor (m) must have " + bound};
        }
        if (!inRange(e.stiffnessNPerM, 0.0, kMaxEffectStiffnessNPerM)) {
            return EffectProblem{"stiffness_n_per_m", range("the stiffness (N/m)", e.stiffnessNPerM,
                                                            0.0, kMaxEffectStiffnessNPerM) +
                                                          "; a stiffer spring only oscillates"};
        }
        if (e.target != SpringTarget::Point) {
            const double length = glm::length(e.axis);
            if (!(std::abs(length - 1.0) <= 1e-6)) {
                return EffectProblem{e.target == SpringTarget::Line ? "direction" : "normal",
                                     "must be a unit vector (got length " + show(length) +
                                         "; ForceEffect::springToLine and springToPlane "
                                         "normalise)"};
            }
        }
        break;
    case EffectType::Damper:
        if (!inRange(e.dampingNsPerM, 0.0, kMaxDampingNsPerM)) {
            return EffectProblem{"damping_n_s_per_m", range("the damping (N·s/m)", e.dampingNsPerM,
                                                            0.0, kMaxDampingNsPerM)};
        }
        break;
    case EffectType::Constant: {
        const double magnitude = glm::length(e.forceN);
        if (!inRange(magnitude, 0.0, kMaxEffectForceN)) {
            return EffectProblem{
                "force_n", range("the force's magnitude (N)", magnitude, 0.0, kMaxEffectForceN)};
        }
        break;
    }
    default:
        return EffectProblem{"type", "unknown effect type"};
    }
    switch (e.region.shape) {
    case RegionShape::Everywhere:
        break;
    case RegionShape::Box:
        if (!place(e.region.centerM)) {
            return EffectProblem{"region.box.center", "the centre (m) must have " + bound};
        }
        for (int a = 0; a < 3; ++a) {
            const double h = e.region.halfExtentsM[a];
            if (!(std::isfinite(h) && h > 0.0 && h <= kMaxEffectLengthM)) {
                return EffectProblem{"region.box.half_extents",
                                     "each half extent (m) must be > 0 and <= " +
                                         show(kMaxEffectLengthM) + " (got " + show(h) + ")"};
            }
        }
        break;
    case RegionShape::Sphere:
        if (!place(e.region.centerM)) {
            return EffectProblem{"region.sphere.center", "the centre (m) must have " + bound};
        }
        if (!(std::isfinite(e.region.radiusM) && e.region.radiusM > 0.0 &&
              e.region.radiusM <= kMaxEffectLengthM)) {
            return EffectProblem{"region.sphere.radius_m",
                                 "the radius (m) must be > 0 and <= " + show(kMaxEffectLengthM) +
                                     " (got " + show(e.region.radiusM) + ")"};
        }
        break;
    default:
        return EffectProblem{"region", "unknown region shape"};
    }
    return std::nullopt;
}

} // namespace hapto
