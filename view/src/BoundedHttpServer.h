#pragma once
/// cpp-httplib's server with the limits it lacks: a whole request head read within a deadline
/// and a size and line cap, bounded keep-alive, a viewer that takes nothing dropped, and a
/// stop that never waits for a client.

#include <httplib.h>

#include <chrono>
#include <cstddef>
#include <mutex>
#include <set>

namespace hapto {

/// What one connection may cost the server.
struct HttpLimits {
    /// A request's head (request line and headers) must arrive whole within this long from the
    /// moment the server waits for it; an idle keep-alive connection is closed after it too.
    std::chrono::milliseconds headTimeout{2000};
    /// A connection with bytes queued that takes none of them for this long is dropped.
    std::chrono::milliseconds writeTimeout{2000};
    std::size_t maxHeadBytes = 16 * 1024; ///< Request line and headers; more is 431.
    std::size_t maxHeaderLines = 64;      ///< Header lines; more is 431.
    std::size_t maxRequestLine = 8192;    ///< A longer request line is 414 (cpp-httplib's own).
    std::size_t maxRequestsPerConnection = 32; ///< Keep-alive ends after this many.
};

/// Design note: cpp-httplib 0.11 reads headers one line at a time with no count, no total and
/// only a per-read timeout, so a client dribbling one byte every few seconds holds a worker,
/// and stop() waits for it, for ever; a header flood grows memory without bound. This class
/// takes over the one per-connection entry point the library lets a subclass replace
/// (process_and_close_socket): it reads each request's head itself, under a total deadline and
/// the caps above, answers 408/414/431 on its own (and 416 to a request for several byte
/// ranges, which the library would answer with a copy of the body per range), and only then lets
/// the library parse the buffered head and route it (process_request). It keeps every open client
/// socket in a set: closeClients() shuts them all down, which wakes any worker blocked on one at
/// once, and a connection accepted after it is closed unread. Writes give up when the client has
/// taken none of the queued bytes for writeTimeout (the send queue, SIOCOUTQ), however large the
/// kernel's buffers are. The cost: one set insertion per connection and a ioctl per write.
class BoundedHttpServer : public httplib::Server {
public:
    explicit BoundedHttpServer(HttpLimits limits) : mLimits(limits) {}
    /// Shuts down every client connection (their workers return at once) and closes any
    /// accepted later unread; call before stop(). [any thread]
    void closeClients();

private:
    bool process_and_close_socket(socket_t sock) override;
    bool track(socket_t sock); // false once closing
    void untrack(socket_t sock);

    HttpLimits mLimits;
    std::mutex mMutex; // guards the two below
    std::set<socket_t> mClients;
    bool mClosing = false;
};

} // namespace hapto
