#include "hapto/index/IndexSpec.h"

#include "hapto/io/InputError.h"

#include <charconv>
#include <cmath>
#include <string>
#include <system_error>
#include <vector>

namespace hapto {
namespace {

const char* const kForms = "use brute, grid:N (e.g. grid:5) or octree:M:MIN (e.g. "
                           "octree:2:0.005, MIN in metres), each optionally followed by :aabb";

[[noreturn]] void fail(std::string_view text, const std::string& what) {
    throw InputError("index spec '" + std::string(text) + "': " + what);
}

std::vector<std::string_view> split(std::string_view text) {
    std::vector<std::string_view> parts;
    std::size_t start = 0;
    for (;;) {
        const std::size_t colon = text.find(':', start);
        parts.push_back(text.substr(start, colon - start));
        if (colon == std::string_view::npos) {
            return parts;
        }
        start = colon + 1;
    }
}

bool parseInt(std::string_view s, int& out) {
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && ptr == s.data() + s.size() && !s.empty();
}

bool parseDouble(std::string_view s, double& out) {
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return ec == std::errc() && ptr == s.data() + s.size() && !s.empty();
}

} // namespace

IndexSpec IndexSpec::brute() {
    return {};
}

IndexSpec IndexSpec::grid(int cells, OverlapMode mode) {
    IndexSpec s;
    s.kind = Kind::Grid;
    s.gridCells = cells;
    s.mode = mode;
    return s;
}

IndexSpec IndexSpec::octree(int maxObjects, double minLeafSize, OverlapMode mode) {
    IndexSpec s;
    s.kind = Kind::Octree;
    s.maxObjects = maxObjects;
    s.minLeafSize = minLeafSize;
    s.mode = mode;
    return s;
}

IndexSpec IndexSpec::parse(std::string_view text) {
    std::vector<std::string_view> parts = split(text);
    OverlapMode mode = OverlapMode::Obb;
    if (parts.size() > 1 && (parts.back() == "aabb" || parts.back() == "obb")) {
        mode = parts.back() == "aabb" ? OverlapMode::Aabb : OverlapMode::Obb;
        parts.pop_back();
    }
    const std::string_view kind = parts.front();
    if (kind == "brute" && parts.size() == 1) {
        IndexSpec s = brute();
        s.mode = mode;
        return s;
    }
    if (kind == "grid" && parts.size() == 2) {
        int n = 0;
        if (!parseInt(parts[1], n) || n < 1 || n > kMaxGridCells) {
            fail(text, "grid:N needs N, the cells per side, a whole number from 1 to " +
                           std::to_string(kMaxGridCells) + " (as in grid:5); got '" +
                           std::string(parts[1]) + "'");
        }
        return grid(n, mode);
    }
    if (kind == "octree" && parts.size() == 3) {
        int m = 0;
        double minSize = 0.0;
        if (!parseInt(parts[1], m) || m < 1 || m > kMaxLeafObjects) {
            fail(text, "octree:M:MIN needs M, the most objects a leaf holds, a whole number "
                       "from 1 to " +
                           std::to_string(kMaxLeafObjects) +
                           " (as in octree:2:0.005); "
                           "got '" +
                           std::string(parts[1]) + "'");
        }
        if (!parseDouble(parts[2], minSize) || !std::isfinite(minSize) || !(minSize > 0.0)) {
            fail(text, "octree:M:MIN needs MIN, the minimum leaf edge in metres, a number > 0 "
                       "(as in octree:2:0.005 for 5 mm); got '" +
                           std::string(parts[2]) + "'");
        }
        return octree(m, minSize, mode);
    }
    if (kind == "brute" || kind == "grid" || kind == "octree") {
        fail(text, "wrong number of ':' fields; " + std::string(kForms));
    }
    fail(text, "unknown index; " + std::string(kForms));
}

std::string IndexSpec::toString() const {
    std::string s;
    switch (kind) {
    case Kind::BruteForce:
        s = "brute";
        break;
    case Kind::Grid:
        s = "grid:" + std::to_string(gridCells);
        break;
    case Kind::Octree: {
        char buf[64];
        // Shortest text that reads back as the same double, in plain notation when sensible.
        const auto res =
            minLeafSize >= 1e-6 && minLeafSize < 1e6
                ? std::to_chars(buf, buf + sizeof buf, minLeafSize, std::chars_format::fixed)
                : std::to_chars(buf, buf + sizeof buf, minLeafSize);
        s = "octree:" + std::to_string(maxObjects) + ":" + std::string(buf, res.ptr);
        break;
    }
    }
    if (mode == OverlapMode::Aabb) {
        s += ":aabb";
    }
    return s;
}

} // namespace hapto
