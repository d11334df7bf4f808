#include "core/ScratchMapping.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

namespace terrain {

Expected<ScratchMapping> ScratchMapping::create(const std::filesystem::path& directory, std::uint64_t bytes)
{
    const std::filesystem::path dir = directory.empty() ? std::filesystem::path(".") : directory;
    int fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd < 0 && (errno == EOPNOTSUPP || errno == EISDIR || errno == EINVAL)) {
        // A file system without O_TMPFILE: a named file, unlinked before it is used.
        std::string pattern = (dir / ".prep-scratch-XXXXXX").string();
        fd = ::mkstemp(pattern.data());
        if (fd >= 0) {
            ::unlink(pattern.c_str());
        }
    }
    if (fd < 0) {
        return makeError(dir.string(), ": cannot create a scratch file there: ", std::strerror(errno));
    }
    if (bytes == 0) {
        bytes = 1;
    }
    if (::ftruncate(fd, static_cast<off_t>(bytes)) != 0) {
        const int error = errno;
        ::close(fd);
        return makeError(dir.string(), ": cannot size a scratch file of ", bytes, " bytes: ", std::strerror(error));
    }
    // Reserved now: a sparse file would take its blocks at the first write to each page, and a full disk
    // then kills the process with SIGBUS instead of an error.
    if (const int reserved = ::posix_fallocate(fd, 0, static_cast<off_t>(bytes)); reserved != 0) {
        ::close(fd);
        return makeError(dir.string(), ": cannot reserve a scratch file of ", bytes,
                         " bytes: ", std::strerror(reserved),
                         reserved == ENOSPC ? " (the disk is full: free space there, or give more --memory)" : "");
    }
    void* data = ::mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    const int error = errno;
    ::close(fd);  // the mapping keeps the file
    if (data == MAP_FAILED) {
        return makeError(dir.string(), ": cannot map a scratch file of ", bytes, " bytes: ", std::strerror(error));
    }
    // Small pages: without this the page cache gives the file large folios (2 MiB on ext4 with Linux 6.x),
    // and one touch maps a whole folio, so reading a node's samples at a coarse stride, or a subtree's
    // border, would make megabytes resident per sample and release() could not give them back by region.
    // Random access also turns off read-ahead, which a pass re-reading released pages does not want.
    ::madvise(data, bytes, MADV_RANDOM);
    return ScratchMapping(data, bytes);
}

ScratchMapping::ScratchMapping(ScratchMapping&& other) noexcept
    : mData(std::exchange(other.mData, nullptr)), mSize(std::exchange(other.mSize, 0))
{
}

ScratchMapping& ScratchMapping::operator=(ScratchMapping&& other) noexcept
{
    if (this != &other) {
        if (mData) {
            ::munmap(mData, mSize);
        }
        mData = std::exchange(other.mData, nullptr);
        mSize = std::exchange(other.mSize, 0);
    }
    return *this;
}

ScratchMapping::~ScratchMapping()
{
    if (mData) {
        ::munmap(mData, mSize);
    }
}

void ScratchMapping::release(std::uint64_t offset, std::uint64_t bytes) const
{
    const auto page = static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
    const std::uint64_t end = std::min(offset + bytes, mSize);
    const std::uint64_t first = (offset + page - 1) / page * page;
    const std::uint64_t last = end / page * page;
    if (first < last) {
        ::madvise(static_cast<char*>(mData) + first, last - first, MADV_DONTNEED);
    }
}

}  // namespace terrain
