#pragma once
/// The view's JSON spelling of vectors and quaternions, shared by its documents and its live feed.

#include "hapto/core/Geometry.h"

#include <nlohmann/json.hpp>

namespace hapto::detail {

/// A vector as [x, y, z].
inline nlohmann::json vec(const Vec3& v) {
    return nlohmann::json::array({v.x, v.y, v.z});
}

/// A rotation as [w, x, y, z].
inline nlohmann::json quat(const Quat& q) {
    return nlohmann::json::array({q.w, q.x, q.y, q.z});
}

} // namespace hapto::detail
