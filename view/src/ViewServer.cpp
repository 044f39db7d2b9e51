// The view's web server: fixed assets, JSON documents, and the live frame stream (SSE).

#include "hapto/view/ViewServer.h"

#include "BoundedHttpServer.h"
#include "ViewAssets.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace hapto {
namespace {

// The whole of a file we ship or depend on (three.js); throws naming the file and package.
std::string readAsset(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        throw std::runtime_error(path.string() +
                                 ": not found; the view needs three.js from Debian's libjs-three "
                                 "(tools/setup.sh installs it)");
    }
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

// An IP address in IPv6 form (IPv4 as ::ffff:a.b.c.d), whatever its spelling; nullopt when the
// text is not an address.
std::optional<in6_addr> parseAddress(const std::string& text) {
    in6_addr v6{};
    if (inet_pton(AF_INET6, text.c_str(), &v6) == 1) {
        return v6;
    }
    in_addr v4{};
    if (inet_pton(AF_INET, text.c_str(), &v4) != 1) {
        return std::nullopt;
    }
    v6.s6_addr[10] = v6.s6_addr[11] = 0xff;
    std::memcpy(&v6.s6_addr[12], &v4, sizeof v4);
    return v6;
}

bool isLoopback(const in6_addr& a) {
    return IN6_IS_ADDR_LOOPBACK(&a) || (IN6_IS_ADDR_V4MAPPED(&a) && a.s6_addr[12] == 127);
}

bool isWildcard(const in6_addr& a) {
    static const in6_addr anyV4 = *parseAddress("0.0.0.0");
    return IN6_IS_ADDR_UNSPECIFIED(&a) || std::memcmp(&a, &anyV4, sizeof a) == 0;
}

std::string lowerCase(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

// The host a Host header names, lower case: "name", "name:port", "[v6]" or "[v6]:port" and
// nothing else (no user part, no text after the address or the port); nullopt otherwise.
std::optional<std::string> hostOf(const std::string& header) {
    std::string host, rest;
    if (!header.empty() && header.front() == '[') {
        const std::size_t close = header.find(']');
        in6_addr v6{};
        if (close == std::string::npos ||
            inet_pton(AF_INET6, header.substr(1, close - 1).c_str(), &v6) != 1) {
            return std::nullopt; // brackets hold an IPv6 address and only that
        }
        host = header.substr(1, close - 1);
        rest = header.substr(close + 1);
    } else {
        const std::size_t colon = header.find(':');
        host = header.substr(0, colon);
        rest = colon == std::string::npos ? "" : header.substr(colon);
        const auto nameChar = [](unsigned char c) {
            return std::isalnum(c) != 0 || c == '-' || c == '.';
        };
        if (host.empty() || !std::all_of(host.begin(), host.end(), nameChar)) {
            return std::nullopt;
        }
    }
    const auto digit = [](unsigned char c) { return std::isdigit(c) != 0; };
    if (!rest.empty() && (rest.size() < 2 || rest.size() > 6 || rest.front() != ':' ||
                          !std::all_of(rest.begin() + 1, rest.end(), digit))) {
        return std::nullopt;
    }
    return lowerCase(host);
}

// A path as a cpp-httplib route (a regular expression) that matches that path only.
std::string exactly(const std::string& path) {
    std::string pattern;
    for (const char c : path) {
        if (std::strchr("\\^$.|?*+()[]{}", c) != nullptr) {
            pattern += '\\';
        }
        pattern += c;
    }
    return pattern;
}

} // namespace

bool isLoopbackAddress(const std::string& address) {
    const auto parsed = parseAddress(address);
    return lowerCase(address) == "localhost" || (parsed && isLoopback(*parsed));
}

bool hostHeaderAllowed(const std::string& bindAddress, const std::string& hostHeader) {
    const auto host = hostOf(hostHeader);
    if (!host) {
        return false;
    }
    const auto hostAddress = parseAddress(*host);
    const bool loopbackName = *host == "localhost" || (hostAddress && isLoopback(*hostAddress));
    const auto bound = parseAddress(bindAddress);
    if (!bound) { // bound by name: that name (or, for "localhost", any loopback name)
        return lowerCase(bindAddress) == "localhost" ? loopbackName
                                                     : *host == lowerCase(bindAddress);
    }
    if (isLoopback(*bound)) {
        return loopbackName;
    }
    if (isWildcard(*bound)) {
        return loopbackName || hostAddress.has_value();
    }
    return hostAddress && std::memcmp(&*hostAddress, &*bound, sizeof(in6_addr)) == 0;
}

ViewServer::ViewServer(ViewServerOptions options)
    : mOptions(std::move(options)),
      mServer(std::make_unique<BoundedHttpServer>(HttpLimits{
          .headTimeout = mOptions.requestTimeout, .writeTimeout = mOptions.writeTimeout})) {
    mThreeJs = readAsset(mOptions.threeJsDir / "build" / "three.min.js");
    mOrbitControls =
        readAsset(mOptions.threeJsDir / "examples" / "js" / "controls" / "OrbitControls.js");
}

ViewServer::~ViewServer() {
    stop();
}

void ViewServer::setDocument(const std::string& path, std::string body) {
    if (mListener.joinable()) {
        throw std::logic_error("ViewServer::setDocument after start");
    }
    mDocuments[path] = std::move(body);
}

std::string ViewServer::url() const {
    const std::string host = mOptions.bindAddress.find(':') != std::string::npos
                                 ? "[" + mOptions.bindAddress + "]"
                                 : mOptions.bindAddress;
    return "http://" + (host == "0.0.0.0" ? std::string("127.0.0.1") : host) + ":" +
           std::to_string(mPort) + "/";
}

void ViewServer::route() {
    httplib::Server& s = *mServer;
    // Read-only, one host: every request passes here first.
    s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
        if (req.method != "GET" && req.method != "HEAD") {
            res.status = 405;
            res.set_header("Allow", "GET, HEAD");
            res.set_content("the view is read-only: only GET and HEAD\n", "text/plain");
            return httplib::Server::HandlerResponse::Handled;
        }
        if (!hostHeaderAllowed(mOptions.bindAddress, req.get_header_value("Host"))) {
            res.status = 403;
            res.set_content("this view answers only to the host name it listens on\n",
                            "text/plain");
            return httplib::Server::HandlerResponse::Handled;
        }
        return httplib::Server::HandlerResponse::Unhandled;
    });
    const auto fixed = [&s](const std::string& path, const std::string* body, const char* type) {
        s.Get(exactly(path), [body, type](const httplib::Request&, httplib::Response& res) {
            res.set_header("Cache-Control", "no-store");
            res.set_content(*body, type);
        });
    };
    static const std::string index = view_assets::kIndexHtml;
    static const std::string script = view_assets::kViewJs;
    fixed("/", &index, "text/html; charset=utf-8");
    fixed("/index.html", &index, "text/html; charset=utf-8");
    fixed("/view.js", &script, "text/javascript; charset=utf-8");
    fixed("/three/three.min.js", &mThreeJs, "text/javascript; charset=utf-8");
    fixed("/three/OrbitControls.js", &mOrbitControls, "text/javascript; charset=utf-8");
    for (const auto& [path, body] : mDocuments) {
        fixed(path, &body, "application/json");
    }
    if (!mOptions.liveStream) {
        return;
    }
    s.Get("/stream", [this](const httplib::Request& req, httplib::Response& res) {
        // EventSource sends Origin on a cross-origin request; the page's own has none or ours.
        const std::string origin = req.get_header_value("Origin");
        if (!origin.empty() && origin != "http://" + req.get_header_value("Host")) {
            res.status = 403;
            res.set_content("stream refused: request from another origin (" + origin + ")\n",
                            "text/plain");
            return;
        }
        if (mStreams.fetch_add(1) >= mOptions.maxStreamClients) {
            mStreams.fetch_sub(1);
            res.status = 503;
            res.set_content("too many viewers (at most " +
                                std::to_string(mOptions.maxStreamClients) + ")\n",
                            "text/plain");
            return;
        }
        res.set_header("Cache-Control", "no-store");
        auto lastSeq = std::make_shared<std::uint64_t>(0);
        res.set_chunked_content_provider(
            "text/event-stream",
            [this, lastSeq](std::size_t, httplib::DataSink& sink) {
                std::string message;
                {
                    std::unique_lock lock(mFrameMutex);
                    mFrameChanged.wait_for(lock, std::chrono::milliseconds(500),
                                           [&] { return mStopping || mFrameSeq != *lastSeq; });
                    if (mStopping) {
                        return false;
                    }
                    if (mFrameSeq == *lastSeq) {
                        message = ": idle\n\n"; // a comment: finds a closed viewer
                    } else {
                        *lastSeq = mFrameSeq;
                        message = "data: " + mFrame + "\n\n";
                    }
                }
                // Outside the lock: a stalled viewer blocks only this pool thread, until the
                // write timeout drops it.
                return sink.write(message.data(), message.size());
            },
            [this](bool) { mStreams.fetch_sub(1); });
    });
}

