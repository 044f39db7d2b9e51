#pragma once
/// Helpers shared by the tests: temporary files and running the `hapto` command.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <ranges>
#include <sstream>
#include <stdexcept>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <vector>

namespace hapto::test {

/// Polls `pred` every millisecond until it holds or the hang guard expires (a guard against a
/// hang, not a timing requirement); returns whether it held. For tests whose subject runs on
/// threads of its own (a device's I/O thread, an emulator, a servo thread).
template <class P>
bool eventually(P&& pred, std::chrono::milliseconds guard = std::chrono::seconds(10)) {
    const auto end = std::chrono::steady_clock::now() + guard;
    while (std::chrono::steady_clock::now() < end) {
        if (pred()) {
            return true;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return pred();
}

/// A fresh directory under the system temp dir, removed when the object dies.
class TempDir {
public:
    TempDir() {
        std::random_device rd;
        mPath = std::filesystem::temp_directory_path() /
                ("hapto-test-" + std::to_string(rd()) + std::to_string(rd()));
        std::filesystem::create_directories(mPath);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(mPath, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return mPath; }
    std::filesystem::path operator/(const std::string& name) const { return mPath / name; }

private:
    std::filesystem::path mPath;
};

/// Writes text to a file.
inline void writeFile(const std::filesystem::path& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
}

/// Reads a whole file.
inline std::string readFile(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

/// The result of running a command.
struct CommandResult {
    int exitCode = -1;
    std::string output; ///< stdout and stderr, interleaved.
};

/// Runs `hapto ARGS` (a shell fragment) from the build tree, capturing its output.
inline CommandResult runHapto(const std::string& args) {
    const std::string cmd = std::string(HAPTO_BINARY_DIR) + "/tools/hapto " + args + " 2>&1";
    CommandResult r;
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) {
        return r;
    }
    char buf[4096];
    std::size_t n;
    while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) {
        r.output.append(buf, n);
    }
    const int status = pclose(pipe);
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

/// The lines of `text` (without their line ends).
inline std::vector<std::string> linesOf(const std::string& text) {
    std::vector<std::string> lines;
    std::size_t start = 0;
    while (start < text.size()) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        lines.push_back(text.substr(start, end - start));
        start = end + 1;
    }
    return lines;
}

/// The names in a folder, sorted.
inline std::vector<std::string> namesIn(const std::filesystem::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
        names.push_back(e.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
}

/// The files named PWNED* anywhere under `root`: made by a hostile name run as a command.
inline std::vector<std::string> pwned(const std::filesystem::path& root) {
    std::vector<std::string> out;
    for (const auto& e : std::filesystem::recursive_directory_iterator(root)) {
        if (e.path().filename().string().rfind("PWNED", 0) == 0) {
            out.push_back(e.path().string());
        }
    }
    return out;
}

/// Runs the enclosing scope in `dir`, so a relative command in a name (run by hapto, started
/// from here) would act there.
class InFolder {
public:
    explicit InFolder(const std::filesystem::path& dir) : mOld(std::filesystem::current_path()) {
        std::filesystem::current_path(dir);
    }
    ~InFolder() { std::filesystem::current_path(mOld); }
    InFolder(const InFolder&) = delete;
    InFolder& operator=(const InFolder&) = delete;

private:
    std::filesystem::path mOld;
};

/// The n-th (from 0) ```json block after the heading `section` in a user-guide page
/// (docs/guide/<page>), so a test loads exactly what the guide shows.
inline std::string guideJsonBlock(const std::string& page, const std::string& section, int n) {
    const std::string text =
        readFile(std::filesystem::path(HAPTO_SOURCE_DIR) / "docs" / "guide" / page);
    std::size_t at = text.find(section);
    for (int i = 0; i <= n && at != std::string::npos; ++i) {
        at = text.find("```json\n", at);
        at = at == std::string::npos ? at : at + 8;
    }
    if (at == std::string::npos) {
        throw std::runtime_error("docs/guide/" + page + ": no json block " + std::to_string(n) +
                                 " after '" + section + "'");
    }
    return text.substr(at, text.find("```", at) - at);
}

/// A device file of one valid simulated device with `extra` spliced into its object.
inline std::string deviceFileWith(const std::string& extra) {
    return R"({"format": "hapto-devices", "version": 1, "devices": [{"name": "a", "kind": "sim")" +
           (extra.empty() ? "" : ", " + extra) + "}]}";
}

/// FNV-1a over 64-bit words, fed field by field: pins a structure to the hash an earlier
/// version of the code gave.
struct Fnv {
    std::uint64_t h = 1469598103934665603ull; ///< The hash so far.
    void add(std::uint64_t v) {
        for (int i = 0; i < 8; ++i) {
            h = (h ^ ((v >> (8 * i)) & 0xFF)) * 1099511628211ull;
        }
    }
    void add(double v) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, &v, sizeof bits);
        add(bits);
    }
    /// A vector's x, y and z.
    template <class V>
    requires requires(const V& v) { v.x + v.y + v.z; }
    void add(const V& v) {
        add(double(v.x));
        add(double(v.y));
        add(double(v.z));
    }
    /// A range of integers: its size, then each.
    template <std::ranges::sized_range R> void add(const R& values) {
        add(std::uint64_t(std::ranges::size(values)));
        for (const auto v : values) {
            add(std::uint64_t(v));
        }
    }
};

} // namespace hapto::test
