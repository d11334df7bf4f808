#include "core/AtomicFile.h"

#include <fcntl.h>
#include <pthread.h>
#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>

namespace terrain {

std::filesystem::path temporaryOutputName(const std::filesystem::path& path, std::string_view extension)
{
    // Unique per process and per call, so concurrent writers of different outputs never collide.
    static std::atomic<unsigned> counter{0};
    const std::string suffix =
        ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + std::string(extension);
    // Within the longest name a directory entry may have, however long the output's own name is.
    std::string base = path.filename().string();
    base.resize(std::min(base.size(), kMaxFileNameBytes - suffix.size()));
    return path.parent_path() / (base + suffix);
}

Status checkOutputPath(const std::filesystem::path& path)
{
    const std::string name = path.filename().string();
    if (name.empty() || name == "." || name == "..") {
        return makeError(path.string(), ": cannot create output file: no file name (give one)");
    }
    if (name.size() > kMaxFileNameBytes) {
        return makeError(path.string(), ": cannot create output file: its name is ", name.size(),
                         " bytes long, more than the ", kMaxFileNameBytes, " a file name may have");
    }
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) {
        return makeError(path.string(), ": cannot create output file: it is a directory (give a file name in it)");
    }
    const std::filesystem::path directory =
        path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
    if (!std::filesystem::is_directory(directory, ec)) {
        return makeError(path.string(), ": cannot create output file: the directory ", directory.string(),
                         " does not exist");
    }
    if (::access(directory.c_str(), W_OK | X_OK) != 0) {
        return makeError(path.string(), ": cannot create output file in ", directory.string(), ": ",
                         std::strerror(errno));
    }
    return {};
}

namespace {

/// strerror plus what the user can do about the errors a full disk or a size limit gives.
std::string describeWriteError(int error)
{
    std::string text = std::strerror(error);
    if (error == ENOSPC) {
        text += " (the disk is full: free some space or write the output elsewhere)";
    } else if (error == EDQUOT) {
        text += " (the disk quota is used up: free some space or write the output elsewhere)";
    } else if (error == EFBIG) {
        text += " (the file is larger than this process may write, see ulimit -f, or than the filesystem allows)";
    }
    return text;
}

/// Blocks the signals that ask a program to stop (Ctrl-C, kill, a closed terminal) in the calling thread
/// while alive, so a stop requested between naming the output and renaming it takes effect after the
/// rename instead of leaving the named temporary behind. SIGKILL cannot be blocked; that window stays (two
/// system calls wide), as does any other thread of the process that does not block these signals.
class StopSignalsDeferred {
public:
    StopSignalsDeferred()
    {
        sigset_t stop;
        sigemptyset(&stop);
        for (int signal : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) {
            sigaddset(&stop, signal);
        }
        mBlocked = ::pthread_sigmask(SIG_BLOCK, &stop, &mPrevious) == 0;
    }
    ~StopSignalsDeferred()
    {
        if (mBlocked) {
            ::pthread_sigmask(SIG_SETMASK, &mPrevious, nullptr);
        }
    }
    StopSignalsDeferred(const StopSignalsDeferred&) = delete;
    StopSignalsDeferred& operator=(const StopSignalsDeferred&) = delete;

private:
    sigset_t mPrevious{};
    bool mBlocked = false;
};
}  // namespace

AtomicFile::AtomicFile(std::FILE* file, std::filesystem::path path, std::filesystem::path temporaryPath)
    : mFile(file), mPath(std::move(path)), mTemporaryPath(std::move(temporaryPath))
{
}