int ViewServer::start() {
    httplib::Server& s = *mServer;
    const std::size_t threads = mOptions.maxStreamClients + 4; // streams + page loads
    s.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
    s.set_payload_max_length(4096); // nothing is uploaded
    // SO_REUSEADDR only: cpp-httplib's default adds SO_REUSEPORT, which would let a second
    // server share (and take over part of) a port already in use.
    s.set_socket_options([](socket_t sock) {
        int yes = 1;
        setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    route();
    s.set_error_handler([](const httplib::Request&, httplib::Response& res) {
        if (res.body.empty()) {
            res.set_content(std::to_string(res.status) + "\n", "text/plain");
        }
    });

    mPort = mOptions.port == 0
                ? s.bind_to_any_port(mOptions.bindAddress)
                : (s.bind_to_port(mOptions.bindAddress, mOptions.port) ? mOptions.port : -1);
    if (mPort <= 0) {
        throw std::runtime_error("the view cannot listen on " + mOptions.bindAddress + ":" +
                                 std::to_string(mOptions.port) +
                                 " (in use, or not an address of this machine)");
    }
    mListener = std::thread([&s] { s.listen_after_bind(); });
    // stop() must find it running, or the listener would never end.
    while (!s.is_running()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return mPort;
}

void ViewServer::stop() {
    {
        std::lock_guard lock(mFrameMutex);
        mStopping = true;
    }
    mFrameChanged.notify_all();
    if (mListener.joinable()) {
        mServer->closeClients(); // a worker blocked on a client returns now
        mServer->stop();
        mListener.join();
    }
}

void ViewServer::publish(std::string frameJson) {
    {
        std::lock_guard lock(mFrameMutex);
        mFrame.swap(frameJson);
        ++mFrameSeq;
    }
    mFrameChanged.notify_all();
    // frameJson now holds the previous frame: freed here, outside the lock.
}

std::uint64_t ViewServer::framesPublished() const {
    std::lock_guard lock(mFrameMutex);
    return mFrameSeq;
}

} // namespace hapto
