#pragma once
/// The items an index holds, enumerated once for every builder (internal).
///
/// A builder works on the scene's indexed items (Scene.h): boxes and spheres by their slot,
/// mesh triangles as triangle items, mesh objects' own slots left out. Their ids ascend in
/// dense order (slots below kTriangleItemBit, triangles above it), so a list kept in the order
/// of this enumeration is a list of ascending item ids.

#include "hapto/scenes/Scene.h"

#include <cstdint>
#include <vector>

namespace hapto::detail {

/// The scene's indexed items, ascending. [control]
inline std::vector<std::uint32_t> indexedItems(const Scene& scene) {
    std::vector<std::uint32_t> items;
    items.reserve(scene.itemCount());
    for (std::uint32_t i = 0; i < scene.itemCount(); ++i) {
        const std::uint32_t item = scene.item(i);
        if (scene.isIndexed(item)) {
            items.push_back(item);
        }
    }
    return items;
}

/// How many items indexedItems() gives: the boxes, spheres and triangles, O(objects). [control]
inline std::uint64_t indexedItemCount(const Scene& scene) {
    std::uint64_t meshes = 0;
    for (const SceneObject& o : scene.objects()) {
        meshes += o.shape == Shape::Mesh ? 1 : 0;
    }
    return scene.itemCount() - meshes;
}

} // namespace hapto::detail
