// Output files written whole or not at all (temporary beside the target, then rename).

#include "hapto/io/OutputFile.h"

#include "hapto/io/InputError.h"
#include "hapto/io/InputFile.h"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <iostream>
#include <random>
#include <stdexcept>
#include <streambuf>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

namespace hapto {
namespace fs = std::filesystem;
namespace {

std::string quoted(const fs::path& p) {
    return "'" + p.string() + "'";
}

/// The file a write to `path` lands in: a symlink's target, else `path` itself.
fs::path resolveTarget(const fs::path& path) {
    std::error_code ec;
    if (fs::is_symlink(fs::symlink_status(path, ec))) {
        const fs::path resolved = fs::weakly_canonical(path, ec);
        if (!ec) {
            return resolved;
        }
    }
    return path;
}

/// `p` made absolute, symlinks resolved as far as they exist, lexically normal otherwise.
fs::path resolved(const fs::path& p) {
    std::error_code ec;
    const fs::path absolute = fs::absolute(p, ec).lexically_normal();
    const fs::path canonical = fs::weakly_canonical(absolute, ec);
    return ec ? absolute : canonical;
}

/// Throws InputError when `target` (symlinks resolved) exists and is not a regular file;
/// `what` names the output ("-o 'x'" or "'x'").
void refuseNonFile(const fs::path& target, const std::string& what) {
    const std::string kind = nonRegularKind(target); // empty: a regular file, or nothing there
    if (kind.empty()) {
        return;
    }
    if (kind == "a directory") {
        throw InputError(what + ": this is a folder; give a file name to write");
    }
    throw InputError(what + ": this is " + kind +
                     ", not a regular file; give the name of a file (an output is written "
                     "beside it and renamed into place)");
}

fs::path folderOf(const fs::path& path) {
    return path.has_parent_path() ? path.parent_path() : fs::path(".");
}

} // namespace

// FdBuf is Impl's own, not the anonymous namespace's: Impl is declared in the header, and a
// member whose type has internal linkage makes GCC warn (-Wsubobject-linkage) when the unity
// build includes this file into its unit.
struct AtomicOutputFile::Impl {
    /// A streambuf writing to a file descriptor through a buffer; errors make the stream bad.
    class FdBuf final : public std::streambuf {
    public:
        explicit FdBuf(int fd) : mFd(fd), mBuffer(1 << 16) {
            setp(mBuffer.data(), mBuffer.data() + mBuffer.size());
        }
        bool failed() const { return mFailed; }
        int error() const { return mErrno; }

    protected:
        int_type overflow(int_type c) override {
            if (sync() != 0) {
                return traits_type::eof();
            }
            if (!traits_type::eq_int_type(c, traits_type::eof())) {
                *pptr() = traits_type::to_char_type(c);
                pbump(1);
            }
            return traits_type::not_eof(c);
        }
        int sync() override {
            const char* p = pbase();
            while (p < pptr() && !mFailed) {
                const ssize_t n = ::write(mFd, p, static_cast<std::size_t>(pptr() - p));
                if (n < 0 && errno == EINTR) {
                    continue;
                }
                if (n <= 0) {
                    mFailed = true;
                    mErrno = n < 0 ? errno : EIO;
                    break;
                }
                p += n;
            }
            setp(mBuffer.data(), mBuffer.data() + mBuffer.size());
            return mFailed ? -1 : 0;
        }

    private:
        int mFd;
        std::vector<char> mBuffer;
        bool mFailed = false;
        int mErrno = 0;
    };

