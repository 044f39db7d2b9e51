// Design note: open first (O_NONBLOCK, so a FIFO without a writer does not block the open),
// then fstat the descriptor; only a regular file is read, and only up to the limit. Checking
// the descriptor rather than the path means nothing can be swapped in between.

#include "hapto/io/InputFile.h"

#include "hapto/io/InputError.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hapto {
namespace {

std::string kindOf(mode_t mode) {
    if (S_ISREG(mode)) {
        return "";
    }
    if (S_ISDIR(mode)) {
        return "a directory";
    }
    if (S_ISFIFO(mode)) {
        return "a FIFO";
    }
    if (S_ISSOCK(mode)) {
        return "a socket";
    }
    if (S_ISCHR(mode)) {
        return "a character device";
    }
    if (S_ISBLK(mode)) {
        return "a block device";
    }
    return "not a regular file";
}

std::string showBytes(std::uint64_t bytes) {
    char buf[64];
    if (bytes < (1u << 20)) {
        std::snprintf(buf, sizeof buf, "%llu bytes", static_cast<unsigned long long>(bytes));
    } else if (bytes < (1u << 30)) {
        std::snprintf(buf, sizeof buf, "%.1f MiB", static_cast<double>(bytes) / (1 << 20));
    } else {
        std::snprintf(buf, sizeof buf, "%.1f GiB", static_cast<double>(bytes) / (1 << 30));
    }
    return buf;
}

} // namespace

std::string nonRegularKind(const std::filesystem::path& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        return "";
    }
    return kindOf(st.st_mode);
}

InputFile::InputFile(const std::filesystem::path& path, std::string_view what,
                     std::uint64_t maxBytes)
    : mPath(path.string()), mWhat(what), mMaxBytes(maxBytes) {
    if (const std::size_t nul = mPath.find('\0'); nul != std::string::npos) {
        std::string shown;
        for (const char c : mPath) {
            shown += c == '\0' ? std::string("\\0") : std::string(1, c);
        }
        throw InputError(shown + ": a NUL byte (\\0) in the " + mWhat + "'s path (at character " +
                         std::to_string(nul) + "; the system would read the path only up to it)");
    }
    const auto refuse = [&](const std::string& kind) {
        throw InputError(mPath + ": is " + kind + ", not a regular file (give the " + mWhat +
                         " as a file on disk)");
    };
    mFd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (mFd < 0) {
        const int err = errno;
        // A socket cannot be opened at all (ENXIO): say what it is rather than why open failed.
        if (const std::string kind = nonRegularKind(path); !kind.empty()) {
            refuse(kind);
        }
        throw InputError(mPath + ": cannot open the " + mWhat + " (" + std::strerror(err) +
                         (err == ENOENT ? "; does it exist?)" : ")"));
    }
    struct stat st {};
    if (::fstat(mFd, &st) != 0) {
        const int err = errno;
        ::close(mFd);
        mFd = -1;
        throw InputError(mPath + ": cannot read the " + mWhat + " (" + std::strerror(err) + ")");
    }
    if (const std::string kind = kindOf(st.st_mode); !kind.empty()) {
        ::close(mFd);
        mFd = -1;
        refuse(kind);
    }
    mSize = static_cast<std::uint64_t>(st.st_size);
    if (mSize > mMaxBytes) {
        ::close(mFd);
        mFd = -1;
        throw InputError(mPath + ": the " + mWhat + " is " + showBytes(mSize) + ", more than the " +
                         showBytes(mMaxBytes) + " limit for input files");
    }
    // Reads block normally from here on (a regular file never blocks anyway).
    const int flags = ::fcntl(mFd, F_GETFL);
    if (flags >= 0) {
        (void)::fcntl(mFd, F_SETFL, flags & ~O_NONBLOCK);
    }
}

InputFile::~InputFile() {
    if (mFd >= 0) {
        ::close(mFd);
    }
}

std::string InputFile::readHead(std::size_t bytes) {
    std::string head(static_cast<std::size_t>(std::min<std::uint64_t>(bytes, mSize)), '\0');
    std::size_t used = 0;
    while (used < head.size()) {
        const ssize_t n =
            ::pread(mFd, head.data() + used, head.size() - used, static_cast<off_t>(used));
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0) {
            throw InputError(mPath + ": cannot read the " + mWhat + " (" + std::strerror(errno) +
                             ")");
        }
        if (n == 0) {
            break;
        }
        used += static_cast<std::size_t>(n);
    }
    head.resize(used);
    return head;
}

std::string InputFile::readAll() {
    std::string text;
    text.resize(static_cast<std::size_t>(mSize));
    std::size_t used = 0;
    for (;;) {
        if (used == text.size()) {
            // Files in /proc report size 0, and a file may grow: read on, within the limit.
            if (text.size() >= mMaxBytes) {
                char probe;
                const ssize_t n = ::read(mFd, &probe, 1);
                if (n == 0) {
                    break;
                }
                throw InputError(mPath + ": the " + mWhat + " grew past the " +
                                 showBytes(mMaxBytes) + " limit for input files while reading");
            }
            const std::size_t grown = std::max<std::size_t>(4096, text.size());
            text.resize(
                static_cast<std::size_t>(std::min<std::uint64_t>(text.size() + grown, mMaxBytes)));
        }
        const ssize_t n = ::read(mFd, text.data() + used, text.size() - used);
        if (n < 0) {
            if (errno == EINTR) {
                continue;
            }
            throw InputError(mPath + ": cannot read the " + mWhat + " (" + std::strerror(errno) +
                             ")");
        }
        if (n == 0) {
            break;
        }
        used += static_cast<std::size_t>(n);
    }
    text.resize(used);
    return text;
}

std::FILE* InputFile::releaseToStdio() {
    std::FILE* f = ::fdopen(mFd, "rb");
    if (!f) {
        throw InputError(mPath + ": cannot read the " + mWhat + " (" + std::strerror(errno) + ")");
    }
    mFd = -1;
    return f;
}

} // namespace hapto
