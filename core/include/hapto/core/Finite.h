#pragma once
/// finite(): true when every component of a vector is a finite number (no NaN, no infinity).

#include "hapto/core/Geometry.h"

#include <cmath>

namespace hapto {

/// True when x, y and z are all finite. [servo]
inline bool finite(const Vec3& v) noexcept {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

} // namespace hapto
