// Reading .map files (paper 3.2.14; Appendix A `reader = stream | memory_mapped`): the header and directory
// at open, node payloads on demand from any thread.
#pragma once

#include "core/Expected.h"
#include "quadtree/HeightCodec.h"
#include "quadtree/MapFormat.h"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace terrain {

/// How node payloads are read: pread() per node, or from one read-only mapping of the whole file.
enum class ReaderKind { Stream, MemoryMapped };

/// Parses "stream" or "memory_mapped".
Expected<ReaderKind> parseReaderKind(const std::string& text);

/// A static node decoded: its heights window (codes, W x W, rows south to north, borders included) and
/// its texture (T x T RGB, rows south to north).
struct StaticNode {
    NodeId id;
    std::vector<std::uint16_t> heights;
    std::vector<std::uint8_t> texture;
};

class MapFile {
public:
    /// Opens and validates header and directory (structure and checksums). Errors name the file.
    static Expected<std::unique_ptr<MapFile>> open(const std::filesystem::path& path, ReaderKind kind);
    virtual ~MapFile() = default;

    const MapHeader& header() const { return mHeader; }
    const NodeWindow& window() const { return mWindow; }
    /// All static nodes, sorted by NodeId::key().
    std::span<const DirectoryEntry> directory() const { return mDirectory; }
    /// The entry of a static node, or null when the map has no such node.
    const DirectoryEntry* find(const NodeId& id) const;
    const std::string& name() const { return mName; }

    /// Reads a node's payload and checks its CRC. Errors name the file and the node: a checksum mismatch,
    /// or a file truncated since it was opened. Safe to call from several threads at once.
    Expected<std::vector<std::uint8_t>> readPayload(const DirectoryEntry& entry) const;

    /// Reads and decodes a node. `parentHeights` is the parent's decoded window (empty for the root).
    /// Errors name the file and the node. Safe to call from several threads at once.
    Expected<StaticNode> loadNode(const NodeId& id, std::span<const std::uint16_t> parentHeights) const;

    /// Decodes the root and then each node on the path down to `id`, returning `id`.
    Expected<StaticNode> loadPath(const NodeId& id) const;

protected:
    MapFile(std::string name, MapHeader header, std::vector<DirectoryEntry> directory);
    /// Reads `size` bytes at `offset` into `out`. Errors say what went wrong (e.g. the file is now shorter);
    /// readPayload prefixes the file and node. Must not crash when the file shrinks while open.
    virtual Status readBytes(std::uint64_t offset, std::size_t size, std::uint8_t* out) const = 0;

private:
    std::string mName;
    MapHeader mHeader;
    NodeWindow mWindow;
    std::vector<DirectoryEntry> mDirectory;
};

}  // namespace terrain
