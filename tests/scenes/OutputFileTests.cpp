// Output files written whole or not at all, output-path checks and same-file detection
// (hapto/io/OutputFile.h), in process.

#include "hapto/io/OutputFile.h"

#include "TestSupport.h"

#include "hapto/io/InputError.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>
#include <vector>

using namespace hapto;
using namespace hapto::test;
namespace fs = std::filesystem;

namespace {

/// While it lives, no file of this process grows past `bytes`: a write beyond fails with EFBIG
/// (SIGXFSZ ignored), as on a full disk.
struct FileSizeLimit {
    rlimit old{};
    void (*oldHandler)(int);
    explicit FileSizeLimit(rlim_t bytes) : oldHandler(std::signal(SIGXFSZ, SIG_IGN)) {
        REQUIRE(getrlimit(RLIMIT_FSIZE, &old) == 0);
        rlimit lower = old;
        lower.rlim_cur = bytes;
        REQUIRE(setrlimit(RLIMIT_FSIZE, &lower) == 0);
    }
    ~FileSizeLimit() {
        setrlimit(RLIMIT_FSIZE, &old);
        std::signal(SIGXFSZ, oldHandler);
    }
};

/// A Unix socket bound at `path`, for as long as it lives.
struct BoundSocket {
    int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    explicit BoundSocket(const fs::path& path) {
        sockaddr_un addr{};
        addr.sun_family = AF_UNIX;
        REQUIRE(path.string().size() < sizeof addr.sun_path);
        std::copy_n(path.c_str(), path.string().size(), addr.sun_path);
        REQUIRE(::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0);
    }
    ~BoundSocket() { ::close(fd); }
};

} // namespace

TEST_CASE("an output replaces its file only when committed, and leaves no temporary") {
    TempDir dir;
    writeFile(dir / "out.csv", "old\n");
    {
        AtomicOutputFile file(dir / "out.csv");
        file.stream() << "new contents\n";
        file.stream().flush();
        CHECK(readFile(dir / "out.csv") == "old\n");
        CHECK(namesIn(dir.path()).size() == 2); // the temporary, beside the target
        file.commit();
    }
    CHECK(readFile(dir / "out.csv") == "new contents\n");
    CHECK(namesIn(dir.path()) == std::vector<std::string>{"out.csv"});
}

TEST_CASE("rows of text pass 1 MiB in pieces and land whole, and only at finish") {
    TempDir dir;
    writeFile(dir / "rows.csv", "old\n");
    std::string want = "n\n";
    {
        TextOutput out(dir / "rows.csv");
        out.text() = "n\n";
        for (int i = 0; i < 200000; ++i) { // about 1.3 MB: written out at least once before finish
            const std::string row = std::to_string(i) + ",abc\n";
            out.text() += row;
            want += row;
            out.afterRow();
            CHECK(out.text().size() <= (std::size_t{1} << 20) + row.size());
        }
        CHECK(readFile(dir / "rows.csv") == "old\n");
        out.finish();
    }
    CHECK(readFile(dir / "rows.csv") == want);
    CHECK(namesIn(dir.path()) == std::vector<std::string>{"rows.csv"});
    // A write that fails is an error naming the file, not a silent short file; the old file
    // stays and no temporary is left.
    {
        TextOutput full(dir / "rows.csv");
        full.text() = std::string(64 * 1024, 'x');
        const FileSizeLimit limit(4096); // as if the disk filled up after 4 KiB
        CHECK_THROWS_WITH(full.finish(), Catch::Contains("rows.csv"));
    }
    CHECK(readFile(dir / "rows.csv") == want);
    CHECK(namesIn(dir.path()) == std::vector<std::string>{"rows.csv"});
}

TEST_CASE("an output abandoned before commit leaves the old file and no temporary") {
    TempDir dir;
    writeFile(dir / "out.csv", "old\n");
    {
        AtomicOutputFile file(dir / "out.csv");
        file.stream() << std::string(1 << 20, 'x'); // more than the buffer: bytes reach the disk
    }
    CHECK(readFile(dir / "out.csv") == "old\n");
    CHECK(namesIn(dir.path()) == std::vector<std::string>{"out.csv"});
    {
        AtomicOutputFile file(dir / "new.csv");
        file.stream() << "never committed";
    }
    CHECK(namesIn(dir.path()) == std::vector<std::string>{"out.csv"});
}

TEST_CASE("writing through a symlink replaces the file it names and keeps the link") {
    TempDir dir;
    writeFile(dir / "real.json", "old");
    fs::create_symlink("real.json", dir / "link.json");
    writeFileAtomically(dir / "link.json", "new");
    CHECK(fs::is_symlink(fs::symlink_status(dir / "link.json")));
    CHECK(readFile(dir / "real.json") == "new");
    CHECK(namesIn(dir.path()) == std::vector<std::string>{"link.json", "real.json"});
}