Expected<AtomicFile> AtomicFile::create(const std::filesystem::path& path)
{
    // Preferably an unnamed file in the target directory (O_TMPFILE): if the process dies before commit,
    // even by SIGKILL, nothing at all is left behind. Filesystems without it get a named temporary.
    // What would only fail at the rename, after all the work: checked first.
    TERRAIN_TRY(checkOutputPath(path));
    auto directory = path.parent_path().empty() ? std::filesystem::path(".") : path.parent_path();
    int fd = ::open(directory.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0644);
    if (fd >= 0) {
        std::FILE* file = ::fdopen(fd, "wb");
        if (file) {
            return AtomicFile(file, path, {});
        }
        ::close(fd);
    }
    auto temporary = temporaryOutputName(path);
    std::FILE* file = std::fopen(temporary.c_str(), "wb");
    if (!file) {
        return makeError(path.string(), ": cannot create output file: ", std::strerror(errno));
    }
    return AtomicFile(file, path, std::move(temporary));
}

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : mFile(std::exchange(other.mFile, nullptr)),
      mPath(std::move(other.mPath)),
      mTemporaryPath(std::move(other.mTemporaryPath)),
      mSize(other.mSize),
      mErrno(other.mErrno)
{
}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept
{
    if (this != &other) {
        discard();
        mFile = std::exchange(other.mFile, nullptr);
        mPath = std::move(other.mPath);
        mTemporaryPath = std::move(other.mTemporaryPath);
        mSize = other.mSize;
        mErrno = other.mErrno;
    }
    return *this;
}

AtomicFile::~AtomicFile()
{
    discard();
}

void AtomicFile::discard()
{
    if (mFile) {
        std::fclose(mFile);
        mFile = nullptr;
        if (!mTemporaryPath.empty()) {
            std::error_code ignored;
            std::filesystem::remove(mTemporaryPath, ignored);
        }
    }
}

void AtomicFile::write(const void* data, std::size_t size)
{
    if (mErrno != 0 || size == 0) {
        return;
    }
    if (std::fwrite(data, 1, size, mFile) != size) {
        mErrno = errno ? errno : EIO;
    }
    mSize += size;
}

void AtomicFile::writeAt(std::uint64_t offset, const void* data, std::size_t size)
{
    if (mErrno != 0) {
        return;
    }
    if (std::fseek(mFile, static_cast<long>(offset), SEEK_SET) != 0 || std::fwrite(data, 1, size, mFile) != size ||
        std::fseek(mFile, 0, SEEK_END) != 0) {
        mErrno = errno ? errno : EIO;
    }
    mSize = std::max<std::uint64_t>(mSize, offset + size);
}

Status AtomicFile::commit()
{
    if (!mFile) {
        return makeError(mPath.string(), ": output already committed or discarded");
    }
    int error = mErrno;
    if (error == 0 && std::fflush(mFile) != 0) {
        error = errno;
    }
    if (error == 0 && ::fsync(::fileno(mFile)) != 0) {
        error = errno;
    }
    if (error != 0) {
        discard();
        return makeError(mPath.string(), ": write failed: ", describeWriteError(error));
    }
    const StopSignalsDeferred deferred;
    if (mTemporaryPath.empty()) {
        // Give the unnamed file a name next to the target, then rename that over the target (linkat
        // cannot replace an existing file).
        auto temporary = temporaryOutputName(mPath);
        auto procPath = "/proc/self/fd/" + std::to_string(::fileno(mFile));
        if (::linkat(AT_FDCWD, procPath.c_str(), AT_FDCWD, temporary.c_str(), AT_SYMLINK_FOLLOW) != 0) {
            int linkError = errno;
            discard();
            return makeError(mPath.string(), ": cannot give the output a name: ", describeWriteError(linkError));
        }
        mTemporaryPath = temporary;
    }
    std::fclose(mFile);
    mFile = nullptr;
    std::error_code ec;
    std::filesystem::rename(mTemporaryPath, mPath, ec);
    if (ec) {
        std::error_code removed;  // its own: the rename's reason is the one to report
        std::filesystem::remove(mTemporaryPath, removed);
        return makeError(mPath.string(), ": cannot rename temporary output into place: ", ec.message());
    }
    return {};
}

Status writeFileAtomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes)
{
    auto file = AtomicFile::create(path);
    TERRAIN_TRY(file);
    file->write(bytes);
    return file->commit();
}

}  // namespace terrain
