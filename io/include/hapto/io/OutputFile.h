#pragma once
/// Output files written whole or not at all, and the checks made on output paths before work.
///
/// Design note. Every file a command writes (`-o`, `--report`, experiment and soak outputs)
/// goes to a temporary file in the target's own folder (`<name>.tmp-XXXXXX`, created
/// exclusively, never through a symlink) and is renamed onto the target only once it is
/// complete and synced, so a failure or a kill leaves the old file as it was, never a half
/// file. The temporary is removed when anything fails before the rename. A target that is a
/// symlink is resolved first (the link stays, its file is replaced). A target that exists and
/// is not a regular file (a folder, a FIFO, a socket, a device such as /dev/null or a terminal)
/// is refused: it cannot be replaced, and opening a FIFO to write waits for a reader for ever.
/// Paths are only stat()ed, never opened, before the temporary is made. The checks run before
/// any work starts, so bad output paths are refused (InputError, exit code 2) instead of being
/// found after a long run.

#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>

namespace hapto {

/// One output file being written: a stream onto a temporary beside the target, renamed into
/// place by commit(). Destroyed without commit(), it removes the temporary. [control]
class AtomicOutputFile {
public:
    /// Creates the temporary. Throws InputError naming `path` when it is not a regular file
    /// (checkOutputKind) or its folder cannot take it.
    explicit AtomicOutputFile(const std::filesystem::path& path);
    /// Removes the temporary unless commit() succeeded.
    ~AtomicOutputFile();
    AtomicOutputFile(const AtomicOutputFile&) = delete;
    AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

    /// Where to write the contents.
    std::ostream& stream();
    /// Flushes and syncs the contents and renames them onto the target. Throws
    /// std::runtime_error (the temporary removed, the target untouched) when that fails.
    void commit();
    /// The target as given.
    const std::filesystem::path& path() const { return mPath; }

private:
    struct Impl;
    std::filesystem::path mPath;
    std::unique_ptr<Impl> mImpl;
};

/// Rows of text (CSV) written whole to a file through an AtomicOutputFile, or to standard
/// output when the path is empty. The caller appends rows to text(); the text is written out
/// each time it passes 1 MiB (afterRow()) and at finish(). [control]
class TextOutput {
public:
    /// Opens the output (see AtomicOutputFile); `path` empty: standard output.
    explicit TextOutput(const std::filesystem::path& path);
    /// The text not yet written: append rows here.
    std::string& text() noexcept { return mText; }
    /// Writes the text out once it holds more than 1 MiB; call after each row.
    void afterRow();
    /// Writes the rest and renames the file into place. Throws std::runtime_error naming the
    /// file, or standard output, when a write failed (the file is then left as it was).
    void finish();

private:
    std::unique_ptr<AtomicOutputFile> mFile;
    std::ostream* mOut;
    std::string mText;
};

/// Writes `content` to `path` through an AtomicOutputFile. Throws InputError when the folder
/// cannot take it, std::runtime_error when the write fails. [control]
void writeFileAtomically(const std::filesystem::path& path, std::string_view content);

/// Refuses (InputError naming `option` and `path`) an output path that exists and is not a
/// regular file once symlinks are followed: a folder, a FIFO, a socket, a character or block
/// device. A missing path passes. Only stat()s the path, so it never blocks. [control]
void checkOutputKind(const std::filesystem::path& path, std::string_view option);
/// Refuses (InputError naming `option`) an output file that cannot be written: what
/// checkOutputKind refuses, or a path whose folder does not exist or is not writable. Nothing
/// is created. [control]
void checkOutputFile(const std::filesystem::path& path, std::string_view option);
/// Refuses (InputError naming `option`) an output folder that cannot be used: an existing
/// non-folder, a folder not writable, or (when missing) a nearest existing parent that is not a
/// writable folder. Nothing is created. [control]
void checkOutputFolder(const std::filesystem::path& dir, std::string_view option);

/// True when `a` and `b` name the same file: the same inode when both exist (hard links and
/// symlinks included), else the same absolute path once resolved. [control]
bool sameFile(const std::filesystem::path& a, const std::filesystem::path& b);
/// Refuses (InputError) writing `output` (given with `outOption`) over the input `input`
/// (given as `inWhat`, e.g. "--scene"): an input is never overwritten. Empty paths pass.
void refuseSameFile(const std::filesystem::path& output, std::string_view outOption,
                    const std::filesystem::path& input, std::string_view inWhat);

} // namespace hapto
