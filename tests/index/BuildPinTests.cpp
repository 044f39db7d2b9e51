// Pins what the octree and grid builds produce on seeded scenes: every node (cell, kind, first
// child or slot run, links), every leaf's list, the outside objects and the stats' counts and
// bytes, folded into one FNV-1a hash per scene and spec. The figures were taken from the builds
// before they were split into parts; a refactor of the builds must leave them unchanged.

#include "IndexTestScenes.h"
#include "TestSupport.h"

#include "hapto/index/Octree.h"
#include "hapto/index/UniformGrid.h"

#include <catch2/catch.hpp>

#include <cstring>
#include <sstream>
#include <string>

using namespace hapto;
using namespace hapto::test;

namespace {

void addStats(Fnv& f, const SpatialIndex& index) {
    const IndexStats& st = index.stats();
    for (const std::uint64_t v :
         {std::uint64_t(st.objects), st.nodes, st.leaves, st.emptyLeaves, std::uint64_t(st.depth),
          st.leavesAtMinimumSize, st.objectCellPairs, std::uint64_t(st.maxObjectsPerLeaf),
          st.outsideObjects, st.bytes}) {
        f.add(v);
    }
    f.add(index.outsideObjects());
}

std::string octreeLine(const Octree& tree) {
    Fnv f;
    std::uint64_t leaves = 0;
    for (std::uint32_t i = 0; i < tree.nodes().size(); ++i) {
        const OctreeNode& n = tree.nodes()[i];
        f.add(std::uint64_t(n.level()));
        for (int a = 0; a < 3; ++a) {
            f.add(std::uint64_t(n.cell(a)));
        }
        f.add(std::uint64_t(n.isLeaf()));
        f.add(std::uint64_t(n.isLeaf() ? n.firstSlot() : n.firstChild()));
        f.add(std::uint64_t(tree.parent(i)));
        for (const std::uint32_t link : n.neighbours) {
            f.add(std::uint64_t(link));
        }
        if (n.isLeaf()) {
            f.add(tree.leafObjects(i));
            ++leaves;
        }
    }
    addStats(f, tree);
    std::ostringstream s;
    s << tree.nodes().size() << ' ' << leaves << ' ' << std::hex << f.h;
    return s.str();
}

std::string gridLine(const UniformGrid& grid) {
    Fnv f;
    for (std::uint32_t c = 0; c < grid.cellCount(); ++c) {
        f.add(grid.leafObjects(c));
        const Aabb b = grid.leafBounds(c);
        for (int a = 0; a < 3; ++a) {
            f.add(b.min[a]);
            f.add(b.max[a]);
        }
    }
    addStats(f, grid);
    std::ostringstream s;
    s << grid.cellCount() << ' ' << grid.stats().objectCellPairs << ' ' << std::hex << f.h;
    return s.str();
}

// The test scenes, and one large enough that the builds' nested parallel loops run (a node
// with more than 4096 objects).
std::vector<std::pair<std::string, Scene>> pinnedScenes() {
    std::vector<std::pair<std::string, Scene>> s = testScenes();
    ClusterOptions c;
    c.count = 20000;
    c.clusters = 3;
    c.cubeSize = 0.004;
    c.spread = 0.01;
    c.rotate = true;
    c.seed = 31;
    s.emplace_back("large clustered", makeClusterScene(c));
    return s;
}

// One line per scene and spec: "scene | spec | nodes-or-cells leaves-or-pairs hash".
std::string buildLines() {
    std::string out;
    for (const auto& [name, scene] : pinnedScenes()) {
        for (const IndexSpec& spec : testSpecs()) {
            std::string line;
            if (spec.kind == IndexSpec::Kind::Octree) {
                line = octreeLine(*Octree::build(scene, spec));
            } else if (spec.kind == IndexSpec::Kind::Grid) {
                line = gridLine(*UniformGrid::build(scene, spec));
            } else {
                continue;
            }
            out += name + " | " + spec.toString() + " | " + line + "\n";
        }
    }
    return out;
}

// clang-format off
const char* const kPinned = R"(random rotated | grid:1 | 1 300 f3a2ccb991cf4dc3
random rotated | grid:5 | 125 920 ea86175eea330b00
random rotated | grid:16 | 4096 4857 4f6ccfa3d5471765
random rotated | octree:2:0.005 | 7841 6861 447bfc734f7e0b60
random rotated | octree:1:0.001 | 145777 127555 1a5f22bc0f29b002
random rotated | octree:8:0.02 | 473 414 26ec9ba7251c505
random rotated | grid:1:aabb | 1 300 f3a2ccb991cf4dc3
random rotated | grid:5:aabb | 125 1034 b71b486267383e8
random rotated | grid:16:aabb | 4096 7430 5b7cbf387ab53282
random rotated | octree:2:0.005:aabb | 13241 11586 90bc3123c8c6895d
random rotated | octree:1:0.001:aabb | 494681 432846 3d1800a28345de55
random rotated | octree:8:0.02:aabb | 473 414 9e5cb0949aee2dea
clustered rotated | grid:1 | 1 1500 1a6ee2b1f8dba9a1
clustered rotated | grid:5 | 125 1608 c0f9cb0e2cd45805
clustered rotated | grid:16 | 4096 2814 71093bba4d69df31
clustered rotated | octree:2:0.005 | 961 841 536c43f81a0ac355
clustered rotated | octree:1:0.001 | 13377 11705 16ea906e540910b4
clustered rotated | octree:8:0.02 | 153 134 15f6df42939b0026
clustered rotated | grid:1:aabb | 1 1500 1a6ee2b1f8dba9a1
clustered rotated | grid:5:aabb | 125 1608 c0f9cb0e2cd45805
clustered rotated | grid:16:aabb | 4096 2923 b2931c79c3d5da8b
clustered rotated | octree:2:0.005:aabb | 969 848 d4976fd4f37eb179
clustered rotated | octree:1:0.001:aabb | 15137 13245 508717a47cea8250
clustered rotated | octree:8:0.02:aabb | 153 134 b0034dae18073ca
lattice touching | grid:1 | 1 216 1770248dcb53e8e4
lattice touching | grid:5 | 125 1000 48a36a6dec1ef87b
lattice touching | grid:16 | 4096 10648 d66570c89fe194a4
lattice touching | octree:2:0.005 | 4041 3536 d6e2c4e6d06a84c4
lattice touching | octree:1:0.001 | 150921 132056 3e41edeb044e8d4c
lattice touching | octree:8:0.02 | 73 64 61ca54ed58e61131
lattice touching | grid:1:aabb | 1 216 1770248dcb53e8e4
lattice touching | grid:5:aabb | 125 1000 48a36a6dec1ef87b
lattice touching | grid:16:aabb | 4096 10648 d66570c89fe194a4
lattice touching | octree:2:0.005:aabb | 4041 3536 d6e2c4e6d06a84c4
lattice touching | octree:1:0.001:aabb | 150921 132056 3e41edeb044e8d4c
lattice touching | octree:8:0.02:aabb | 73 64 61ca54ed58e61131
lattice paper | grid:1 | 1 125 232d457087a85408
lattice paper | grid:5 | 125 125 d8fb8a8674d6278e
lattice paper | grid:16 | 4096 5832 4a65b589e41f4729
lattice paper | octree:2:0.005 | 4041 3536 e8a694a38994ff94
lattice paper | octree:1:0.001 | 14985 13112 4c3a4ca183aece11
lattice paper | octree:8:0.02 | 73 64 f6f1c340dc1420df
lattice paper | grid:1:aabb | 1 125 232d457087a85408
lattice paper | grid:5:aabb | 125 125 d8fb8a8674d6278e
lattice paper | grid:16:aabb | 4096 5832 4a65b589e41f4729
lattice paper | octree:2:0.005:aabb | 4041 3536 e8a694a38994ff94
lattice paper | octree:1:0.001:aabb | 14985 13112 4c3a4ca183aece11
lattice paper | octree:8:0.02:aabb | 73 64 f6f1c340dc1420df
degenerate | grid:1 | 1 219 79c8dbf097bda2fd
degenerate | grid:5 | 125 567 d9eb021769ddcdc0
degenerate | grid:16 | 4096 6122 7b1dde39529bf184
degenerate | octree:2:0.005 | 4649 4068 97fb749a2713e7dc
degenerate | octree:1:0.001 | 479857 419875 d1d92759bb47f128
degenerate | octree:8:0.02 | 145 127 b45e3a496921d804
degenerate | grid:1:aabb | 1 219 79c8dbf097bda2fd
degenerate | grid:5:aabb | 125 586 f7c65f4898a7472f
degenerate | grid:16:aabb | 4096 6517 547c3ca611747179
degenerate | octree:2:0.005:aabb | 5857 5125 540a9bdec27bff94
degenerate | octree:1:0.001:aabb | 612433 535879 2cd691c2b6b42983
degenerate | octree:8:0.02:aabb | 153 134 3e811df1be162596
meshes | grid:1 | 1 1864 ac5d77f89a5a12d9
meshes | grid:5 | 125 2951 cbba909884faa7
meshes | grid:16 | 4096 6526 133ac92c7ec0cb4c
meshes | octree:2:0.005 | 5977 5230 697d889d7b92a9d5
meshes | octree:1:0.001 | 92177 80655 f33a0a2e7ae7e305
meshes | octree:8:0.02 | 361 316 f2bceddde4605079
meshes | grid:1:aabb | 1 1864 ac5d77f89a5a12d9
meshes | grid:5:aabb | 125 3062 456f4b0c64055278
meshes | grid:16:aabb | 4096 7747 9348d12b3f38b491
meshes | octree:2:0.005:aabb | 6873 6014 bf6e776ee0a95414
meshes | octree:1:0.001:aabb | 166865 146007 9d90cb18b3492001
meshes | octree:8:0.02:aabb | 361 316 39535a850ee8b054
large clustered | grid:1 | 1 20000 799fba508a14326e
large clustered | grid:5 | 125 22808 d1358240807ea18
large clustered | grid:16 | 4096 49080 ec9d619fed2541c4
large clustered | octree:2:0.005 | 2137 1870 7dc636d2f970c170
large clustered | octree:1:0.001 | 61249 53593 a38fd570a2d110a8
large clustered | octree:8:0.02 | 153 134 29f9543f53018710
large clustered | grid:1:aabb | 1 20000 799fba508a14326e
large clustered | grid:5:aabb | 125 22849 1835dbaa53d9e441
large clustered | grid:16:aabb | 4096 52778 c4435be3e2caebb0
large clustered | octree:2:0.005:aabb | 2241 1961 d4936cc485ee1762
large clustered | octree:1:0.001:aabb | 67601 59151 9cbb0424a3a689b2
large clustered | octree:8:0.02:aabb | 153 134 b100c901fdec5664
)";
// clang-format on

} // namespace

TEST_CASE("octree and grid builds give the pinned structures on seeded scenes", "[threads]") {
    CHECK(buildLines() == kPinned);
}