    fs::path target;    // where the contents end up (a symlink resolved)
    fs::path temporary; // beside the target, renamed onto it by commit()
    int fd = -1;
    std::unique_ptr<FdBuf> buf;
    std::unique_ptr<std::ostream> stream;
    bool committed = false;
};

AtomicOutputFile::AtomicOutputFile(const fs::path& path)
    : mPath(path), mImpl(std::make_unique<Impl>()) {
    Impl& m = *mImpl;
    m.target = resolveTarget(path);
    refuseNonFile(m.target, quoted(path));
    struct stat st {};
    const bool exists = ::stat(m.target.c_str(), &st) == 0;
    std::random_device random;
    const char* digits = "0123456789abcdefghijklmnopqrstuvwxyz";
    for (int attempt = 0; attempt < 100 && m.fd < 0; ++attempt) {
        std::string suffix = ".tmp-";
        for (int i = 0; i < 6; ++i) {
            suffix += digits[random() % 36];
        }
        m.temporary = m.target;
        m.temporary += suffix;
        // Created, never opened if it exists: a FIFO put there meanwhile cannot block this.
        m.fd =
            ::open(m.temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
        if (m.fd < 0 && errno != EEXIST) {
            break;
        }
    }
    if (m.fd < 0) {
        throw InputError("cannot write " + quoted(path) + " (" + std::strerror(errno) +
                         "); check that the folder " + quoted(folderOf(m.target)) +
                         " exists and is writable");
    }
    if (exists && S_ISREG(st.st_mode)) {
        (void)::fchmod(m.fd, st.st_mode & 07777); // a replaced file keeps its permissions
    }
    m.buf = std::make_unique<Impl::FdBuf>(m.fd);
    m.stream = std::make_unique<std::ostream>(m.buf.get());
}

AtomicOutputFile::~AtomicOutputFile() {
    if (mImpl->fd >= 0) {
        ::close(mImpl->fd);
    }
    if (!mImpl->committed && !mImpl->temporary.empty()) {
        ::unlink(mImpl->temporary.c_str());
    }
}

std::ostream& AtomicOutputFile::stream() {
    return *mImpl->stream;
}

void AtomicOutputFile::commit() {
    Impl& m = *mImpl;
    if (m.committed || m.fd < 0) {
        throw std::logic_error("AtomicOutputFile::commit called twice");
    }
    m.stream->flush();
    const bool written = !m.buf->failed() && static_cast<bool>(*m.stream);
    int error = m.buf->failed() ? m.buf->error() : 0;
    bool ok = written;
    if (ok && ::fsync(m.fd) != 0) {
        ok = false;
        error = errno;
    }
    if (::close(m.fd) != 0 && ok) {
        ok = false;
        error = errno;
    }
    m.fd = -1;
    if (ok && ::rename(m.temporary.c_str(), m.target.c_str()) != 0) {
        ok = false;
        error = errno;
    }
    if (!ok) {
        throw std::runtime_error("writing " + quoted(mPath) + " failed (" +
                                 std::strerror(error ? error : EIO) +
                                 "); the file was left as it was");
    }
    m.committed = true;
}

TextOutput::TextOutput(const fs::path& path)
    : mFile(path.empty() ? nullptr : std::make_unique<AtomicOutputFile>(path)),
      mOut(mFile ? &mFile->stream() : &std::cout) {}

void TextOutput::afterRow() {
    if (mText.size() > (std::size_t{1} << 20)) {
        mOut->write(mText.data(), static_cast<std::streamsize>(mText.size()));
        mText.clear();
    }
}

void TextOutput::finish() {
    mOut->write(mText.data(), static_cast<std::streamsize>(mText.size()));
    mText.clear();
    if (mFile) {
        mFile->commit(); // checks the stream, names the file
        return;
    }
    mOut->flush();
    if (!*mOut) {
        throw std::runtime_error("writing to standard output failed");
    }
}

void writeFileAtomically(const fs::path& path, std::string_view content) {
    AtomicOutputFile file(path);
    file.stream().write(content.data(), static_cast<std::streamsize>(content.size()));
    file.commit();
}

void checkOutputFile(const fs::path& path, std::string_view option) {
    if (path.empty()) {
        return;
    }
    const std::string what = std::string(option) + " " + quoted(path);
    const fs::path target = resolveTarget(path);
    refuseNonFile(target, what);
    std::error_code ec;
    const fs::path folder = folderOf(target);
    if (!fs::exists(folder, ec)) {
        throw InputError(what + ": the folder " + quoted(folder) +
                         " does not exist; create it first");
    }
    if (!fs::is_directory(folder, ec)) {
        throw InputError(what + ": " + quoted(folder) + " is not a folder");
    }
    if (::access(folder.c_str(), W_OK | X_OK) != 0) {
        throw InputError(what + ": the folder " + quoted(folder) + " is not writable (" +
                         std::strerror(errno) + ")");
    }
}

void checkOutputKind(const fs::path& path, std::string_view option) {
    if (!path.empty()) {
        refuseNonFile(path, std::string(option) + " " + quoted(path));
    }
}

void checkOutputFolder(const fs::path& dir, std::string_view option) {
    if (dir.empty()) {
        return;
    }
    const std::string what = std::string(option) + " " + quoted(dir);
    std::error_code ec;
    fs::path existing = dir;
    while (!fs::exists(existing, ec) && existing.has_parent_path() &&
           existing.parent_path() != existing) {
        existing = existing.parent_path();
    }
    if (!fs::exists(existing, ec)) {
        existing = ".";
    }
    if (!fs::is_directory(existing, ec)) {
        throw InputError(what + ": " + quoted(existing) +
                         (existing == dir ? " exists and is not a folder"
                                          : " is not a folder, so the folder cannot be made"));
    }
    if (::access(existing.c_str(), W_OK | X_OK) != 0) {
        throw InputError(what + ": the folder " + quoted(existing) + " is not writable (" +
                         std::strerror(errno) + ")");
    }
}

bool sameFile(const fs::path& a, const fs::path& b) {
    if (a.empty() || b.empty()) {
        return false;
    }
    std::error_code ec;
    if (fs::exists(a, ec) && fs::exists(b, ec)) {
        const bool same = fs::equivalent(a, b, ec);
        return !ec && same;
    }
    return resolved(a) == resolved(b);
}

void refuseSameFile(const fs::path& output, std::string_view outOption, const fs::path& input,
                    std::string_view inWhat) {
    if (sameFile(output, input)) {
        throw InputError(std::string(outOption) + " " + quoted(output) + " is the same file as " +
                         std::string(inWhat) + " " + quoted(input) +
                         "; an input is never overwritten: write the output somewhere else");
    }
}

} // namespace hapto
