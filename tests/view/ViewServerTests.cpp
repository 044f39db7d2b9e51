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

#include <fstream>
#include <sstream>

using namespace hapto;

namespace {

// A raw HTTP/1.1 exchange, byte for byte as written (no client normalising the path).
class RawConnection {
public:
    explicit RawConnection(int port) {
        mFd = socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in addr{};
        addr.sin_family = AF_INET;
        addr.sin_port = htons(static_cast<std::uint16_t>(port));
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        REQUIRE(connect(mFd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
        timeval tv{5, 0};
        setsockopt(mFd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
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

std::string fileText(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

} // namespace

TEST_CASE("the view serves its page, its script, three.js and its documents") {
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

TEST_CASE("the view refuses path traversal and serves no file it does not list") {
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

TEST_CASE("the view is read-only: only GET and HEAD are answered") {
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

TEST_CASE("a stream from another origin, or a loopback view under another host name, is refused") {
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

TEST_CASE("the view serves at most its limit of streams, a closed one frees its place") {
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

TEST_CASE("a port in use is refused with the address named") {
    ViewServer first;
    const int port = first.start();
    ViewServerOptions options;
    options.port = port;
    ViewServer second(options);
    CHECK_THROWS_WITH(second.start(), Catch::Contains("127.0.0.1:" + std::to_string(port)));
}
