// Output files that appear whole or not at all: written to an unnamed file in the target directory
// (O_TMPFILE; a named temporary where the filesystem lacks it), flushed, synced, then named and renamed
// over the final name. An interrupted or failed write leaves no partial file; with O_TMPFILE not even a
// temporary survives a killed process (SIGINT, SIGTERM, SIGHUP and SIGQUIT are held off in the committing
// thread between naming the file and renaming it; only SIGKILL in those two system calls can leave the
// name). A full disk or a file size limit is reported by commit() as such, naming the path.
#pragma once

#include "core/Expected.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string_view>

namespace terrain {

/// The longest name a directory entry may have (NAME_MAX on Linux file systems).
inline constexpr std::size_t kMaxFileNameBytes = 255;

/// Whether an output can be created at `path`, checked before any work is done for it: a file name of at most
/// kMaxFileNameBytes, not a directory, in an existing directory this process may write to. The error names
/// the path and what is wrong (the system's reason where it gives one).
Status checkOutputPath(const std::filesystem::path& path);

/// A temporary name beside `path` for writing it, unique per process and call, ending in `extension` (short),
/// within kMaxFileNameBytes however long the output's own name is.
std::filesystem::path temporaryOutputName(const std::filesystem::path& path, std::string_view extension = "");

class AtomicFile {
public:
    /// Opens the output for writing. Fails with a message naming the path.
    static Expected<AtomicFile> create(const std::filesystem::path& path);

    AtomicFile(AtomicFile&& other) noexcept;
    AtomicFile& operator=(AtomicFile&& other) noexcept;
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;
    /// Removes the temporary file unless commit() succeeded.
    ~AtomicFile();

    /// Appends bytes; errors are remembered and reported by commit().
    void write(const void* data, std::size_t size);
    void write(std::span<const std::uint8_t> bytes) { write(bytes.data(), bytes.size()); }
    /// Overwrites bytes at an absolute offset (e.g. a header patched after the body); errors reported by commit().
    void writeAt(std::uint64_t offset, const void* data, std::size_t size);
    /// Bytes written so far (the current end of file).
    std::uint64_t size() const { return mSize; }
    /// Flushes, syncs and renames to the final path. Fails with a message naming the path.
    Status commit();

    const std::filesystem::path& path() const { return mPath; }

private:
    AtomicFile(std::FILE* file, std::filesystem::path path, std::filesystem::path temporaryPath);
    void discard();

    std::FILE* mFile = nullptr;
    std::filesystem::path mPath;
    std::filesystem::path mTemporaryPath;
    std::uint64_t mSize = 0;
    int mErrno = 0;
};

/// Writes a whole buffer atomically.
Status writeFileAtomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

}  // namespace terrain
