// Built and run by the install test against an installed hapto, linking hapto::index alone
// (with what it needs: scenes, io, core). It builds a uniform grid over the grasp scene and
// prints how many items the leaf at the scene's centre lists.

#include <hapto/index/IndexSpec.h>
#include <hapto/index/SpatialIndex.h>
#include <hapto/scenes/Generators.h>

#include <cstdio>

using namespace hapto;

int main() {
    const Scene scene = makeGraspScene();
    const auto index = buildIndex(scene, IndexSpec::grid(4));
    const LocateResult found = index->locate(index->bounds().center());
    std::printf("%u items, %zu in the leaf at the centre\n", index->itemCount(),
                found.candidates.size());
    return index->itemCount() > 0 ? 0 : 1;
}
