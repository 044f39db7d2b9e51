#pragma once
/// The view's web server: the page, its script, three.js, a few JSON documents and one live
/// stream of frames (Server-Sent Events), read-only and loopback-only by default.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace hapto {

class BoundedHttpServer;

/// Where Debian's libjs-three puts three.js (build/three.min.js, examples/js/controls/...).
inline constexpr const char* kDefaultThreeJsDir = "/usr/share/javascript/three";

/// How a ViewServer listens.
struct ViewServerOptions {
    std::string bindAddress = "127.0.0.1"; ///< Loopback unless asked otherwise.
    int port = 0;                          ///< TCP port; 0 takes any free one.
    std::size_t maxStreamClients = 4;      ///< Live streams served at once; more get 503.
    std::filesystem::path threeJsDir = kDefaultThreeJsDir; ///< libjs-three's folder.
    /// A connection whose client takes none of the bytes queued for it for this long (a
    /// stalled viewer, once its receive buffer is full) is dropped.
    std::chrono::milliseconds writeTimeout{2000};
    /// A request's head must arrive whole within this long (an idle keep-alive connection is
    /// closed after it too).
    std::chrono::milliseconds requestTimeout{2000};
    /// Serves `/stream` (a live session); a recording has no stream (404).
    bool liveStream = true;
};

/// True for 127.0.0.0/8, ::1 (in any spelling, IPv4-mapped included) and "localhost".
/// [any thread]
bool isLoopbackAddress(const std::string& address);

/// True when a request's Host header (`name[:port]`, `[v6][:port]`, nothing else) names a
/// server bound to `bindAddress`, addresses compared parsed: bound to loopback, "localhost"
/// or a loopback address; bound to a wildcard (0.0.0.0, ::), those or any IP address (an
/// address cannot be rebound by DNS); bound to another address or name, that one only.
/// Anything else is a DNS-rebinding attempt. [any thread]
bool hostHeaderAllowed(const std::string& bindAddress, const std::string& hostHeader);

/// Serves the view. Design note: the page is read-only by construction: only GET and HEAD
/// are answered (anything else is 405), and only a fixed list of paths: the page and its
/// script (built into the binary), three.js and OrbitControls from libjs-three's folder, and
/// the documents set with setDocument(); any other path, a traversal ("/../") included, is
/// 404 without touching the file system. The live stream (`/stream`, text/event-stream) sends
/// the newest frame given to publish(): a viewer that is slow skips frames, one that stalls is
/// dropped once it has taken nothing for the write timeout, and neither is ever waited for by
/// the publisher. A stream request from another origin (its Origin header is not this server)
/// is 403, and so is a request naming a host the binding does not admit (hostHeaderAllowed:
/// DNS rebinding). Several ranges in one request are 416 (one range is served). The HTTP
/// work runs on cpp-httplib's threads (a pool sized for the stream limit plus a few page
/// loads) under BoundedHttpServer's limits: a request head within requestTimeout, at most
/// 64 header lines and 16 KiB (431), bounded keep-alive, and a stop() that shuts every client
/// connection down instead of waiting for it.
class ViewServer {
public:
    /// Checks that three.js is where it should be; throws std::runtime_error naming the file
    /// and the package when it is not. [control]
    explicit ViewServer(ViewServerOptions options = {});
    ~ViewServer();
    ViewServer(const ViewServer&) = delete;
    ViewServer& operator=(const ViewServer&) = delete;

    /// Serves `body` as JSON at `path` ("/scene.json"); before start() only. [control]
    void setDocument(const std::string& path, std::string body);
    /// Binds and starts serving; returns the port. Throws std::runtime_error when the address
    /// cannot be bound. [control]
    int start();
    /// Ends every stream, shuts every client connection down and stops serving; waits for the
    /// server's threads, never for a client. [control]
    void stop();
    /// The port served (after start()). [any thread]
    int port() const { return mPort; }
    /// The page's address, "http://127.0.0.1:PORT/". [any thread]
    std::string url() const;

    /// Makes `frameJson` (one line of JSON) the newest frame and wakes the streams. Never
    /// waits for a viewer. Not for a servo thread (it allocates and takes a short lock).
    /// [any thread]
    void publish(std::string frameJson);
    /// Frames published so far. [any thread]
    std::uint64_t framesPublished() const;
    /// Streams open now. [any thread]
    std::size_t streamClients() const { return mStreams.load(); }

private:
    void route();

    ViewServerOptions mOptions;
    std::unique_ptr<BoundedHttpServer> mServer;
    std::thread mListener;
    std::map<std::string, std::string> mDocuments; // fixed once started
    std::string mThreeJs, mOrbitControls;          // read at construction
    int mPort = 0;
    std::atomic<std::size_t> mStreams{0};

    mutable std::mutex mFrameMutex; // guards the three below; held only to copy a frame
    std::condition_variable mFrameChanged;
    std::string mFrame;
    std::uint64_t mFrameSeq = 0;
    bool mStopping = false;
};

} // namespace hapto
