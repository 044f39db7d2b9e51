// A `--view` session ends on time whatever its HTTP clients do, and finishes its report and
// recordings. [realtime]: a real process and real sockets (127.0.0.1 only); the test waits with
// a generous bound and asserts no counts of ticks or sleeps.

#include "TestSupport.h"

#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <future>
#include <thread>

using namespace hapto::test;

namespace {

sockaddr_in loopback(int port) {
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    return addr;
}

// A port free now on 127.0.0.1 (the kernel's pick, released for the session to take).
int freePort() {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr = loopback(0);
    REQUIRE(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
    socklen_t len = sizeof addr;
    getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
    close(fd);
    return ntohs(addr.sin_port);
}

// A connection to the session's view once it listens (-1 if it never does within the guard).
int connectWhenListening(int port) {
    int fd = -1;
    eventually(
        [&] {
            fd = socket(AF_INET, SOCK_STREAM, 0);
            sockaddr_in addr = loopback(port);
            if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
                return true;
            }
            close(fd);
            fd = -1;
            return false;
        },
        std::chrono::seconds(30));
    return fd;
}

} // namespace

TEST_CASE("a view session ends on time with a client dribbling its headers and one idle, its "
          "report and recordings finished",
          "[realtime]") {
    TempDir dir;
    const int port = freePort();
    const auto report = dir.path() / "report.json";
    const auto traces = dir.path() / "traces";
    const auto start = std::chrono::steady_clock::now();
    auto session = std::async(std::launch::async, [&] {
        // A hand the machine stalls past the watchdog is reopened after 20 ms, not 1 s: this
        // case is about the view's clients, not the fault rules.
        return runHapto("run --view --view-port " + std::to_string(port) +
                        " --duration 2 --reopen-ms 20 --record " + traces.string() + " --report " +
                        report.string());
    });
    const std::string host = "Host: 127.0.0.1:" + std::to_string(port) + "\r\n";
    const int idle = connectWhenListening(port); // keep-alive: answered, then nothing
    REQUIRE(idle >= 0);
    const std::string head = "HEAD /view.js HTTP/1.1\r\n" + host + "\r\n";
    CHECK(send(idle, head.data(), head.size(), MSG_NOSIGNAL) > 0);
    const int slow = connectWhenListening(port);
    REQUIRE(slow >= 0);
    const std::string partial = "GET / HTTP/1.1\r\n" + host + "X-Slow: ";
    CHECK(send(slow, partial.data(), partial.size(), MSG_NOSIGNAL) > 0);
    // A byte every 100 ms until the session has ended or a minute has passed; reconnect when
    // the server drops the head, so a client is always dribbling.
    std::atomic<bool> ended{false};
    std::thread dribble([&] {
        int fd = slow;
        for (int i = 0; i < 600 && !ended; ++i) {
            if (send(fd, "a", 1, MSG_NOSIGNAL) != 1) {
                close(fd);
                fd = socket(AF_INET, SOCK_STREAM, 0);
                sockaddr_in addr = loopback(port);
                if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
                    send(fd, partial.data(), partial.size(), MSG_NOSIGNAL);
                }
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
        close(fd);
    });
    const CommandResult r = session.get();
    const double tookS =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ended = true;
    dribble.join();
    close(idle);
    INFO(r.output);
    CHECK(r.exitCode == 0);
    CHECK(tookS < 30.0); // a hang guard: the dribbling client runs for a minute
    CHECK(std::filesystem::exists(report));
    CHECK(readFile(report).find("\"devices\"") != std::string::npos);
    CHECK(std::filesystem::exists(traces / "left.trace"));
    CHECK(std::filesystem::exists(traces / "right.trace"));
    for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
        CHECK(entry.path().filename().string().find(".tmp-") == std::string::npos);
    }
    for (const auto& entry : std::filesystem::directory_iterator(traces)) {
        CHECK(entry.path().filename().string().find(".tmp-") == std::string::npos);
    }
}
