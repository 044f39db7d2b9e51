// Compiled (syntax only) by the "tick hook misuse" ctests, once per HAPTO_MISUSE: each misuse
// must stop the compilation with TickHook's own message (tests/runtime/CMakeLists.txt), not
// with "cannot convert '<brace-enclosed initializer list>' to 'const hapto::TickHook&'".
// HAPTO_MISUSE=0 compiles: the forms the user guide shows (docs/guide/library.md).

#include "hapto/runtime/Runtime.h"

using namespace hapto;

namespace {

struct Spring {
    double stiffnessNPerM = 20.0;
};

Vec3 spring(void* context, const TickHookArgs& tick) noexcept {
    return -static_cast<Spring*>(context)->stiffnessNPerM * tick.devicePointM;
}

[[maybe_unused]] Vec3 springThatMayThrow(void* context, const TickHookArgs& tick) {
    return -static_cast<Spring*>(context)->stiffnessNPerM * tick.devicePointM;
}

} // namespace

void registerHooks(Runtime& runtime) {
    Spring data;
    [[maybe_unused]] const Spring constant;
    runtime.setTickHook(0, {&spring, &data});
    runtime.setTickHook(0,
                        {[](void*, const TickHookArgs&) noexcept { return Vec3(0.0); }, nullptr});
#if HAPTO_MISUSE == 1 // a lambda without noexcept
    runtime.setTickHook(0, {[](void*, const TickHookArgs&) { return Vec3(0.0); }, &data});
#elif HAPTO_MISUSE == 2 // a function without noexcept
    runtime.setTickHook(0, {&springThatMayThrow, &data});
#elif HAPTO_MISUSE == 3 // a lambda that captures
    runtime.setTickHook(0, {[&data](void*, const TickHookArgs& tick) noexcept {
                                return -data.stiffnessNPerM * tick.devicePointM;
                            },
                            nullptr});
#elif HAPTO_MISUSE == 4 // a context pointer to const
    runtime.setTickHook(0, {&spring, &constant});
#elif HAPTO_MISUSE == 5 // another signature
    runtime.setTickHook(0, {[](const TickHookArgs&) noexcept { return Vec3(0.0); }, &data});
#endif
}
