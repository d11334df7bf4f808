// What a resident node costs, and how many nodes a memory budget holds (memory_budget): the node cache is
// sized by bytes, the GPU's slot and the node's CPU data together, rather than by a count of nodes.
#pragma once

#include "lod/NodeData.h"
#include "quadtree/MapFormat.h"

#include <cstddef>
#include <cstdint>

namespace terrain {

/// GPU bytes of one slot of the renderer's node pools (TerrainRenderer): what each resident node costs there.
struct SlotBytes {
    std::size_t heights = 0;    ///< the surface with a 1-sample border, 16 bits a sample
    std::size_t normals = 0;    ///< the parent's normals at its samples, 2 bytes each (without normal maps)
    std::size_t colour = 0;     ///< the colour texture (RGB8, or DXT1 with node_texture_compression; RGBA8 with
                                ///< shadows: the sun's visibility in alpha)
    std::size_t weights = 0;    ///< material weights (RGBA4), 0 without detail layers
    std::size_t normalMap = 0;  ///< the normal map of the surface below (RGTC2, or RG8), 0 without normal maps
    std::size_t light = 0;      ///< the sky's visibility, own and parent's (RG8 a sample), 0 without shadows
    std::size_t constants = 0;  ///< per drawn node, in the frame's constants buffer
    std::size_t total() const { return heights + normals + colour + weights + normalMap + light + constants; }
};

/// The most texture arrays each of the renderer's pools spreads its slots over: with 2048 layers an array
/// (GL_MAX_ARRAY_TEXTURE_LAYERS on llvmpipe and common GPUs) 32768 nodes. A frame is drawn in one call per
/// pair of arrays in use (a node's, its parent's).
inline constexpr std::size_t kMaxPoolArrays = 16;

/// The formats of the node pools that decide a slot's size.
struct PoolLayout {
    int normalMapTexels = 0;       ///< per side; 0: no normal maps (then the parent's normals)
    bool compressNormals = false;  ///< RGTC2 normal maps (1 byte a texel, padded to 4 x 4 blocks), else RG8
    bool dxt1 = false;             ///< DXT1 colour (half a byte a texel, padded to 4 x 4 blocks), else RGB8
    int detailLayers = 0;          ///< the materials' detail textures: > 0 adds the weights and their constants
    bool shadows = false;          ///< the sun's and sky's visibility at the samples (lod/NodeHorizons.h)
};
/// The slot of a node of `header`'s maps in pools of `layout` (no GL: the tool sizes caches with it too).
SlotBytes poolSlotBytes(const MapHeader& header, const PoolLayout& layout);

/// The CPU bytes `node` holds: the struct, its arrays' allocations (capacities, not sizes) and its
/// tessellation errors.
std::size_t residentBytes(const NodeData& node);

/// The budget when none is given (memory_budget = 0): 1/16 of the machine's physical memory, at least 128 MiB
/// and at most 4 GiB.
std::uint64_t defaultMemoryBudget(std::uint64_t physicalBytes);

/// The machine's physical memory in bytes (sysconf), or 0 when the system does not say.
std::uint64_t physicalMemoryBytes();

/// The node cache for a budget.
struct CacheSizing {
    std::size_t nodes = 0;           ///< the cache's capacity: budget / bytesPerNode, within [5, maxNodes]
    std::size_t bytesPerNode = 0;    ///< what one resident node costs (GPU slot plus CPU data)
    bool limitedByMaxNodes = false;  ///< the budget would hold more than maxNodes (what the GPU's pools hold)
    bool belowMinimum = false;       ///< the budget holds fewer than 5 nodes: the cache has 5 anyway
};
/// Precondition: bytesPerNode > 0, maxNodes >= 5.
CacheSizing sizeCache(std::uint64_t budgetBytes, std::size_t bytesPerNode, std::size_t maxNodes);

}  // namespace terrain