TEST_CASE("a replaced file keeps its permissions") {
    TempDir dir;
    writeFile(dir / "out.txt", "old");
    fs::permissions(dir / "out.txt",
                    fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
    writeFileAtomically(dir / "out.txt", "new");
    CHECK(fs::status(dir / "out.txt").permissions() ==
          (fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read));
}

TEST_CASE("a FIFO, a socket or a device is refused as an output, never opened or replaced") {
    TempDir dir;
    REQUIRE(::mkfifo((dir / "ff").c_str(), 0600) == 0);
    // A reader holds the FIFO open, so a write that opened it would not block but succeed.
    const int reader = ::open((dir / "ff").c_str(), O_RDONLY | O_NONBLOCK);
    REQUIRE(reader >= 0);
    CHECK_THROWS_WITH(checkOutputFile(dir / "ff", "-o"),
                      Catch::Contains("-o") && Catch::Contains("ff") && Catch::Contains("a FIFO"));
    CHECK_THROWS_WITH(writeFileAtomically(dir / "ff", "x"), Catch::Contains("a FIFO"));
    CHECK_THROWS_AS(TextOutput(dir / "ff"), InputError);
    char byte = 0;
    CHECK(::read(reader, &byte, 1) == 0); // nothing was written into it
    ::close(reader);
    fs::create_symlink("ff", dir / "link");
    CHECK_THROWS_WITH(checkOutputFile(dir / "link", "--report"),
                      Catch::Contains("--report") && Catch::Contains("a FIFO"));

    const BoundSocket socket(dir / "sock");
    CHECK_THROWS_WITH(checkOutputFile(dir / "sock", "--json"),
                      Catch::Contains("--json") && Catch::Contains("a socket"));
    CHECK_THROWS_AS(AtomicOutputFile(dir / "sock"), InputError);

    CHECK_THROWS_WITH(checkOutputFile("/dev/null", "-o"),
                      Catch::Contains("/dev/null") && Catch::Contains("a character device"));
    CHECK_THROWS_AS(writeFileAtomically("/dev/null", "into the void\n"), InputError);
    struct stat st {};
    REQUIRE(::stat("/dev/null", &st) == 0);
    CHECK(S_ISCHR(st.st_mode)); // not replaced
    CHECK(fs::is_fifo(dir / "ff"));
    CHECK(fs::is_socket(dir / "sock"));
    CHECK(namesIn(dir.path()) == std::vector<std::string>{"ff", "link", "sock"});

    // checkOutputKind refuses by kind only: a missing file, even in a missing folder, passes.
    CHECK_THROWS_WITH(checkOutputKind(dir / "ff", "--record (device 'left')"),
                      Catch::Contains("--record (device 'left')") && Catch::Contains("a FIFO"));
    CHECK_THROWS_WITH(checkOutputKind(dir.path(), "-o"), Catch::Contains("folder"));
    CHECK_NOTHROW(checkOutputKind(dir / "missing" / "left.trace", "--record"));
    writeFile(dir / "plain", "x");
    CHECK_NOTHROW(checkOutputKind(dir / "plain", "-o"));
}

TEST_CASE("outputs that cannot be written are refused, naming the option and the path") {
    TempDir dir;
    fs::create_directory(dir / "sub");
    CHECK_THROWS_WITH(checkOutputFile(dir / "sub", "--report"),
                      Catch::Contains("--report") && Catch::Contains("folder"));
    CHECK_THROWS_WITH(checkOutputFile(dir / "missing" / "r.json", "-o"),
                      Catch::Contains("-o") && Catch::Contains("missing") &&
                          Catch::Contains("does not exist"));
    CHECK_THROWS_AS(AtomicOutputFile(dir / "sub"), InputError);
    CHECK_THROWS_AS(AtomicOutputFile(dir / "missing" / "r.json"), InputError);
    CHECK_NOTHROW(checkOutputFile(dir / "fine.json", "-o"));

    writeFile(dir / "file", "x");
    CHECK_THROWS_WITH(checkOutputFolder(dir / "file", "--record"),
                      Catch::Contains("--record") && Catch::Contains("not a folder"));
    CHECK_THROWS_AS(checkOutputFolder(dir / "file" / "deeper", "--record"), InputError);
    CHECK_NOTHROW(checkOutputFolder(dir / "sub", "--record"));
    CHECK_NOTHROW(checkOutputFolder(dir / "new" / "deeper", "--record"));
    CHECK(namesIn(dir.path()) == std::vector<std::string>{"file", "sub"}); // nothing created
}

TEST_CASE("the same file is recognised through other spellings, symlinks and hard links") {
    TempDir dir;
    writeFile(dir / "a.json", "a");
    writeFile(dir / "b.json", "b");
    fs::create_symlink(dir / "a.json", dir / "sym.json");
    fs::create_hard_link(dir / "a.json", dir / "hard.json");
    fs::create_directory(dir / "sub");
    CHECK(sameFile(dir / "a.json", dir / "sub" / ".." / "a.json"));
    CHECK(sameFile(dir / "a.json", dir / "sym.json"));
    CHECK(sameFile(dir / "hard.json", dir / "a.json"));
    CHECK_FALSE(sameFile(dir / "a.json", dir / "b.json"));
    CHECK(sameFile(dir / "new.json", dir / "sub" / ".." / "new.json")); // neither exists yet
    CHECK_FALSE(sameFile(dir / "new.json", dir / "other.json"));
    CHECK_FALSE(sameFile("", dir / "a.json"));
    CHECK_THROWS_WITH(refuseSameFile(dir / "sym.json", "-o", dir / "a.json", "--scene"),
                      Catch::Contains("-o") && Catch::Contains("--scene") &&
                          Catch::Contains("sym.json"));
    CHECK_NOTHROW(refuseSameFile(dir / "b.json", "-o", dir / "a.json", "--scene"));
}
