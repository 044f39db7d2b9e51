// `hapto query` and `hapto index-stats`: build a spatial index over a scene and ask it things.

#include "Commands.h"
#include "Options.h"

#include "hapto/index/Cursor.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/io/InputFile.h"
#include "hapto/io/OutputFile.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace hapto::cli {
namespace {

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) {
        s.remove_prefix(1);
    }
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
        s.remove_suffix(1);
    }
    return s;
}

} // namespace

std::vector<Vec3> readPoints(const std::string& path, const std::string& what) {
    const std::string all = InputFile(path, what).readAll();
    std::vector<Vec3> points;
    std::size_t lineStart = 0;
    for (std::size_t number = 1; lineStart < all.size(); ++number) {
        std::size_t lineEnd = all.find('\n', lineStart);
        if (lineEnd == std::string::npos) {
            lineEnd = all.size();
        }
        const std::string_view text =
            trim(std::string_view(all).substr(lineStart, lineEnd - lineStart));
        lineStart = lineEnd + 1;
        if (text.empty() || (points.empty() && text == "x,y,z")) {
            continue;
        }
        Vec3 p(0.0);
        std::string_view rest = text;
        bool ok = true;
        for (int a = 0; a < 3 && ok; ++a) {
            const std::size_t comma = rest.find(',');
            const bool last = a == 2;
            if (last == (comma != std::string_view::npos)) {
                ok = false;
                break;
            }
            const std::string_view field = trim(rest.substr(0, comma));
            const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), p[a]);
            ok = ec == std::errc() && ptr == field.data() + field.size() && !field.empty() &&
                 std::isfinite(p[a]);
            rest = last ? std::string_view() : rest.substr(comma + 1);
        }
        if (!ok) {
            throw InputError(path + ":" + std::to_string(number) +
                             ": expected a point as three finite numbers x,y,z in metres (e.g. "
                             "0.01,-0.02,0.005), got '" +
                             std::string(text) + "'");
        }
        points.push_back(p);
    }
    return points;
}

namespace {

void runQuery(const std::string& scenePath, const std::string& specText,
              const std::string& pointsPath, const std::string& outPath, std::uint64_t maxIndexMb) {
    if (!specText.empty()) {
        IndexSpec::parse(specText); // a bad --index is refused before any file is read
    }
    if (!outPath.empty()) {
        refuseSameFile(outPath, "-o", scenePath, "--scene");
        refuseSameFile(outPath, "-o", pointsPath, "--points");
        checkOutputFile(outPath, "-o");
    }
    const std::vector<Vec3> points = readPoints(pointsPath, "points file");
    const Scene scene = loadSceneOrDefault(scenePath);
    const std::unique_ptr<SpatialIndex> index =
        buildIndex(scene, sessionIndexSpec(specText, scene, maxIndexMb));

    TextOutput out(outPath);
    std::string& text = out.text();
    text = "point,candidates\n";
    Cursor cursor(*index);
    // A candidate is an object id, or for a mesh triangle "id:triangle" (its mesh's id and its
    // number in that mesh); sorted by id, then triangle (the object itself first).
    constexpr std::int64_t kWholeObject = -1;
    std::vector<std::pair<ObjectId, std::int64_t>> ids;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const LocateResult r = cursor.locate(points[i]);
        ids.clear();
        for (const std::uint32_t item : r.candidates) {
            if (isTriangleItem(item)) {
                const TriangleRef t = scene.triangle(item);
                ids.emplace_back(scene.object(t.objectSlot).id, t.triangle);
            } else {
                ids.emplace_back(scene.object(item).id, kWholeObject);
            }
        }
        std::sort(ids.begin(), ids.end());
        text += std::to_string(i);
        text += ',';
        for (std::size_t k = 0; k < ids.size(); ++k) {
            if (k > 0) {
                text += ' ';
            }
            text += std::to_string(ids[k].first);
            if (ids[k].second != kWholeObject) {
                text += ':';
                text += std::to_string(ids[k].second);
            }
        }
        text += '\n';
        out.afterRow();
    }
    out.finish();
}

nlohmann::json statsJson(const IndexStats& s) {
    nlohmann::json bins = nlohmann::json::array();
    for (const IndexStats::Bin& b : s.objectsPerLeaf) {
        bins.push_back(
            {{"min_objects", b.minObjects}, {"max_objects", b.maxObjects}, {"leaves", b.leaves}});
    }
    return {{"index", s.index},
            {"objects", s.objects},
            {"nodes", s.nodes},
            {"leaves", s.leaves},
            {"empty_leaves", s.emptyLeaves},
            {"depth", s.depth},
            {"leaves_at_minimum_size", s.leavesAtMinimumSize},
            {"object_cell_pairs", s.objectCellPairs},
            {"max_objects_per_leaf", s.maxObjectsPerLeaf},
            {"mean_objects_per_leaf", s.meanObjectsPerLeaf},
            {"objects_per_leaf", bins},
            {"bytes", s.bytes},
            {"bytes_per_object", s.bytesPerObject},
            {"build_seconds", s.buildSeconds},
            {"build_cpu_seconds", s.buildCpuSeconds}};
}

