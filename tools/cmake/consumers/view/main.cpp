// Built and run by the install test against an installed hapto: an application serves the view
// from the installed library (the page is built into it; three.js is read from Debian's
// libjs-three, which the constructor checks). It starts the server on a free loopback port,
// asks it for the page and for three.js over a plain socket, and stops.

#include <hapto/view/ViewServer.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

// The status line of `GET path` from the server on 127.0.0.1:port ("" when it cannot connect).
static std::string statusOf(int port, const std::string& path) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    std::string reply;
    if (connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0) {
        const std::string request = "GET " + path +
                                    " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                                    "\r\nConnection: close\r\n\r\n";
        if (write(fd, request.data(), request.size()) == static_cast<ssize_t>(request.size())) {
            char buffer[256];
            const ssize_t got = read(fd, buffer, sizeof buffer);
            reply.assign(buffer, got > 0 ? static_cast<std::size_t>(got) : 0);
        }
    }
    close(fd);
    return reply.substr(0, reply.find("\r\n"));
}

int main() {
    hapto::ViewServer server;
    const int port = server.start();
    const std::string page = statusOf(port, "/");
    const std::string three = statusOf(port, "/three/three.min.js");
    server.stop();
    std::printf("/ -> %s\n/three/three.min.js -> %s\n", page.c_str(), three.c_str());
    return page == "HTTP/1.1 200 OK" && three == "HTTP/1.1 200 OK" ? 0 : 1;
}
