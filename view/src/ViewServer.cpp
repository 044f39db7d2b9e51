// The view's web server: fixed assets, JSON documents, and the live frame stream (SSE).

#include "hapto/view/ViewServer.h"

#include "ViewAssets.h"

#include <httplib.h>

#include <arpa/inet.h>
#include <sys/socket.h>

#include <fstream>
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

// "host:port" or "[v6]:port" without the port.
std::string hostName(const std::string& hostHeader) {
    if (!hostHeader.empty() && hostHeader.front() == '[') {
        const auto close = hostHeader.find(']');
        return close == std::string::npos ? hostHeader : hostHeader.substr(1, close - 1);
    }
    return hostHeader.substr(0, hostHeader.rfind(':'));
}

} // namespace

bool isLoopbackAddress(const std::string& address) {
    if (address == "localhost" || address == "::1") {
        return true;
    }
    in_addr v4{};
    return inet_pton(AF_INET, address.c_str(), &v4) == 1 &&
           (ntohl(v4.s_addr) >> 24) == 127; // 127.0.0.0/8
}

ViewServer::ViewServer(ViewServerOptions options)
    : mOptions(std::move(options)), mServer(std::make_unique<httplib::Server>()) {
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

bool ViewServer::hostAllowed(const std::string& host) const {
    // Bound to loopback, a page reached under another name is a DNS-rebinding attempt.
    return !isLoopbackAddress(mOptions.bindAddress) || isLoopbackAddress(hostName(host));
}

int ViewServer::start() {
    httplib::Server& s = *mServer;
    const std::size_t threads = mOptions.maxStreamClients + 4; // streams + page loads
    s.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
    s.set_write_timeout(
        std::chrono::duration_cast<std::chrono::microseconds>(mOptions.writeTimeout));
    s.set_read_timeout(std::chrono::seconds(5));
    s.set_payload_max_length(4096); // nothing is uploaded
    // SO_REUSEADDR only: cpp-httplib's default adds SO_REUSEPORT, which would let a second
    // server share (and take over part of) a port already in use.
    s.set_socket_options([](socket_t sock) {
        int yes = 1;
        setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });

    // Read-only, one host: every request passes here first.
    s.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
        if (req.method != "GET" && req.method != "HEAD") {
            res.status = 405;
            res.set_header("Allow", "GET, HEAD");
            res.set_content("the view is read-only: only GET and HEAD\n", "text/plain");
            return httplib::Server::HandlerResponse::Handled;
        }
        if (!hostAllowed(req.get_header_value("Host"))) {
            res.status = 403;
            res.set_content("this view answers only to a loopback host name\n", "text/plain");
            return httplib::Server::HandlerResponse::Handled;
        }
        return httplib::Server::HandlerResponse::Unhandled;
    });
    const auto fixed = [&s](const std::string& path, const std::string* body, const char* type) {
        s.Get(path, [body, type](const httplib::Request&, httplib::Response& res) {
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
