// A device file's runtime fields: each entry's force effects (`effects`) and renderer settings
// (`renderer`), read through the device parser's DeviceEntryReader so their messages name the
// file and the JSON path as every other field's do, and the file's first bad value is the one
// named.

#include "hapto/runtime/DeviceFile.h"

#include "hapto/runtime/BodyCoupling.h"

#include "hapto/io/JsonInput.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace hapto {
namespace {

using namespace hapto::json;

/// Fails at `path` + the problem's dotted field (`region.sphere.radius_m`), so the message
/// names the JSON path of the bad value.
[[noreturn]] void failEffect(const Source& w, const Path& path, const EffectProblem& problem) {
    std::vector<std::string> parts;
    for (std::size_t from = 0;;) {
        const std::size_t dot = problem.field.find('.', from);
        parts.push_back(problem.field.substr(from, dot - from));
        if (dot == std::string::npos) {
            break;
        }
        from = dot + 1;
    }
    std::vector<Path> chain(parts.size()); // reserved: each level points at the one before
    const Path* at = &path;
    for (std::size_t i = 0; i < parts.size(); ++i) {
        chain[i] = *at / parts[i].c_str();
        at = &chain[i];
    }
    w.fail(*at, problem.message);
}

EffectRegion parseRegion(const Source& w, const Json& j, const Path& path) {
    object(w, j, path);
    checkKeys(w, j, path, {"box", "sphere"});
    const Json* box = optional(j, "box");
    const Json* sphere = optional(j, "sphere");
    if ((box != nullptr) == (sphere != nullptr)) {
        w.fail(path, "a region is one of {\"box\": {...}} or {\"sphere\": {...}}");
    }
    if (box) {
        const Path at = path / "box";
        object(w, *box, at);
        checkKeys(w, *box, at, {"center", "half_extents"});
        return EffectRegion::box(
            vec3(w, required(w, *box, at, "center"), at / "center"),
            vec3(w, required(w, *box, at, "half_extents"), at / "half_extents"));
    }
    const Path at = path / "sphere";
    object(w, *sphere, at);
    checkKeys(w, *sphere, at, {"center", "radius_m"});
    return EffectRegion::sphere(vec3(w, required(w, *sphere, at, "center"), at / "center"),
                                number(w, required(w, *sphere, at, "radius_m"), at / "radius_m"));
}

/// One object of a device's `effects` list; its type decides which fields it may have.
ForceEffect parseEffect(const Source& w, const Json& j, const Path& path) {
    object(w, j, path);
    const std::string type = string(w, required(w, j, path, "type"), path / "type");
    ForceEffect e;
    if (type == "spring") {
        checkKeys(
            w, j, path,
            {"type", "enabled", "anchor", "stiffness_n_per_m", "direction", "normal", "region"});
        e.type = EffectType::Spring;
        e.anchorM = vec3(w, required(w, j, path, "anchor"), path / "anchor");
        e.stiffnessNPerM =
            number(w, required(w, j, path, "stiffness_n_per_m"), path / "stiffness_n_per_m");
        const Json* direction = optional(j, "direction");
        const Json* normal = optional(j, "normal");
        if (direction && normal) {
            w.fail(path / "normal", "a spring pulls to a line (\"direction\") or to a plane "
                                    "(\"normal\"), not both");
        }
        if (direction || normal) {
            const char* field = direction ? "direction" : "normal";
            const Vec3 axis = vec3(w, direction ? *direction : *normal, path / field);
            // Scaled by its largest component first: the squares of [1e308, 1e308, 0] overflow
            // and those of [1e-200, 1e-200, 0] underflow, yet both are directions.
            const double largest = std::max({std::abs(axis.x), std::abs(axis.y), std::abs(axis.z)});
            if (!(largest > 0)) {
                w.fail(path / field, std::string("the ") + field + " must not be zero (got [" +
                                         show(axis.x) + ", " + show(axis.y) + ", " + show(axis.z) +
                                         "])");
            }
            e.target = direction ? SpringTarget::Line : SpringTarget::Plane;
            const Vec3 scaled = axis / largest;
            e.axis = scaled / glm::length(scaled);
        }
    } else if (type == "damper") {
        checkKeys(w, j, path, {"type", "enabled", "damping_n_s_per_m", "region"});
        e.type = EffectType::Damper;
        e.dampingNsPerM =
            number(w, required(w, j, path, "damping_n_s_per_m"), path / "damping_n_s_per_m");
    } else if (type == "constant") {
        checkKeys(w, j, path, {"type", "enabled", "force_n", "region"});
        e.type = EffectType::Constant;
        e.forceN = vec3(w, required(w, j, path, "force_n"), path / "force_n");
    } else {
        w.fail(path / "type", "unknown effect type '" + printable(type) +
                                  "' (expected spring, damper or constant)");
    }
    if (const Json* v = optional(j, "enabled")) {
        e.enabled = boolean(w, *v, path / "enabled");
    }
    if (const Json* v = optional(j, "region")) {
        e.region = parseRegion(w, *v, path / "region");
    }
    if (const std::optional<EffectProblem> problem = checkForceEffect(e)) {
        failEffect(w, path, *problem);
    }
    return e;
}

std::vector<ForceEffect> parseEffects(const Source& w, const Json& j, const Path& path) {
    if (!j.is_array()) {
        w.fail(path, "expected an array of effects, got " + typeName(j));
    }
    if (j.size() > kMaxEffectsPerDevice) {
        w.fail(path, "at most " + std::to_string(kMaxEffectsPerDevice) +
                         " effects per device (got " + std::to_string(j.size()) + ")");
    }
    std::vector<ForceEffect> out;
    for (std::size_t i = 0; i < j.size(); ++i) {
        out.push_back(parseEffect(w, j[i], path[i]));
    }
    return out;
}

RendererSettings parseRenderer(const Source& w, const Json& j, const Path& path) {
    object(w, j, path);
    checkKeys(w, j, path, {"damping_n_s_per_m", "torsion_radius_m"});
    RendererSettings s;
    const Json* damping = optional(j, "damping_n_s_per_m");
    const Json* torsion = optional(j, "torsion_radius_m");
    if (damping == nullptr && torsion == nullptr) {
        w.fail(path, "expected 'damping_n_s_per_m' or 'torsion_radius_m' (or both)");
    }
    if (damping != nullptr) {
        s.contactDampingNsPerM = ranged(w, *damping, path / "damping_n_s_per_m", 0.0,
                                        kMaxDampingNsPerM, false, "the contact damping (N·s/m)");
    }
    if (torsion != nullptr) {
        s.torsionRadiusM = ranged(w, *torsion, path / "torsion_radius_m", 0.0, kMaxTorsionRadiusM,
                                  false, "the torsional radius (m)");
    }
    return s;
}

/// One device entry's `effects` and `renderer` (DeviceEntryReader).
DeviceRendering parseRendering(const Source& w, const Json& j, const Path& path) {
    DeviceRendering r;
    if (const Json* v = optional(j, "effects")) {
        r.effects = parseEffects(w, *v, path / "effects");
    }
    if (const Json* v = optional(j, "renderer")) {
        r.renderer = parseRenderer(w, *v, path / "renderer");
    }
    return r;
}

/// A reader that keeps each entry's rendering in `out`, in file order.
DeviceEntryReader readInto(std::vector<DeviceRendering>& out) {
    return [&out](std::size_t device, const Json& entry, const Source& w, const Path& path) {
        out.resize(device + 1);
        out[device] = parseRendering(w, entry, path);
    };
}

} // namespace

DeviceFile loadDeviceFile(const std::filesystem::path& path) {
    DeviceFile file;
    file.devices = loadDeviceConfigFile(path, readInto(file.rendering));
    return file;
}

DeviceFile parseDeviceFile(std::string_view text, std::string_view sourceName) {
    DeviceFile file;
    file.devices = parseDeviceConfig(text, sourceName, readInto(file.rendering));
    return file;
}

} // namespace hapto
