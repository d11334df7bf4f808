#include "quadtree/MapFile.h"

#include "quadtree/PifsCodec.h"

#include "core/MappedCopy.h"
#include "core/Memory.h"
#include "quadtree/TextureCodec.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstring>

namespace terrain {

namespace {

class FileHandle {
public:
    explicit FileHandle(int fd) : mFd(fd) {}
    FileHandle(const FileHandle&) = delete;
    FileHandle& operator=(const FileHandle&) = delete;
    ~FileHandle()
    {
        if (mFd >= 0) {
            ::close(mFd);
        }
    }
    int get() const { return mFd; }
    int release() { return std::exchange(mFd, -1); }

private:
    int mFd;
};

/// Reads exactly `size` bytes at `offset`. Errors say what went wrong; callers prefix the file (and node).
Status preadAll(int fd, std::uint64_t offset, std::size_t size, std::uint8_t* out)
{
    std::size_t done = 0;
    while (done < size) {
        ssize_t n = ::pread(fd, out + done, size - done, static_cast<off_t>(offset + done));
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n < 0) {
            return makeError("read error: ", std::strerror(errno));
        }
        if (n == 0) {
            return makeError("file is truncated (read past its end at offset ", offset + done, ")");
        }
        done += static_cast<std::size_t>(n);
    }
    return {};
}

/// preadAll with the file named in the message.
Status preadAll(int fd, std::uint64_t offset, std::size_t size, std::uint8_t* out, const std::string& name)
{
    auto status = preadAll(fd, offset, size, out);
    if (!status.ok()) {
        return makeError(name, ": ", status.error().message);
    }
    return {};
}

class StreamMapFile final : public MapFile {
public:
    StreamMapFile(std::string name, MapHeader header, std::vector<DirectoryEntry> directory, int fd)
        : MapFile(std::move(name), std::move(header), std::move(directory)), mFd(fd)
    {
    }
    ~StreamMapFile() override { ::close(mFd); }

protected:
    Status readBytes(std::uint64_t offset, std::size_t size, std::uint8_t* out) const override
    {
        return preadAll(mFd, offset, size, out);
    }

private:
    int mFd;
};

class MappedMapFile final : public MapFile {
public:
    MappedMapFile(std::string name, MapHeader header, std::vector<DirectoryEntry> directory, int fd, void* data,
                  std::size_t size)
        : MapFile(std::move(name), std::move(header), std::move(directory)), mFd(fd), mData(data), mSize(size)
    {
    }
    ~MappedMapFile() override
    {
        ::munmap(mData, mSize);
        ::close(mFd);
    }

protected:
    Status readBytes(std::uint64_t offset, std::size_t size, std::uint8_t* out) const override
    {
        if (offset + size > mSize) {
            return makeError("file is truncated (read past its end at offset ", offset, ")");
        }
        // Another process may have truncated the file since it was mapped (prep replaces a map by renaming
        // a new file over it, which leaves this one whole; `truncate`, or copying over it in place, do not).
        // Touching a page past the new end raises SIGBUS. The size check gives the usual case a plain
        // message; a truncation between it and the copy (MapFaultTest hits that window within a second of
        // trying) is caught by copyFromMapping. Bytes changed in place are not detected here: the payload's
        // CRC catches them.
        struct stat info {};
        if (::fstat(mFd, &info) != 0) {
            return makeError("cannot read the file's size: ", std::strerror(errno));
        }
        const auto current = static_cast<std::uint64_t>(info.st_size);
        if (offset + size > current) {
            return makeError("file is truncated: it is now ", current, " bytes (", mSize,
                             " when opened), this read needs bytes ", offset, " to ", offset + size);
        }
        return copyFromMapping(out, static_cast<const std::uint8_t*>(mData) + offset, size);
    }

private:
    int mFd;  ///< kept open for fstat: the mapping's size is the file's size at open
    void* mData;
    std::size_t mSize;
};

}  // namespace

Expected<ReaderKind> parseReaderKind(const std::string& text)
{
    if (text == "stream") {
        return ReaderKind::Stream;
    }
    if (text == "memory_mapped") {
        return ReaderKind::MemoryMapped;
    }
    return makeError("reader '", text, "' is not one of: stream, memory_mapped");
}

MapFile::MapFile(std::string name, MapHeader header, std::vector<DirectoryEntry> directory)
    : mName(std::move(name)), mHeader(std::move(header)), mWindow(mHeader), mDirectory(std::move(directory))
{
}

