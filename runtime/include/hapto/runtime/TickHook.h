#pragma once
/// A per-tick hook: an application's own function, called on a device's servo thread every
/// tick, adding a force of its own.
///
/// Servo-path rules for a hook (the same as for the rest of the tick): it runs on the servo
/// thread, at the device's rate (1 kHz or faster), inside the tick's time budget. It must not
/// allocate (no new, no growing a std::vector or std::string, no std::function), lock a mutex,
/// log, print, make a syscall, throw, or wait for anything; it may read atomics and plain data
/// that do not change while the runtime runs, and do a few microseconds of arithmetic. Data
/// shared with the control thread goes through atomics or a Mailbox (hapto/core/Mailbox.h).
/// Its result is added to the proxy's force before the safety filter, so it is clamped and
/// rate-limited like contact; a non-finite result is replaced by zero and counted
/// (DeviceReport::hookNonFinite), the rest of the tick's force still applies.

#include "hapto/core/Geometry.h"
#include "hapto/devices/Device.h"
#include "hapto/runtime/GodObjectRenderer.h"

#include <span>
#include <type_traits>

namespace hapto {

/// What a hook is given, for this tick (world frame unless said).
struct TickHookArgs {
    const DeviceState& sample;         ///< The device's reading (its own frame, as read()).
    Vec3 devicePointM;                 ///< The device point (m).
    Vec3 velocityMPerS;                ///< Its velocity (m/s), measured or estimated.
    Vec3 proxyM;                       ///< The god-object proxy after this tick's render (m).
    std::span<const Contact> contacts; ///< The proxy's active contacts this tick (0..3).
    Vec3 renderForceN;                 ///< The renderer's force this tick (N).
    double dtS;                        ///< Seconds since the last tick (the servo period).
};

/// The hook: returns an extra force (N, world frame). `context` is the pointer registered
/// with it. A plain function pointer (a captureless lambda declared noexcept converts to it),
/// so calling it never allocates.
using TickHookFn = Vec3 (*)(void* context, const TickHookArgs& args) noexcept;

namespace detail {
/// What TickHook's constructor was given as its function: a hook, or which rule it breaks.
enum class HookForm { Hook, NotNoexcept, Captures, Other };
template <typename F> constexpr HookForm hookForm() {
    if constexpr (std::is_convertible_v<F, TickHookFn>) {
        return HookForm::Hook;
    } else if constexpr (std::is_convertible_v<F, Vec3 (*)(void*, const TickHookArgs&)>) {
        return HookForm::NotNoexcept;
    } else if constexpr (std::is_class_v<F> &&
                         std::is_invocable_v<F&, void*, const TickHookArgs&>) {
        return HookForm::Captures; // a callable object: a lambda with captures, or a functor
    } else {
        return HookForm::Other;
    }
}
} // namespace detail

/// A hook and its context; no hook when `fn` is null. `TickHook{&fn, &data}` or
/// `{[](void* context, const TickHookArgs& tick) noexcept { ... }, &data}`: a function or a
/// lambda that captures nothing, declared noexcept; its data comes through the context pointer.
/// Anything else stops the compilation with a message saying which rule it breaks.
struct TickHook {
    TickHookFn fn = nullptr; ///< Called every tick on the servo thread, or null.
    void* context = nullptr; ///< Passed back to fn; must stay valid while ticks run.

    /// No hook.
    constexpr TickHook() noexcept = default;
    /// `hook` called with `hookContext` every tick. [any thread]
    template <typename F, typename C> constexpr TickHook(F hook, C hookContext) noexcept {
        constexpr detail::HookForm form = detail::hookForm<F>();
        static_assert(form != detail::HookForm::NotNoexcept,
                      "hapto::TickHook: declare the hook noexcept: "
                      "Vec3 hook(void* context, const TickHookArgs& tick) noexcept");
        static_assert(form != detail::HookForm::Captures,
                      "hapto::TickHook: a hook cannot capture (it is a plain function pointer): "
                      "pass its data through the context pointer, TickHook{hook, &data}, and "
                      "declare it noexcept");
        static_assert(form != detail::HookForm::Other,
                      "hapto::TickHook: a hook is "
                      "Vec3 hook(void* context, const TickHookArgs& tick) noexcept");
        static_assert(std::is_convertible_v<C, void*>,
                      "hapto::TickHook: the context pointer is a void*: a pointer to data the "
                      "hook may change (not a pointer to const), or nullptr");
        if constexpr (form == detail::HookForm::Hook && std::is_convertible_v<C, void*>) {
            fn = hook;
            context = hookContext;
        }
    }
};

} // namespace hapto
