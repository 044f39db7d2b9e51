// The default index rule: the paper's octree over boxes and spheres, an octree sized by the
// triangles over meshes.

#include "hapto/index/DefaultIndex.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <vector>

namespace hapto {

std::string defaultIndexSpec(const Scene& scene) {
    std::vector<double> edges; // each triangle's longest edge (m)
    for (const SceneObject& o : scene.objects()) {
        if (o.shape != Shape::Mesh || !o.mesh) {
            continue;
        }
        for (std::uint32_t t = 0; t < o.mesh->triangleCount(); ++t) {
            const auto [p, q, r] = o.mesh->corners(t);
            edges.push_back(std::sqrt(std::max(
                {glm::dot(q - p, q - p), glm::dot(r - q, r - q), glm::dot(p - r, p - r)})));
        }
    }
    if (edges.empty()) {
        return std::string(kDefaultIndexSpec);
    }
    const auto middle = edges.begin() + static_cast<std::ptrdiff_t>(edges.size() / 2);
    std::nth_element(edges.begin(), middle, edges.end());
    const double edge = std::clamp(*middle, kMeshIndexMinLeafM, kMeshIndexMaxLeafM);
    char spec[64];
    std::snprintf(spec, sizeof spec, "octree:%d:%.2g", kMeshIndexLeafItems, edge);
    return spec;
}

IndexSpec sessionIndexSpec(std::string_view given, const Scene& scene, std::uint64_t maxMegabytes) {
    if (given.empty()) {
        return IndexSpec::parse(defaultIndexSpec(scene)).withMaxMegabytes(maxMegabytes);
    }
    return IndexSpec::parse(given).withMaxMegabytes(maxMegabytes);
}

} // namespace hapto
