#include "apps/NodeBudget.h"

#include "synthesis/NormalMap.h"

#include <algorithm>
#include <cstdio>

namespace terrain {

CacheChoice chooseCacheSize(const TengineOptions& o, const MapHeader& header, const MaterialSet* materials, bool s3tc,
                            bool compressNormals, std::size_t nodeBytes, std::size_t maxNodes)
{
    int detailLayers = 0;
    if (materials) {
        for (const Material& material : materials->materials()) {
            detailLayers += static_cast<int>(material.detailTextures.size());
        }
    }
    const int normalTexels = o.dynamicTextureSize > 0 ? normalMapTexels(o.dynamicTextureSize) : 0;
    const SlotBytes slot = o.clipmap
                               ? SlotBytes{}
                               : poolSlotBytes(header, {normalTexels, compressNormals, o.nodeTextureCompression && s3tc,
                                                        detailLayers, o.shadows});
    constexpr double kMiB = 1024.0 * 1024.0;
    auto kb = [](std::size_t bytes) { return static_cast<double>(bytes) / 1024.0; };
    const std::size_t perNode = std::max<std::size_t>(1, slot.total() + nodeBytes);
    char line[320];
    if (o.quadCacheSize > 0) {
        const auto nodes = static_cast<std::size_t>(o.quadCacheSize);
        std::snprintf(line, sizeof line,
                      "node cache: quad_cache_size %zu nodes of %.1f KB (GPU %.1f KB, CPU %.1f KB): %.0f MiB", nodes,
                      kb(perNode), kb(slot.total()), kb(nodeBytes),
                      static_cast<double>(nodes) * static_cast<double>(perNode) / kMiB);
        return {nodes, SIZE_MAX, line};
    }
    const bool machine = o.memoryBudget == 0;
    const std::uint64_t budget =
        machine ? defaultMemoryBudget(physicalMemoryBytes()) : static_cast<std::uint64_t>(o.memoryBudget) * 1024 * 1024;
    const CacheSizing s = sizeCache(budget, perNode, std::max<std::size_t>(maxNodes, 5));
    std::snprintf(line, sizeof line,
                  "node cache: memory_budget %.0f MiB%s holds %zu nodes of %.1f KB (GPU %.1f KB, CPU %.1f KB)%s",
                  static_cast<double>(budget) / kMiB, machine ? " (1/16 of this machine's memory)" : "", s.nodes,
                  kb(perNode), kb(slot.total()), kb(nodeBytes),
                  s.limitedByMaxNodes ? ", as many as the node pools hold"
                  : s.belowMinimum    ? ", the fewest the cache can work with (a node and its four children)"
                                      : "");
    if (s.belowMinimum) {
        return {s.nodes, SIZE_MAX, line};  // the fewest nodes the cache works with, whatever they cost
    }
    const std::uint64_t gpu = static_cast<std::uint64_t>(s.nodes) * slot.total();
    return {s.nodes, static_cast<std::size_t>(std::min<std::uint64_t>(budget - gpu, SIZE_MAX - 1)), line};
}

bool compressNormalMaps(const TengineOptions& o, bool software)
{
    return o.normalMapCompression == TengineOptions::Compression::On ||
           (o.normalMapCompression == TengineOptions::Compression::Auto && !software);
}

}  // namespace terrain