Expected<std::unique_ptr<MapFile>> MapFile::open(const std::filesystem::path& path, ReaderKind kind)
{
    const std::string name = path.string();
    FileHandle fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (fd.get() < 0) {
        return makeError(name, ": cannot open map: ", std::strerror(errno));
    }
    struct stat info {};
    if (::fstat(fd.get(), &info) != 0 || !S_ISREG(info.st_mode)) {
        return makeError(name, ": not a regular file");
    }
    const auto fileSize = static_cast<std::uint64_t>(info.st_size);
    std::vector<std::uint8_t> headerBytes(std::min<std::uint64_t>(fileSize, kHeaderBytes));
    TERRAIN_TRY(preadAll(fd.get(), 0, headerBytes.size(), headerBytes.data(), name));
    auto header = decodeHeader(headerBytes, name);
    TERRAIN_TRY(header);
    if (header->detailRecipeBytes > 0) {
        if (fileSize < header->nodeAreaOffset()) {
            return makeError(name, ": file is ", fileSize, " bytes, shorter than its header and detail recipe");
        }
        std::vector<std::uint8_t> recipeBytes(header->detailRecipeBytes);
        TERRAIN_TRY(preadAll(fd.get(), kHeaderBytes, recipeBytes.size(), recipeBytes.data(), name));
        TERRAIN_TRY(decodeDetailRecipe(recipeBytes, *header, name));
    }
    if (header->roughnessBytes > 0) {
        if (fileSize < header->nodeAreaOffset()) {
            return makeError(name, ": file is ", fileSize, " bytes, shorter than its header and roughness block");
        }
        std::vector<std::uint8_t> roughnessBytes(header->roughnessBytes);
        TERRAIN_TRY(preadAll(fd.get(), header->roughnessOffset(), roughnessBytes.size(), roughnessBytes.data(), name));
        TERRAIN_TRY(decodeRoughness(roughnessBytes, *header, name));
    }
    if (header->georeferenceBytes > 0) {
        if (fileSize < header->nodeAreaOffset()) {
            return makeError(name, ": file is ", fileSize, " bytes, shorter than its header and georeference block");
        }
        std::vector<std::uint8_t> bytes(header->georeferenceBytes);
        TERRAIN_TRY(preadAll(fd.get(), header->georeferenceOffset(), bytes.size(), bytes.data(), name));
        TERRAIN_TRY(decodeGeoreference(bytes, *header, name));
    }
    if (header->directoryOffset + header->directoryBytes != fileSize) {
        return makeError(name, ": file is ", fileSize, " bytes but its directory of ", header->nodeCount,
                         " nodes ends at byte ", header->directoryOffset + header->directoryBytes,
                         " (truncated or extended)");
    }
    // The directory as read and as decoded, before allocating either.
    TERRAIN_TRY(checkAllocation(header->directoryBytes + std::uint64_t{header->nodeCount} * sizeof(DirectoryEntry),
                                name + ": the directory of " + std::to_string(header->nodeCount) + " nodes"));
    std::vector<std::uint8_t> directoryBytes(header->directoryBytes);
    TERRAIN_TRY(preadAll(fd.get(), header->directoryOffset, directoryBytes.size(), directoryBytes.data(), name));
    auto directory = decodeDirectory(directoryBytes, *header, name);
    TERRAIN_TRY(directory);

    if (kind == ReaderKind::MemoryMapped) {
        void* data = ::mmap(nullptr, fileSize, PROT_READ, MAP_SHARED, fd.get(), 0);
        if (data == MAP_FAILED) {
            return makeError(name, ": cannot memory-map: ", std::strerror(errno));
        }
        return std::unique_ptr<MapFile>(new MappedMapFile(name, std::move(header.value()), std::move(directory.value()),
                                                          fd.release(), data, fileSize));
    }
    return std::unique_ptr<MapFile>(
        new StreamMapFile(name, std::move(header.value()), std::move(directory.value()), fd.release()));
}

const DirectoryEntry* MapFile::find(const NodeId& id) const
{
    auto it = std::lower_bound(mDirectory.begin(), mDirectory.end(), id.key(),
                               [](const DirectoryEntry& e, std::uint64_t key) { return e.id.key() < key; });
    return it != mDirectory.end() && it->id == id ? &*it : nullptr;
}

Expected<std::vector<std::uint8_t>> MapFile::readPayload(const DirectoryEntry& entry) const
{
    std::vector<std::uint8_t> payload(entry.payloadBytes());
    auto read = readBytes(entry.offset, payload.size(), payload.data());
    if (!read.ok()) {
        return makeError(mName, ": node ", entry.id.toString(), ": ", read.error().message);
    }
    std::uint32_t crc = crc32Of(payload);
    if (crc != entry.crc) {
        return makeError(mName, ": node ", entry.id.toString(), ": checksum mismatch (stored ", entry.crc,
                         ", computed ", crc, "): the file is corrupt");
    }
    return payload;
}

Expected<StaticNode> MapFile::loadNode(const NodeId& id, std::span<const std::uint16_t> parentHeights) const
{
    const DirectoryEntry* entry = find(id);
    if (!entry) {
        return makeError(mName, ": node ", id.toString(), " is not in the map");
    }
    auto payload = readPayload(*entry);
    TERRAIN_TRY(payload);
    StaticNode node;
    node.id = id;
    node.heights.resize(mWindow.sampleCount());
    node.texture.resize(std::size_t{mHeader.textureSize} * mHeader.textureSize * 3);
    std::span<const std::uint8_t> bytes = payload.value();
    auto status = mHeader.heightCoding == kHeightCodingPifs
                      ? decodePifsHeights(mWindow, id, bytes.first(entry->heightBytes), parentHeights, node.heights)
                      : decodeNodeHeights(mWindow, id, bytes.first(entry->heightBytes), parentHeights,
                                          mHeader.quantizerBin, node.heights);
    if (!status.ok()) {
        return makeError(mName, ": node ", id.toString(), ": ", status.error().message);
    }
    status = decodeTexture(bytes.subspan(entry->heightBytes), static_cast<int>(mHeader.textureSize), node.texture);
    if (!status.ok()) {
        return makeError(mName, ": node ", id.toString(), ": ", status.error().message);
    }
    return node;
}

Expected<StaticNode> MapFile::loadPath(const NodeId& id) const
{
    auto node = loadNode(NodeId::root(), {});
    TERRAIN_TRY(node);
    for (int level = 1; level <= id.level; ++level) {
        NodeId step{level, id.x >> (id.level - level), id.y >> (id.level - level)};
        auto child = loadNode(step, node->heights);
        TERRAIN_TRY(child);
        node = std::move(child);
    }
    return node;
}

}  // namespace terrain
