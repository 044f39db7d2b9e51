#pragma once
/// A device's own renderer settings (a device file's `"renderer"`), laid over the runtime's.

#include "hapto/runtime/ForceEffect.h"
#include "hapto/runtime/RenderOutput.h"

#include <optional>

namespace hapto {

/// What one device changes in the renderer the runtime gives every device
/// (RuntimeOptions::renderer). JSON `"renderer": {"damping_n_s_per_m": b}`.
struct RendererSettings {
    /// The renderer's contact damping b (N·s/m), 0..kMaxDampingNsPerM; none = the runtime's
    /// RuntimeOptions::renderer.damping.
    std::optional<double> contactDampingNsPerM;
    /// The hand's effective torsional radius (m), 0..kMaxTorsionRadiusM (BodyCoupling.h: the
    /// soft-finger patch on dynamic bodies; 0 turns it off); none = the runtime's
    /// RuntimeOptions::renderer.torsionRadiusM.
    std::optional<double> torsionRadiusM;
};

/// `runtime` (the settings every device gets) with one device's own `settings` applied, for a
/// device whose transform scales its motion into the world by `worldScale` (world metres per
/// device metre): the proxy's step is that many times `runtime`'s, the same motion of the
/// hand. [control]
inline RendererConfig withDeviceSettings(const RendererConfig& runtime,
                                         const RendererSettings& settings,
                                         double worldScale = 1.0) {
    RendererConfig c = runtime;
    c.maxProxyStepM *= worldScale;
    if (settings.contactDampingNsPerM) {
        c.damping = *settings.contactDampingNsPerM;
    }
    if (settings.torsionRadiusM) {
        c.torsionRadiusM = *settings.torsionRadiusM;
    }
    return c;
}

} // namespace hapto