void printStats(const IndexStats& s, const std::string& source) {
    std::printf("scene:              %s\n", source.c_str());
    std::printf("index:              %s\n", s.index.c_str());
    std::printf("objects:            %u\n", s.objects);
    std::printf("build:              %.3f s wall, %.3f s CPU (all threads)\n", s.buildSeconds,
                s.buildCpuSeconds);
    std::printf("nodes:              %llu\n", static_cast<unsigned long long>(s.nodes));
    std::printf("leaves:             %llu (%llu empty, %llu at minimum size)\n",
                static_cast<unsigned long long>(s.leaves),
                static_cast<unsigned long long>(s.emptyLeaves),
                static_cast<unsigned long long>(s.leavesAtMinimumSize));
    std::printf("depth:              %u\n", s.depth);
    std::printf("object-cell pairs:  %llu (%.2f per object)\n",
                static_cast<unsigned long long>(s.objectCellPairs),
                s.objects == 0 ? 0.0 : static_cast<double>(s.objectCellPairs) / s.objects);
    std::printf("objects per leaf:   mean %.2f, max %u\n", s.meanObjectsPerLeaf,
                s.maxObjectsPerLeaf);
    for (const IndexStats::Bin& b : s.objectsPerLeaf) {
        if (b.leaves == 0) {
            continue;
        }
        char range[48];
        if (b.minObjects == b.maxObjects) {
            std::snprintf(range, sizeof range, "%u", b.minObjects);
        } else {
            std::snprintf(range, sizeof range, "%u-%u", b.minObjects, b.maxObjects);
        }
        std::printf("  %12s objects: %llu leaves\n", range,
                    static_cast<unsigned long long>(b.leaves));
    }
    std::printf("memory:             %llu bytes (%.1f per object)\n",
                static_cast<unsigned long long>(s.bytes), s.bytesPerObject);
}

} // namespace

void addIndexCommands(CLI::App& app) {
    // query
    {
        auto* cmd = app.add_subcommand(
            "query", "Build an index and list each point's candidate object ids as CSV "
                     "(point,candidates; a mesh triangle as ID:TRIANGLE)");
        auto scene = std::make_shared<std::string>();
        auto spec = std::make_shared<std::string>();
        auto points = std::make_shared<std::string>();
        auto out = std::make_shared<std::string>();
        cmd->add_option("--scene", *scene, "Scene file")->required();
        addIndexOption(cmd, *spec);
        cmd->add_option("--points", *points,
                        "CSV file, one point x,y,z (m) per line, optional header x,y,z")
            ->required();
        cmd->add_option("-o,--output", *out, "Output CSV file (default: standard output)");
        auto maxIndexMb = std::make_shared<std::uint64_t>(IndexSpec::kDefaultMaxMegabytes);
        addMaxIndexMbOption(cmd, *maxIndexMb);
        setExamples(cmd, {"hapto query --scene scene.json --points points.csv",
                          "hapto query --scene scene.json --index grid:5 --points points.csv -o "
                          "candidates.csv"});
        cmd->callback([=] { runQuery(*scene, *spec, *points, *out, *maxIndexMb); });
    }
    // index-stats
    {
        auto* cmd = app.add_subcommand(
            "index-stats", "Build an index over a scene and print its statistics (nodes, "
                           "leaves, depth, fill histogram, object-cell pairs, memory, build "
                           "time)");
        auto scene = std::make_shared<std::string>();
        auto spec = std::make_shared<std::string>();
        auto json = std::make_shared<bool>(false);
        cmd->add_option("--scene", *scene, "Scene file (default: the embedded default scene)");
        addIndexOption(cmd, *spec);
        cmd->add_flag("--json", *json, "Print the statistics as one JSON object");
        auto maxIndexMb = std::make_shared<std::uint64_t>(IndexSpec::kDefaultMaxMegabytes);
        addMaxIndexMbOption(cmd, *maxIndexMb);
        setExamples(cmd, {"hapto index-stats --scene scene.json",
                          "hapto index-stats --scene scene.json --index octree:5:0.002 --json"});
        cmd->callback([=] {
            if (!spec->empty()) {
                IndexSpec::parse(*spec); // a bad --index is refused before the scene is read
            }
            const Scene s = loadSceneOrDefault(*scene);
            const std::unique_ptr<SpatialIndex> index =
                buildIndex(s, sessionIndexSpec(*spec, s, *maxIndexMb));
            if (*json) {
                std::cout << statsJson(index->stats()).dump(2) << "\n";
            } else {
                printStats(index->stats(), scene->empty() ? "(embedded default scene)" : *scene);
            }
        });
    }
}

} // namespace hapto::cli
