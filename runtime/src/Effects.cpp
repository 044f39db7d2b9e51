#include "hapto/runtime/Effects.h"

#include <stdexcept>
#include <string>

namespace hapto {

Vec3 effectForceN(const ForceEffect& e, const Vec3& p, const Vec3& v) noexcept {
    if (!e.enabled || !e.region.contains(p)) {
        return Vec3(0.0);
    }
    switch (e.type) {
    case EffectType::Spring: {
        const Vec3 r = p - e.anchorM;
        switch (e.target) {
        case SpringTarget::Point:
            return -e.stiffnessNPerM * r;
        case SpringTarget::Line: // the offset across the line
            return -e.stiffnessNPerM * (r - glm::dot(r, e.axis) * e.axis);
        case SpringTarget::Plane: // the offset along the normal
            return -e.stiffnessNPerM * glm::dot(r, e.axis) * e.axis;
        }
        break;
    }
    case EffectType::Damper:
        return -e.dampingNsPerM * v;
    case EffectType::Constant:
        return e.forceN;
    }
    return Vec3(0.0);
}

EffectSet::EffectSet(std::span<const ForceEffect> effects) {
    if (effects.size() > kCapacity) {
        throw std::invalid_argument("effects: at most " + std::to_string(kCapacity) +
                                    " per device (got " + std::to_string(effects.size()) + ")");
    }
    for (std::size_t i = 0; i < effects.size(); ++i) {
        if (const std::optional<EffectProblem> problem = checkForceEffect(effects[i])) {
            throw std::invalid_argument("effects[" + std::to_string(i) + "]." + problem->field +
                                        ": " + problem->message);
        }
        mEffects[i] = effects[i];
    }
    mCount = static_cast<std::uint32_t>(effects.size());
}

bool EffectSet::setEnabled(std::size_t index, bool enabled) noexcept {
    if (index >= mCount) {
        return false;
    }
    mEffects[index].enabled = enabled;
    return true;
}

Vec3 EffectSet::forceN(const Vec3& p, const Vec3& v) const noexcept {
    Vec3 sum(0.0);
    for (std::uint32_t i = 0; i < mCount; ++i) {
        sum += effectForceN(mEffects[i], p, v);
    }
    return sum;
}

} // namespace hapto
