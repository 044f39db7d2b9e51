#pragma once
/// Opening the files people name (scenes, device configurations, points, traces): regular
/// files only, of a bounded size, refused at once with a clear message otherwise.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace hapto {

/// The largest input file hapto reads by default (bytes): 4 GiB, about 2 * 10^7 scene objects
/// (a generated object is about 184 bytes of JSON). Larger files are refused before a byte is
/// read, so a huge file cannot exhaust memory.
inline constexpr std::uint64_t kMaxInputFileBytes = std::uint64_t(4) << 30;

/// An input file, opened and checked: a regular file (symbolic links followed) of at most
/// `maxBytes`. Directories, FIFOs and pipes (`/dev/fd/63` from a process substitution),
/// sockets and character or block devices (`/dev/zero`) are refused with an InputError such
/// as "PATH: is a FIFO, not a regular file", without blocking: the file is opened
/// non-blocking and checked on the open descriptor, so a path swapped after a check cannot
/// slip through. All [control].
class InputFile {
public:
    /// Opens and checks `path`; `what` names it in messages ("scene file"). Throws InputError
    /// naming the path and the reason (a path holding a NUL byte, which the system would cut
    /// there, is refused before anything is opened). [control]
    InputFile(const std::filesystem::path& path, std::string_view what,
              std::uint64_t maxBytes = kMaxInputFileBytes);
    ~InputFile();
    InputFile(const InputFile&) = delete;
    InputFile& operator=(const InputFile&) = delete;

    /// The size the file had when opened (bytes). [control]
    std::uint64_t size() const noexcept { return mSize; }
    /// The file's first `bytes` bytes (fewer when it is shorter), read without moving the
    /// position readAll() and releaseToStdio() start from: enough to refuse a file by its
    /// header and size before reading it whole. Throws InputError when reading fails.
    /// [control]
    std::string readHead(std::size_t bytes);
    /// Reads the whole file; throws InputError when reading fails or it has grown past the
    /// limit since it was opened. [control]
    std::string readAll();
    /// Hands the open file over as a stdio stream (the InputFile no longer owns it; the
    /// caller fcloses it). Throws InputError if that fails. [control]
    std::FILE* releaseToStdio();

private:
    std::string mPath;
    std::string mWhat;
    std::uint64_t mMaxBytes;
    std::uint64_t mSize = 0;
    int mFd = -1;
};

/// "a directory", "a FIFO", ...: what a path is when it is not a regular file, or "" when it is
/// one (or does not exist). [control]
std::string nonRegularKind(const std::filesystem::path& path);

} // namespace hapto
