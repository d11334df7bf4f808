// The node cache's capacity from the viewer's options: a count (quad_cache_size) or a memory budget
// (memory_budget, lod/NodeMemory.h), shared by the viewer and tengine-tool error so both hold the same nodes.
#pragma once

#include "apps/TengineOptions.h"
#include "lod/NodeMemory.h"
#include "synthesis/Material.h"

#include <cstddef>
#include <string>

namespace terrain {

struct CacheChoice {
    std::size_t nodes = 0;
    std::string description;  ///< one log line: how the capacity was chosen
};

/// The most slots where no context can be asked (tengine-tool): the node pools' kMaxPoolArrays arrays of
/// OpenGL 4.5's least GL_MAX_ARRAY_TEXTURE_LAYERS (what llvmpipe and common GPUs have).
inline constexpr std::size_t kSlotsWithoutContext = 2048 * kMaxPoolArrays;

/// quad_cache_size when it is set (> 0); else as many nodes as memory_budget pays for (0: the machine's
/// defaultMemoryBudget), each costing its GPU slot in the pools `o` asks for (none in clipmap mode; DXT1 colour
/// only where `s3tc`; RGTC2 normal maps where `compressNormals`) plus `nodeBytes` CPU bytes, at most
/// `maxNodes` (what the node pools hold: TerrainRenderer::maxSlots).
CacheChoice chooseCacheSize(const TengineOptions& o, const MapHeader& header, const MaterialSet* materials, bool s3tc,
                            bool compressNormals, std::size_t nodeBytes, std::size_t maxNodes);

/// Whether normal maps are RGTC2 (normal_map_compression): On, or Auto on a GL that does not rasterize in
/// `software`.
bool compressNormalMaps(const TengineOptions& o, bool software);

}  // namespace terrain
