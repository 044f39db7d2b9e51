// cpp-httplib's server under limits (BoundedHttpServer.h).

#include "BoundedHttpServer.h"

#include <linux/sockios.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <strings.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string>

namespace hapto {
namespace {

using Clock = std::chrono::steady_clock;

// Waits until `sock` is ready for `events` (or has an error to report) or `deadline` passes.
bool waitFor(int sock, short events, Clock::time_point deadline) {
    for (;;) {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
        pollfd p{sock, events, 0};
        const int n = poll(&p, 1, static_cast<int>(std::clamp<long long>(left, 0, 1000)));
        if (n > 0 || (n < 0 && errno != EINTR)) {
            return true; // the read or write that follows reports what happened
        }
        if (n == 0 && Clock::now() >= deadline) {
            return false;
        }
    }
}

// "address" and port of a socket's end, numeric.
void endpoint(int sock, bool peer, std::string& ip, int& port) {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    auto* a = reinterpret_cast<sockaddr*>(&addr);
    if ((peer ? getpeername(sock, a, &len) : getsockname(sock, a, &len)) != 0) {
        return;
    }
    char host[NI_MAXHOST], service[NI_MAXSERV];
    if (getnameinfo(a, len, host, sizeof host, service, sizeof service,
                    NI_NUMERICHOST | NI_NUMERICSERV) == 0) {
        ip = host;
        port = std::atoi(service);
    }
}

enum class Head { Ready, Closed, TimedOut, TooLarge, UriTooLong, ManyRanges };

// True when a head asks for several byte ranges (a Range header holding a comma, or two Range
// headers): cpp-httplib would answer with a copy of the body per range.
bool asksManyRanges(const std::string& head) {
    std::size_t ranges = 0;
    for (std::size_t line = head.find('\n'); line != std::string::npos;
         line = head.find('\n', line + 1)) {
        if (head.size() - line > 6 && strncasecmp(head.data() + line + 1, "range:", 6) == 0) {
            const std::size_t end = head.find('\n', line + 1);
            ranges += head.find(',', line) < end ? 2 : 1;
        }
    }
    return ranges > 1;
}

// One client connection: the request heads it reads ahead of cpp-httplib, then the socket.
class Connection final : public httplib::Stream {
public:
    Connection(int sock, const HttpLimits& limits)
        : mSock(sock), mLimits(limits), mTakenAt(Clock::now()) {}

    // Reads the next request's whole head (and whatever follows it in the same reads) within
    // the head deadline and caps; the bytes stay buffered for read().
    Head readHead() {
        mBuffer.erase(0, mOffset);
        mOffset = 0;
        mReadDeadline = Clock::now() + mLimits.headTimeout;
        for (;;) {
            const std::size_t end = mBuffer.find("\r\n\r\n");
            const std::size_t head = end == std::string::npos ? mBuffer.size() : end + 4;
            const std::size_t firstLine = mBuffer.find('\n');
            if ((firstLine == std::string::npos ? mBuffer.size() : firstLine + 1) >
                mLimits.maxRequestLine + 2) {
                return Head::UriTooLong;
            }
            const auto lines = std::count(mBuffer.begin(), mBuffer.begin() + head, '\n');
            if (head > mLimits.maxHeadBytes ||
                static_cast<std::size_t>(lines) > mLimits.maxHeaderLines + 2) {
                return Head::TooLarge; // + 2: the request line and the blank line
            }
            if (end != std::string::npos) {
                return asksManyRanges(mBuffer.substr(0, head)) ? Head::ManyRanges : Head::Ready;
            }
            if (!waitFor(mSock, POLLIN, mReadDeadline)) {
                return Head::TimedOut;
            }
            char chunk[4096];
            const ssize_t n = recv(mSock, chunk, sizeof chunk, 0);
            if (n <= 0 && !(n < 0 && errno == EINTR)) {
                return Head::Closed;
            }
            mBuffer.append(chunk, static_cast<std::size_t>(std::max<ssize_t>(n, 0)));
        }
    }

    // Answers a head that was refused (nothing for a client that closed or never spoke).
    void refuse(Head head) {
        const char* status = head == Head::UriTooLong   ? "414 URI Too Long"
                             : head == Head::TooLarge   ? "431 Request Header Fields Too Large"
                             : head == Head::ManyRanges ? "416 Range Not Satisfiable"
                             : head == Head::TimedOut && !mBuffer.empty() ? "408 Request Timeout"
                                                                          : nullptr;
        if (status == nullptr) {
            return;
        }
        const std::string body = std::string(status) + "\n";
        const std::string response =
            "HTTP/1.1 " + std::string(status) +
            "\r\nContent-Type: text/plain\r\nContent-Length: " + std::to_string(body.size()) +
            "\r\nConnection: close\r\n\r\n" + body;
        write(response.data(), response.size());
    }

