// Proves the dynamics step never allocates: this binary replaces the global operator new
// (tests/support/CountingNew.h) and counts every allocation made while stepping a closed box
// of bouncing, sliding and resting bodies.

#include "CountingNew.h"
#include "DynamicsTestScenes.h"

#include <catch2/catch.hpp>

using namespace hapto;
using namespace hapto::test;

TEST_CASE("the dynamics step allocates nothing", "[dynamics][threads]") {
    World w(closedBoxScene()); // sleeping on: bodies fall asleep and wake during the run
    const std::uint64_t before = gAllocations.load();
    for (int k = 0; k < 3000; ++k) {
        w.dynamics->step();
        if (k == 1500) {
            w.dynamics->applyImpulse(0, Vec3(0.05, 0.1, 0.0), Vec3(0.0));
        }
    }
    CHECK(gAllocations.load() == before);
    std::vector<int> live(3); // the counter is live
    CHECK(gAllocations.load() > before);
}
