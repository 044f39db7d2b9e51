#pragma once
// The runtime tests' usual world: one 5 cm cube (id 7, 500 N/m) at the origin of the paper's
// 25 cm work cube.

#include "hapto/scenes/Scene.h"

namespace hapto::test {

inline Scene cubeScene() {
    Material m;
    m.stiffness = 500.0;
    return Scene(Aabb{Vec3(-0.125), Vec3(0.125)},
                 {makeBox(7, Vec3(0), Vec3(0.025), Quat(1, 0, 0, 0), m)});
}

} // namespace hapto::test
