#pragma once
/// The force-effect model: springs, dampers and constant forces with the region where each acts,
/// their bounds, and checkForceEffect(), the one home of the effect rules.

#include "hapto/core/Geometry.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace hapto {

/// What a force effect does (JSON `"type"`).
enum class EffectType : std::uint8_t {
    Spring,   ///< Pulls the device point to a point, a line or a plane (`spring`).
    Damper,   ///< Viscosity, F = -b v (`damper`).
    Constant, ///< A constant force (`constant`).
};

/// What a spring pulls to.
enum class SpringTarget : std::uint8_t {
    Point, ///< The anchor: F = -k (x - anchor).
    Line,  ///< The line through the anchor along `axis`: only the offset across it pulls.
    Plane, ///< The plane through the anchor with normal `axis`: only the offset along the
           ///< normal pulls (both sides; a spring, not a wall).
};

/// The shape of the place where an effect acts.
enum class RegionShape : std::uint8_t {
    Everywhere, ///< No region (the default).
    Box,        ///< An axis-aligned box, world frame.
    Sphere,     ///< A ball.
};

/// Where an effect acts (m, world frame): everywhere, inside an axis-aligned box or inside a
/// sphere, the boundary included. JSON `"region": {"box": {"center": [x, y, z],
/// "half_extents": [hx, hy, hz]}}` or `{"sphere": {"center": [x, y, z], "radius_m": r}}`.
struct EffectRegion {
    RegionShape shape = RegionShape::Everywhere; ///< Everywhere, a box or a sphere.
    Vec3 centerM{0.0};                           ///< Box or sphere centre (m).
    Vec3 halfExtentsM{0.0}; ///< Box: half its size along x, y, z (m), each > 0.
    double radiusM = 0.0;   ///< Sphere: its radius (m), > 0.

    /// A box around `center` (m) with half sizes `halfExtents` (m). [any thread]
    static EffectRegion box(const Vec3& center, const Vec3& halfExtents) noexcept {
        return {RegionShape::Box, center, halfExtents, 0.0};
    }
    /// A ball around `center` (m) of radius `radius` (m). [any thread]
    static EffectRegion sphere(const Vec3& center, double radius) noexcept {
        return {RegionShape::Sphere, center, Vec3(0.0), radius};
    }
    /// True when the world point `p` (m) is inside (boundary included). [servo]
    bool contains(const Vec3& p) const noexcept {
        switch (shape) {
        case RegionShape::Box: {
            const Vec3 d = glm::abs(p - centerM);
            return d.x <= halfExtentsM.x && d.y <= halfExtentsM.y && d.z <= halfExtentsM.z;
        }
        case RegionShape::Sphere: {
            const Vec3 d = p - centerM;
            return glm::dot(d, d) <= radiusM * radiusM;
        }
        case RegionShape::Everywhere:
            break;
        }
        return true;
    }
};

/// Effects one device may have at once (a fixed capacity: the servo thread's copy never
/// allocates).
inline constexpr std::size_t kMaxEffectsPerDevice = 8;
/// Largest spring stiffness (N/m). A chosen bound, not a device fact: several times what
/// desktop devices render stably at 1 kHz; a stiffer spring only oscillates. The force is
/// clamped to the device's maximum besides.
inline constexpr double kMaxEffectStiffnessNPerM = 10'000.0;
/// Largest damping (N·s/m), for damper effects and the renderer's contact damping alike. A
/// chosen bound: 100 N·s/m resists a 0.1 m/s hand motion with 10 N, more than a desktop
/// device's peak force.
inline constexpr double kMaxDampingNsPerM = 100.0;
/// Largest constant force (N), per effect. A chosen bound, ten times a PHANToM Premium's
/// 8.5 N peak; the device's own clamp applies as well.
inline constexpr double kMaxEffectForceN = 100.0;
/// Largest |coordinate| of an anchor or region centre, and largest region size (m): the bound
/// on lengths every hapto input has.
inline constexpr double kMaxEffectLengthM = 1e6;

/// One force effect of a device: a plain value (world frame, SI units), checked by
/// checkForceEffect() and evaluated every servo tick by the runtime (Effects.h), its force added
/// to the proxy's before the safety filter. JSON: one object of a device's `"effects"` list
/// (README.md "Force effects"), read by parseDeviceFile() (DeviceFile.h).
struct ForceEffect {
    EffectType type = EffectType::Constant;    ///< JSON `type`.
    bool enabled = true;                       ///< Off: no force. JSON `enabled`.
    SpringTarget target = SpringTarget::Point; ///< Spring: point, line (JSON `direction`) or
                                               ///< plane (JSON `normal`).
    Vec3 anchorM{0.0}; ///< Spring: the point, or a point of the line or plane (m). `anchor`.
    Vec3 axis{0.0};    ///< Spring: the line's direction or the plane's normal, unit length.
    double stiffnessNPerM = 0.0; ///< Spring: k (N/m), 0..kMaxEffectStiffnessNPerM.
                                 ///< `stiffness_n_per_m`.
    double dampingNsPerM = 0.0;  ///< Damper: b (N·s/m), 0..kMaxDampingNsPerM.
                                 ///< `damping_n_s_per_m`.
    Vec3 forceN{0.0};            ///< Constant: the force (N), |F| <= kMaxEffectForceN. `force_n`.
    EffectRegion region;         ///< Where the effect acts; everywhere by default. `region`.

    /// A spring of stiffness `k` (N/m) to the point `anchor` (m). [any thread]
    static ForceEffect springToPoint(const Vec3& anchor, double k) noexcept;
    /// A spring of stiffness `k` (N/m) to the line through `anchor` (m) along `direction`
    /// (any non-zero length; normalised). [any thread]
    static ForceEffect springToLine(const Vec3& anchor, const Vec3& direction, double k) noexcept;
    /// A spring of stiffness `k` (N/m) to the plane through `anchor` (m) with `normal` (any
    /// non-zero length; normalised). [any thread]
    static ForceEffect springToPlane(const Vec3& anchor, const Vec3& normal, double k) noexcept;
    /// A damper of `b` (N·s/m) inside `region` (everywhere by default). [any thread]
    static ForceEffect damper(double b, const EffectRegion& region = {}) noexcept;
    /// A constant force (N, world). [any thread]
    static ForceEffect constant(const Vec3& forceN) noexcept;
};

/// What is wrong with an effect: the JSON field (as in a device file, e.g.
/// `stiffness_n_per_m`, `region.sphere.radius_m`) and what to do.
struct EffectProblem {
    std::string field;   ///< The JSON field at fault, e.g. `region.sphere.radius_m`.
    std::string message; ///< What is wrong and what to do.
};
/// The first problem of `effect` (a gain, force or length out of its documented range, a
/// non-finite value, an axis that is not of unit length), or none. The one home of the
/// effect rules: device files, EffectSet and Runtime::setEffects() all apply it. [any thread]
std::optional<EffectProblem> checkForceEffect(const ForceEffect& effect);

} // namespace hapto
