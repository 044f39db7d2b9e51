#include "hapto/index/IndexStats.h"

#include <algorithm>
#include <bit>

namespace hapto {

void IndexStats::recordLeaves(std::span<const std::uint32_t> counts) {
    leaves = counts.size();
    emptyLeaves = 0;
    objectCellPairs = 0;
    maxObjectsPerLeaf = 0;
    objectsPerLeaf.clear();
    // Bins: 0, 1, 2, 3-4, 5-8, 9-16, ...: bin b >= 1 holds counts in (2^(b-2), 2^(b-1)].
    std::vector<std::uint64_t> bins;
    for (const std::uint32_t c : counts) {
        objectCellPairs += c;
        emptyLeaves += c == 0;
        maxObjectsPerLeaf = std::max(maxObjectsPerLeaf, c);
        const std::size_t bin = c == 0 ? 0 : 1 + std::bit_width(c - 1);
        if (bins.size() <= bin) {
            bins.resize(bin + 1, 0);
        }
        ++bins[bin];
    }
    for (std::size_t b = 0; b < bins.size(); ++b) {
        Bin bin;
        bin.minObjects = b == 0 ? 0 : b == 1 ? 1 : (1u << (b - 2)) + 1;
        bin.maxObjects = b == 0 ? 0 : b >= 33 ? 0xFFFFFFFFu : 1u << (b - 1);
        bin.leaves = bins[b];
        objectsPerLeaf.push_back(bin);
    }
    meanObjectsPerLeaf =
        leaves == 0 ? 0.0 : static_cast<double>(objectCellPairs) / static_cast<double>(leaves);
}

} // namespace hapto
