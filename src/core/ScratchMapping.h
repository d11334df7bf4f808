// A scratch array too large for memory (prep's out-of-core build): an unnamed temporary file,
// mapped shared, so the kernel writes pages back to disk instead of holding them in the process. The file
// has no name (O_TMPFILE, else unlinked at once): nothing is left behind, even after a crash.
#pragma once

#include "core/Expected.h"

#include <cstddef>
#include <cstdint>
#include <filesystem>

namespace terrain {

class ScratchMapping {
public:
    /// A zero-filled mapping of `bytes` bytes backed by a temporary file in `directory`. Errors name the
    /// directory (not writable, no space for a sparse file of that size, the mapping refused).
    static Expected<ScratchMapping> create(const std::filesystem::path& directory, std::uint64_t bytes);

    ScratchMapping(ScratchMapping&& other) noexcept;
    ScratchMapping& operator=(ScratchMapping&& other) noexcept;
    ScratchMapping(const ScratchMapping&) = delete;
    ScratchMapping& operator=(const ScratchMapping&) = delete;
    ~ScratchMapping();

    void* data() const { return mData; }
    std::uint64_t size() const { return mSize; }

    /// Drops this process's resident pages wholly inside [offset, offset + bytes) (madvise DONTNEED): their
    /// contents stay in the file (and the kernel's page cache) and come back on the next touch. Safe while
    /// other threads read or write those pages; only resident memory changes.
    void release(std::uint64_t offset, std::uint64_t bytes) const;

private:
    ScratchMapping(void* data, std::uint64_t size) : mData(data), mSize(size) {}
    void* mData = nullptr;
    std::uint64_t mSize = 0;
};

}  // namespace terrain
