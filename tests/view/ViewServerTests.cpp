// The view's web server: its assets and nothing else, read-only, one origin, a client limit,
// and a stalled viewer that costs the publisher nothing.

#include "hapto/view/ViewServer.h"

#include "TestSupport.h"

#include <catch2/catch.hpp>
#include <httplib.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <sstream>
#include <thread>

using namespace hapto;

namespace {

// A raw HTTP/1.1 exchange, byte for byte as written (no client normalising the path).
class RawConnection {
public:
    // To 127.0.0.1, or to ::1 when `v6`.
    explicit RawConnection(int port, bool v6 = false) {
        mFd = socket(v6 ? AF_INET6 : AF_INET, SOCK_STREAM, 0);
        sockaddr_in addr{};
        addr.sin_family = AF_INET;
        addr.sin_port = htons(static_cast<std::uint16_t>(port));
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        sockaddr_in6 addr6{};
        addr6.sin6_family = AF_INET6;
        addr6.sin6_port = htons(static_cast<std::uint16_t>(port));
        addr6.sin6_addr = in6addr_loopback;
        REQUIRE(
            connect(mFd,
                    v6 ? reinterpret_cast<sockaddr*>(&addr6) : reinterpret_cast<sockaddr*>(&addr),
                    v6 ? sizeof addr6 : sizeof addr) == 0);
        timeval tv{5, 0};
        setsockopt(mFd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        setsockopt(mFd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    }
    int fd() const { return mFd; }
    // Sends what it can of `text`; false once the connection refuses more.
    bool trySend(const std::string& text) {
        return ::send(mFd, text.data(), text.size(), MSG_NOSIGNAL) ==
               static_cast<ssize_t>(text.size());
    }
    ~RawConnection() { close(); }
    void close() {
        if (mFd >= 0) {
            ::close(mFd);
            mFd = -1;
        }
    }
    void send(const std::string& text) {
        REQUIRE(::send(mFd, text.data(), text.size(), MSG_NOSIGNAL) ==
                static_cast<ssize_t>(text.size()));
    }
    // Reads until `marker` has arrived (or the connection ends or times out).
    std::string readUntil(const std::string& marker) {
        std::string got;
        char buffer[4096];
        while (got.find(marker) == std::string::npos) {
            const ssize_t n = recv(mFd, buffer, sizeof buffer, 0);
            if (n <= 0) {
                break;
            }
            got.append(buffer, static_cast<std::size_t>(n));
        }
        return got;
    }

private:
    int mFd = -1;
};

int statusOf(const std::string& response) {
    // "HTTP/1.1 404 Not Found"
    return response.size() > 12 ? std::stoi(response.substr(9, 3)) : 0;
}

std::string request(const std::string& method, const std::string& path, int port,
                    const std::string& extraHeaders = "") {
    RawConnection c(port);
    c.send(method + " " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n" +
           extraHeaders + "Content-Length: 0\r\nConnection: close\r\n\r\n");
    return c.readUntil("\r\n\r\n\x01never"); // to the end
}

// A GET naming `host` in its Host header, over IPv4 or IPv6 loopback; the whole response.
std::string requestAs(const std::string& host, const std::string& path, int port, bool v6,
                      const std::string& extraHeaders = "") {
    RawConnection c(port, v6);
    c.send("GET " + path + " HTTP/1.1\r\nHost: " + host + "\r\n" + extraHeaders +
           "Connection: close\r\n\r\n");
    return c.readUntil("\r\n\r\n\x01never");
}

// This process's resident memory, bytes.
std::size_t residentBytes() {
    std::ifstream statm("/proc/self/statm");
    std::size_t pages = 0, resident = 0;
    statm >> pages >> resident;
    return resident * static_cast<std::size_t>(sysconf(_SC_PAGESIZE));
}

std::string fileText(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

} // namespace

TEST_CASE("the view serves its page, its script, three.js and its documents", "[threads]") {
    ViewServer server;
    server.setDocument("/scene.json", R"({"objects":[]})");
    const int port = server.start();
    REQUIRE(port > 0);
    CHECK(server.url() == "http://127.0.0.1:" + std::to_string(port) + "/");
    httplib::Client client("127.0.0.1", port);

    auto page = client.Get("/");
    REQUIRE(page);
    CHECK(page->status == 200);
    CHECK(page->get_header_value("Content-Type").find("text/html") == 0);
    CHECK(page->body.find("/three/three.min.js") != std::string::npos);
    CHECK(page->body.find("/view.js") != std::string::npos);
    auto script = client.Get("/view.js");
    REQUIRE(script);
    CHECK(script->body.find("EventSource('/stream')") != std::string::npos);
    auto three = client.Get("/three/three.min.js");
    REQUIRE(three);
    CHECK(three->body == fileText(std::string(kDefaultThreeJsDir) + "/build/three.min.js"));
    auto orbit = client.Get("/three/OrbitControls.js");
    REQUIRE(orbit);
    CHECK(orbit->body.find("OrbitControls") != std::string::npos);
    auto scene = client.Get("/scene.json");
    REQUIRE(scene);
    CHECK(scene->body == R"({"objects":[]})");
    CHECK(scene->get_header_value("Content-Type") == "application/json");
    auto missing = client.Get("/trace.json");
    REQUIRE(missing);
    CHECK(missing->status == 404);
}

TEST_CASE("the view refuses path traversal and serves no file it does not list", "[threads]") {
    ViewServer server;
    const int port = server.start();
    const std::string passwd = fileText("/etc/passwd");
    for (const std::string path :
         {"/../../../../etc/passwd", "/three/../../../../../etc/passwd",
          "/%2e%2e/%2e%2e/%2e%2e/etc/passwd", "/three/..%2f..%2f..%2fetc%2fpasswd",
          "/three/three.js", "/three/../view.js/../../../etc/passwd", "//etc/passwd",
          "/three/build/three.min.js", "/usr/share/javascript/three/build/three.min.js"}) {
        INFO(path);
        const std::string response = request("GET", path, port);
        const int status = statusOf(response);
        CHECK((status == 404 || status == 400));
        CHECK(response.find("root:") == std::string::npos);
    }
    // The same connection code does reach a listed asset.
    CHECK(statusOf(request("GET", "/view.js", port)) == 200);
}

TEST_CASE("the view is read-only: only GET and HEAD are answered", "[threads]") {
    ViewServer server;
    server.setDocument("/scene.json", R"({"objects":[1]})");
    const int port = server.start();
    for (const std::string method : {"POST", "PUT", "DELETE", "PATCH", "OPTIONS"}) {
        for (const std::string path : {"/", "/scene.json", "/stream", "/view.js"}) {
            INFO(method << " " << path);
            const std::string response = request(method, path, port);
            CHECK(statusOf(response) == 405);
            CHECK(response.find("Allow: GET, HEAD") != std::string::npos);
        }
    }
    httplib::Client client("127.0.0.1", port);
    auto scene = client.Get("/scene.json");
    REQUIRE(scene);
    CHECK(scene->body == R"({"objects":[1]})");
    CHECK(statusOf(request("HEAD", "/scene.json", port)) == 200);
}

TEST_CASE("a stream from another origin, or a loopback view under another host name, is refused",
          "[threads]") {
    ViewServer server;
    const int port = server.start();
    server.publish(R"({"t":1})");
    const std::string self = "127.0.0.1:" + std::to_string(port);

    CHECK(statusOf(request("GET", "/stream", port, "Origin: http://evil.example\r\n")) == 403);
    CHECK(statusOf(request("GET", "/stream", port, "Origin: http://localhost:1\r\n")) == 403);
    CHECK(server.streamClients() == 0);
    {
        RawConnection c(port); // DNS rebinding: a name that resolved to us
        c.send("GET / HTTP/1.1\r\nHost: evil.example:" + std::to_string(port) +
               "\r\nConnection: close\r\n\r\n");
        CHECK(statusOf(c.readUntil("\r\n\r\n")) == 403);
    }
    // The page's own stream: same origin, gets the newest frame.
    RawConnection c(port);
    c.send("GET /stream HTTP/1.1\r\nHost: " + self + "\r\nOrigin: http://" + self + "\r\n\r\n");
    const std::string got = c.readUntil("\n\n");
    CHECK(statusOf(got) == 200);
    CHECK(got.find("text/event-stream") != std::string::npos);
    CHECK(got.find(R"(data: {"t":1})") != std::string::npos);
}

TEST_CASE("the view serves at most its limit of streams, a closed one frees its place",
          "[threads]") {
    ViewServerOptions options;
    options.maxStreamClients = 2;
    ViewServer server(options);
    const int port = server.start();
    server.publish(R"({"t":0})");
    const std::string get =
        "GET /stream HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n";
    RawConnection a(port), b(port);
    a.send(get);
    b.send(get);
    CHECK(statusOf(a.readUntil("\n\n")) == 200);
    CHECK(statusOf(b.readUntil("\n\n")) == 200);
    CHECK(server.streamClients() == 2);
    {
        RawConnection c(port);
        c.send(get);
        const std::string refused = c.readUntil("\r\n\r\n");
        CHECK(statusOf(refused) == 503);
    }
    CHECK(server.streamClients() == 2);
    // The page still loads while the streams are full.
    CHECK(statusOf(request("GET", "/", port)) == 200);
    a.close();
    // The server notices at its next write (a frame, or the idle comment).
    server.publish(R"({"t":1})");
    CHECK(test::eventually([&] {
        server.publish(R"({"t":2})");
        return server.streamClients() == 1;
    }));
    RawConnection d(port);
    d.send(get);
    CHECK(statusOf(d.readUntil("\n\n")) == 200);
}

TEST_CASE("a viewer that stalls costs the publisher nothing and is dropped", "[realtime]") {
    ViewServerOptions options;
    options.writeTimeout = std::chrono::milliseconds(200);
    ViewServer server(options);
    const int port = server.start();
    RawConnection stalled(port);
    stalled.send("GET /stream HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n");
    REQUIRE(test::eventually([&] { return server.streamClients() == 1; }));
    // Frames far larger than the socket buffers: the stalled viewer reads none of them.
    const std::string big = "{\"pad\":\"" + std::string(256 * 1024, 'x') + "\"}";
    std::atomic<int> published{0};
    std::thread publisher([&] {
        for (int i = 0; i < 200; ++i) {
            server.publish(big);
            published.fetch_add(1);
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
    });
    // Every publish returns (a hang guard, not a timing), and the stalled stream is dropped.
    CHECK(test::eventually([&] { return published.load() == 200; }, std::chrono::seconds(30)));
    publisher.join();
    CHECK(server.framesPublished() == 200);
    CHECK(test::eventually([&] { return server.streamClients() == 0; }));
}

TEST_CASE("loopback addresses, and a missing three.js named with its package") {
    CHECK(isLoopbackAddress("127.0.0.1"));
    CHECK(isLoopbackAddress("127.1.2.3"));
    CHECK(isLoopbackAddress("::1"));
    CHECK(isLoopbackAddress("localhost"));
    CHECK_FALSE(isLoopbackAddress("0.0.0.0"));
    CHECK_FALSE(isLoopbackAddress("192.0.2.1"));
    CHECK_FALSE(isLoopbackAddress("evil.example"));
    ViewServerOptions options;
    options.threeJsDir = "/nonexistent/three";
    CHECK_THROWS_WITH(ViewServer(options),
                      Catch::Contains("/nonexistent/three/build/three.min.js") &&
                          Catch::Contains("libjs-three"));
}

TEST_CASE("a port in use is refused with the address named", "[threads]") {
    ViewServer first;
    const int port = first.start();
    ViewServerOptions options;
    options.port = port;
    ViewServer second(options);
    CHECK_THROWS_WITH(second.start(), Catch::Contains("127.0.0.1:" + std::to_string(port)));
}

TEST_CASE("a stop never waits for a client: one dribbling its headers, one idle between requests",
          "[realtime]") {
    ViewServerOptions options;
    options.requestTimeout = std::chrono::seconds(120); // only the stop can end the slow head
    ViewServer server(options);
    const int port = server.start();
    RawConnection idle(port); // keep-alive: a request answered, then nothing
    idle.send("HEAD /view.js HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n");
    CHECK(statusOf(idle.readUntil("\r\n\r\n")) == 200);
    RawConnection slow(port);
    slow.send("GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nX-Slow: ");
    std::atomic<bool> refused{false};
    std::thread dribble([&] {
        for (int i = 0; i < 600 && !refused; ++i) { // a byte each 100 ms, a minute at most
            refused = !slow.trySend("a");
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const auto before = std::chrono::steady_clock::now();
    server.stop();
    const auto stopS =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
    // A hang guard, far from both the slow client's minute and the keep-alive's 5 s.
    CHECK(stopS < 4.0);
    CHECK(idle.readUntil("\x01never").empty()); // closed by the server
    CHECK(test::eventually([&] { return refused.load(); }));
    refused = true;
    dribble.join();
}

TEST_CASE("a request head must arrive whole within the request timeout", "[realtime]") {
    ViewServerOptions options;
    options.requestTimeout = std::chrono::milliseconds(500);
    ViewServer server(options);
    const int port = server.start();
    RawConnection slow(port);
    slow.send("GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nX-Slow: ");
    std::atomic<bool> refused{false};
    std::thread dribble([&] {
        for (int i = 0; i < 600 && !refused; ++i) { // a byte each 100 ms, a minute at most
            refused = !slow.trySend("a");
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    });
    // Each byte came within the old per-read timeout; the head as a whole did not.
    CHECK(statusOf(slow.readUntil("\r\n\r\n")) == 408);
    CHECK(test::eventually([&] { return refused.load(); }, std::chrono::seconds(20)));
    refused = true;
    dribble.join();
    // An idle keep-alive connection is closed after the same time.
    RawConnection idle(port);
    idle.send("GET /view.js HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n");
    CHECK(statusOf(idle.readUntil("\r\n\r\n")) == 200);
    idle.readUntil("\x01never"); // to the end of the connection (or the 5 s receive guard)
    char byte = 0;
    CHECK(recv(idle.fd(), &byte, 1, 0) == 0);
    // The server still answers.
    CHECK(statusOf(request("GET", "/view.js", port)) == 200);
}

TEST_CASE(
    "a header flood is refused with 431 and not read further, and long lines keep 414 and 400",
    "[threads]") {
    ViewServer server;
    const int port = server.start();
    const std::string start = "GET / HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n";
    std::string headers;
    for (int i = 0; i < 60; ++i) {
        headers += "X-" + std::to_string(i) + ": b\r\n";
    }
    {
        RawConnection c(port); // 60 headers: served
        c.send(start + headers + "Connection: close\r\n\r\n");
        CHECK(statusOf(c.readUntil("\r\n\r\n")) == 200);
    }
    {
        RawConnection c(port); // 120 small headers, 1.3 KB: too many
        c.send(start + headers + headers + "\r\n");
        CHECK(statusOf(c.readUntil("\r\n\r\n")) == 431);
    }
    {
        RawConnection c(port); // 40 KB in few lines: too large
        c.send(start + "X-A: " + std::string(8000, 'a') + "\r\nX-B: " + std::string(8000, 'b') +
               "\r\nX-C: " + std::string(8000, 'c') + "\r\n\r\n");
        CHECK(statusOf(c.readUntil("\r\n\r\n")) == 431);
    }
    CHECK(statusOf(request("GET", "/" + std::string(9000, 'a'), port)) == 414);
    CHECK(statusOf(request("GET", "/" + std::string(40000, 'a'), port)) == 414);
    CHECK(statusOf(request("GET", "/", port, "X-Long: " + std::string(9000, 'x') + "\r\n")) == 400);

    // A flood of 64 MB of small headers: the server stops reading after its cap, so the
    // sender is refused long before the end, and this process's memory stays flat.
    const std::size_t residentBefore = residentBytes();
    RawConnection flood(port);
    flood.send(start);
    std::string chunk;
    while (chunk.size() < 64 * 1024) {
        chunk += "X-Flood: a\r\n";
    }
    std::size_t sent = 0;
    while (sent < 64u * 1024 * 1024 && flood.trySend(chunk)) {
        sent += chunk.size();
    }
    CHECK(sent < 64u * 1024 * 1024);
    CHECK(statusOf(flood.readUntil("\r\n\r\n")) == 431);
    CHECK(residentBytes() < residentBefore + 32u * 1024 * 1024);
    CHECK(statusOf(request("GET", "/view.js", port)) == 200);
}

TEST_CASE("paths match exactly, and several ranges in one request are refused", "[threads]") {
    ViewServerOptions options;
    options.liveStream = false;
    ViewServer server(options);
    server.setDocument("/scene.json", R"({"objects":[]})");
    const int port = server.start();
    for (const std::string path : {"/viewXjs", "/sceneXjson", "/index_html", "/three/threeXminXjs",
                                   "/three/OrbitControlsXjs", "/view.jsX", "/scene.json/"}) {
        INFO(path);
        CHECK(statusOf(request("GET", path, port)) == 404);
    }
    CHECK(statusOf(request("GET", "/view.js", port)) == 200);
    CHECK(statusOf(request("GET", "/scene.json", port)) == 200);
    // A recording has no live stream: nothing to hold a viewer's place.
    CHECK(statusOf(request("GET", "/stream", port)) == 404);

    const std::string one = request("GET", "/view.js", port, "Range: bytes=0-9\r\n");
    CHECK(statusOf(one) == 206);
    std::string many = "Range: bytes=0-";
    for (int i = 0; i < 500; ++i) {
        many += ",0-";
    }
    const std::string refused = request("GET", "/three/three.min.js", port, many + "\r\n");
    CHECK(statusOf(refused) == 416);
    CHECK(refused.size() < 1024);
    CHECK(statusOf(request("GET", "/view.js", port, "Range: bytes=0-0,1-1\r\n")) == 416);
}

TEST_CASE("the Host check holds for every binding, addresses compared parsed") {
    // Loopback, in every spelling.
    for (const std::string bind :
         {"127.0.0.1", "::1", "0:0:0:0:0:0:0:1", "::ffff:127.0.0.1", "0000::0001", "localhost"}) {
        INFO(bind);
        CHECK(isLoopbackAddress(bind));
        CHECK(hostHeaderAllowed(bind, "127.0.0.1:8340"));
        CHECK(hostHeaderAllowed(bind, "localhost:8340"));
        CHECK(hostHeaderAllowed(bind, "LocalHost"));
        CHECK(hostHeaderAllowed(bind, "[::1]:8340"));
        CHECK(hostHeaderAllowed(bind, "[0:0:0:0:0:0:0:1]"));
        CHECK(hostHeaderAllowed(bind, "[::ffff:127.0.0.1]:1"));
        for (const std::string host :
             {"evil.com:8340", "evil.com", "127.0.0.1:80@evil.com", "[::1]evil.com",
              "[::1]:80@evil.com", "127.0.0.1.evil.com", "localhost.evil.com:1", "",
              "127.0.0.1:", "127.0.0.1:1234567", "[evil.com]:1", "[::1", "::1",
              "127.0.0.1 evil.com", "user@127.0.0.1", "192.0.2.1:8340"}) {
            INFO(host);
            CHECK_FALSE(hostHeaderAllowed(bind, host));
        }
    }
    CHECK_FALSE(isLoopbackAddress("::ffff:10.0.0.1"));
    CHECK_FALSE(isLoopbackAddress("::"));
    // Another address admits that address only, in any spelling.
    CHECK(hostHeaderAllowed("192.0.2.1", "192.0.2.1:8340"));
    CHECK(hostHeaderAllowed("192.0.2.1", "[::ffff:192.0.2.1]:8340"));
    CHECK(hostHeaderAllowed("2001:db8::1", "[2001:DB8:0::1]:8340"));
    CHECK_FALSE(hostHeaderAllowed("192.0.2.1", "127.0.0.1:8340"));
    CHECK_FALSE(hostHeaderAllowed("192.0.2.1", "evil.com:8340"));
    CHECK_FALSE(hostHeaderAllowed("192.0.2.1", "192.0.2.1:80@evil.com"));
    // A wildcard admits loopback names and addresses, never a name DNS could rebind.
    for (const std::string bind : {"0.0.0.0", "::", "::ffff:0.0.0.0"}) {
        INFO(bind);
        CHECK(hostHeaderAllowed(bind, "192.0.2.1:8340"));
        CHECK(hostHeaderAllowed(bind, "localhost:8340"));
        CHECK_FALSE(hostHeaderAllowed(bind, "evil.com:8340"));
        CHECK_FALSE(hostHeaderAllowed(bind, "127.0.0.1:80@evil.com"));
    }
}

TEST_CASE("loopback spelled long keeps the rebinding check on every path", "[threads]") {
    for (const std::string bind : {"0:0:0:0:0:0:0:1", "::ffff:127.0.0.1"}) {
        INFO(bind);
        ViewServerOptions options;
        options.bindAddress = bind;
        ViewServer server(options);
        server.setDocument("/scene.json", R"({"objects":[]})");
        server.publish(R"({"t":1})");
        const int port = server.start();
        const bool v6 = bind == "0:0:0:0:0:0:0:1";
        const std::string self = (v6 ? "[::1]:" : "127.0.0.1:") + std::to_string(port);
        const std::string evil = "evil.com:" + std::to_string(port);
        for (const std::string path : {"/", "/scene.json", "/stream"}) {
            INFO(path);
            CHECK(statusOf(requestAs(evil, path, port, v6, "Origin: http://" + evil + "\r\n")) ==
                  403);
            CHECK(statusOf(requestAs("127.0.0.1:80@evil.com", path, port, v6)) == 403);
            CHECK(statusOf(requestAs("[::1]evil.com", path, port, v6)) == 403);
        }
        CHECK(statusOf(requestAs(self, "/scene.json", port, v6)) == 200);
        RawConnection c(port, v6);
        c.send("GET /stream HTTP/1.1\r\nHost: " + self + "\r\nOrigin: http://" + self + "\r\n\r\n");
        CHECK(c.readUntil("\n\n").find(R"(data: {"t":1})") != std::string::npos);
    }
}

TEST_CASE("a stream viewer that stops reading is dropped by time, its buffers full", "[realtime]") {
    ViewServer server; // the 2 s default
    const int port = server.start();
    RawConnection stalled(port);
    stalled.send("GET /stream HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\n\r\n");
    REQUIRE(test::eventually([&] { return server.streamClients() == 1; }));
    // Live frames of about a kilobyte, 30 a second, none of them read, for 20 s at most: a
    // generous bound (a few seconds fill the viewer's receive buffer), far below the half
    // minute it took while the server's own send buffer grew.
    const std::string frame = "{\"pad\":\"" + std::string(1000, 'x') + "\"}";
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (std::chrono::steady_clock::now() < end && server.streamClients() > 0) {
        server.publish(frame);
        std::this_thread::sleep_for(std::chrono::milliseconds(33));
    }
    CHECK(server.streamClients() == 0);
}
