// The node cache's capacity from the viewer's options: a count (quad_cache_size) or a memory budget
// (memory_budget, lod/NodeMemory.h), shared by the viewer and tengine-tool error so both hold the same nodes.
#pragma once

#include "apps/TengineOptions.h"
#include "lod/NodeMemory.h"
#include "synthesis/Material.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace terrain {

struct CacheChoice {
    std::size_t nodes = 0;
    /// What memory_budget leaves the nodes' CPU data once the GPU's slots are paid (StreamerOptions::cacheBytes);
    /// SIZE_MAX with quad_cache_size (a count alone).
    std::size_t cpuBytes = SIZE_MAX;
    std::string description;  ///< one log line: how the capacity was chosen
};

/// The most slots where no context can be asked (tengine-tool): the node pools' kMaxPoolArrays arrays of
/// OpenGL 4.5's least GL_MAX_ARRAY_TEXTURE_LAYERS (what llvmpipe and common GPUs have).
inline constexpr std::size_t kSlotsWithoutContext = 2048 * kMaxPoolArrays;

/// quad_cache_size when it is set (> 0); else as many nodes as memory_budget pays for (0: the machine's
/// defaultMemoryBudget), each costing its GPU slot in the pools `o` asks for (none in clipmap mode; DXT1 colour
/// only where `s3tc`; RGTC2 normal maps where `compressNormals`) plus `nodeBytes` CPU bytes (a typical node's),
/// at most `maxNodes` (what the node pools hold: TerrainRenderer::maxSlots), and the budget less the slots for
/// the nodes' CPU bytes (nodes larger than `nodeBytes` leave slots empty; the budget holds either way).
CacheChoice chooseCacheSize(const TengineOptions& o, const MapHeader& header, const MaterialSet* materials, bool s3tc,
                            bool compressNormals, std::size_t nodeBytes, std::size_t maxNodes);

/// Whether normal maps are RGTC2 (normal_map_compression): On, or Auto on a GL that does not rasterize in
/// `software`.
bool compressNormalMaps(const TengineOptions& o, bool software);

}  // namespace terrain