    bool is_readable() const override {
        return mOffset < mBuffer.size() || waitFor(mSock, POLLIN, mReadDeadline);
    }
    ssize_t read(char* ptr, size_t size) override {
        if (mOffset < mBuffer.size()) {
            const std::size_t n = std::min(size, mBuffer.size() - mOffset);
            std::memcpy(ptr, mBuffer.data() + mOffset, n);
            mOffset += n;
            return static_cast<ssize_t>(n);
        }
        return waitFor(mSock, POLLIN, mReadDeadline) ? recv(mSock, ptr, size, 0) : -1;
    }
    bool is_writable() const override {
        for (;;) {
            if (stalled()) {
                return false;
            }
            pollfd p{mSock, POLLOUT, 0};
            const int n = poll(&p, 1, 100); // a slice: the stall rule is checked between them
            if (n > 0) {
                return (p.revents & (POLLERR | POLLHUP | POLLNVAL)) == 0;
            }
            if (n < 0 && errno != EINTR) {
                return false;
            }
        }
    }
    ssize_t write(const char* ptr, size_t size) override {
        std::size_t sent = 0;
        while (sent < size) {
            if (!is_writable()) {
                return -1;
            }
            const ssize_t n = send(mSock, ptr + sent, size - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
            if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
                return -1;
            }
            sent += static_cast<std::size_t>(std::max<ssize_t>(n, 0));
            mWrittenSince += static_cast<std::size_t>(std::max<ssize_t>(n, 0));
        }
        return static_cast<ssize_t>(size);
    }
    void get_remote_ip_and_port(std::string& ip, int& port) const override {
        endpoint(mSock, true, ip, port);
    }
    void get_local_ip_and_port(std::string& ip, int& port) const override {
        endpoint(mSock, false, ip, port);
    }
    socket_t socket() const override { return mSock; }

private:
    // True when bytes wait in the send queue and the client has acknowledged none of them for
    // the write timeout: it stopped reading and its receive buffer is full. (SIOCOUTQ: bytes
    // sent and not acknowledged, or not sent yet; less than before plus what was written
    // since means some were acknowledged.)
    bool stalled() const {
        int queued = 0;
        if (ioctl(mSock, SIOCOUTQ, &queued) != 0) {
            return false; // not TCP: the poll in is_writable decides
        }
        const auto now = Clock::now();
        const auto queuedNow = static_cast<std::size_t>(queued);
        const bool taken = queuedNow < mQueued + mWrittenSince;
        mQueued = queuedNow;
        mWrittenSince = 0;
        if (queuedNow == 0 || taken) {
            mTakenAt = now;
            return false;
        }
        return now - mTakenAt >= mLimits.writeTimeout;
    }

    int mSock;
    const HttpLimits& mLimits;
    std::string mBuffer;     // read from the socket, not yet handed to cpp-httplib
    std::size_t mOffset = 0; // what of mBuffer was handed
    Clock::time_point mReadDeadline;
    mutable std::size_t mQueued = 0;       // in the send queue at the last stalled()
    mutable std::size_t mWrittenSince = 0; // handed to send() since
    mutable Clock::time_point mTakenAt;    // when the client last took some or had none
};

} // namespace

void BoundedHttpServer::closeClients() {
    std::lock_guard lock(mMutex);
    mClosing = true;
    for (const socket_t sock : mClients) {
        shutdown(sock, SHUT_RDWR); // not close(): the worker closes it, no descriptor reuse
    }
}

bool BoundedHttpServer::track(socket_t sock) {
    std::lock_guard lock(mMutex);
    if (!mClosing) {
        mClients.insert(sock);
    }
    return !mClosing;
}

void BoundedHttpServer::untrack(socket_t sock) {
    std::lock_guard lock(mMutex);
    mClients.erase(sock);
}

bool BoundedHttpServer::process_and_close_socket(socket_t sock) {
    bool ok = false;
    if (track(sock)) {
        Connection connection(sock, mLimits);
        for (std::size_t n = 0; n < mLimits.maxRequestsPerConnection; ++n) {
            const Head head = connection.readHead();
            if (head != Head::Ready) {
                connection.refuse(head);
                break;
            }
            bool closedByClient = false;
            const bool last = n + 1 == mLimits.maxRequestsPerConnection;
            ok = process_request(connection, last, closedByClient, [](httplib::Request&) {});
            if (!ok || closedByClient) {
                break;
            }
        }
        untrack(sock);
    }
    shutdown(sock, SHUT_RDWR);
    close(sock);
    return ok;
}

} // namespace hapto
