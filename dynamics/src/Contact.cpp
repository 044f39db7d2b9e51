#include "hapto/dynamics/Contact.h"

namespace hapto {

// The narrow phase; a placeholder until the pair tests land: reports nothing.
void collide(const ConvexShape&, const ConvexShape&, double, ContactManifold& out) noexcept {
    out.count = 0;
}

} // namespace hapto
