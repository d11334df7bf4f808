#include "lod/NodeMemory.h"

#include "core/Check.h"

#include <unistd.h>

#include <algorithm>

namespace terrain {

namespace {

template <typename T>
std::size_t heapBytes(const std::vector<T>& v)
{
    return v.capacity() * sizeof(T);
}

}  // namespace

std::size_t residentBytes(const NodeData& node)
{
    std::size_t bytes = sizeof(NodeData) + heapBytes(node.codes) + heapBytes(node.heights.base) +
                        heapBytes(node.heights.displacement) + heapBytes(node.heights.slope) +
                        heapBytes(node.heights.curvature) + heapBytes(node.heights.weights) +
                        heapBytes(node.materialWeights) + heapBytes(node.texture) + heapBytes(node.mapTexture) +
                        heapBytes(node.normalMap) + heapBytes(node.normalMapBlocks) + heapBytes(node.horizons.codes) +
                        heapBytes(node.parentHorizons.codes);
    if (node.tessellation) {
        const TessellationErrors& t = *node.tessellation;
        bytes += sizeof(TessellationErrors) + heapBytes(t.blocks.lambda) + heapBytes(t.snap) + heapBytes(t.flip) +
                 heapBytes(t.top);
    }
    return bytes;
}

SlotBytes poolSlotBytes(const MapHeader& header, const PoolLayout& layout)
{
    TERRAIN_EXPECTS(layout.normalMapTexels >= 0 && layout.detailLayers >= 0, "counts are >= 0");
    const auto n = static_cast<std::size_t>(header.chunkSize), w = n + 2, m = (n + 1) / 2;
    const auto t = static_cast<std::size_t>(header.textureSize);
    auto blocks = [](std::size_t texels) { return (texels + 3) / 4 * 4; };  // 4 x 4 blocks (blockLayerSize)
    SlotBytes b;
    b.heights = w * w * sizeof(std::uint16_t);
    b.normals = layout.normalMapTexels == 0 ? m * m * 2 : 0;
    b.colour = layout.shadows ? t * t * 4 : (layout.dxt1 ? blocks(t) * blocks(t) / 2 : t * t * 3);
    b.weights = layout.detailLayers > 0 ? n * n * sizeof(std::uint16_t) : 0;
    b.light = layout.shadows ? n * n * 2 : 0;
    const auto texels = static_cast<std::size_t>(layout.normalMapTexels);
    b.normalMap = layout.compressNormals ? blocks(texels) * blocks(texels) : texels * texels * 2;
    b.constants = (3 + static_cast<std::size_t>(layout.detailLayers)) * 4 * sizeof(float);
    return b;
}

std::uint64_t defaultMemoryBudget(std::uint64_t physicalBytes)
{
    constexpr std::uint64_t kMiB = 1024 * 1024;
    return std::clamp<std::uint64_t>(physicalBytes / 16, 128 * kMiB, 4096 * kMiB);
}

std::uint64_t physicalMemoryBytes()
{
    const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGE_SIZE);
    return pages > 0 && size > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(size) : 0;
}

CacheSizing sizeCache(std::uint64_t budgetBytes, std::size_t bytesPerNode, std::size_t maxNodes)
{
    TERRAIN_EXPECTS(bytesPerNode > 0 && maxNodes >= 5, "a node costs something and the cache holds at least 5");
    CacheSizing s;
    s.bytesPerNode = bytesPerNode;
    const std::uint64_t fits = budgetBytes / bytesPerNode;
    s.limitedByMaxNodes = fits > maxNodes;
    s.belowMinimum = fits < 5;
    s.nodes = static_cast<std::size_t>(std::clamp<std::uint64_t>(fits, 5, maxNodes));
    return s;
}

}  // namespace terrain
