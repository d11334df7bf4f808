// Resident quadtree nodes as the runtime holds them (paper 3.2.14-3.2.15, 3.4.1): immutable once built,
// shared between the cache (render thread) and the workers that decode or synthesize children from them.
#pragma once

#include "core/Expected.h"
#include "light/Horizon.h"
#include "lod/BlockErrors.h"
#include "quadtree/NodeId.h"
#include "synthesis/DualHeightMap.h"

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

namespace terrain {

struct NodeData {
    NodeId id;
    bool isStatic = true;            ///< read from the map; false: synthesized (a dynamic node, 3.4)
    bool hasChildren = false;        ///< children can be loaded or synthesized (and are wanted: see the source)
    bool hasStaticChildren = false;  ///< the children are in the map (else they would be dynamic)
    float deltaC = 0.0f;             ///< nested error, metres (eq. 3.1; 3.4.1 for dynamic nodes)
    double zMin = 0.0;               ///< nested bounding box, absolute metres (3.2.12)
    double zMax = 0.0;
    double spacing = 0.0;                       ///< metres between the node's samples
    std::vector<std::uint16_t> codes;           ///< static nodes: the window of height codes the map's children
                                                ///< are predicted from; empty for dynamic nodes
    DualHeightMap heights;                      ///< base + displacement, (N + 4)^2, metres above the map's offset
    std::vector<std::uint8_t> materialWeights;  ///< N x N x 4 material weights (DetailSynthesizer), or empty
    std::vector<std::uint8_t> texture;          ///< T x T RGB, rows south to north: the ground colours drawn
    /// The map's colours under `texture` before the materials' cover (synthesis coverTexture): what a dynamic
    /// child's colours are upsampled from; kept only by nodes whose children are synthesized, and empty where
    /// there is no cover (texture is then the map's).
    std::vector<std::uint8_t> mapTexture;
    const std::vector<std::uint8_t>& uncoveredTexture() const { return mapTexture.empty() ? texture : mapTexture; }
    /// The normal map of the surface below the node (synthesis/NormalMap.h): normalMapTexels^2 pairs (x, y)
    /// as GL_RG8_SNORM, rows south to north; empty when normal maps are off (DetailPolicy::normalMapSize 0).
    std::vector<std::int8_t> normalMap;
    /// The same normal map as RGTC2 blocks (lod/NodeTextures.h, compressRgtc2) where the source keeps them so
    /// (DetailPolicy::compressNormalMaps); normalMap is then empty.
    std::vector<std::uint8_t> normalMapBlocks;
    /// The horizons of the node's surface at a lattice of its samples (lod/NodeHorizons.h) and its parent's
    /// over the node's square (latticeQuadrant; the node's own, halved, for the root), for the shadows and sky
    /// visibility the renderer draws; size 0 where the source makes no horizons (DetailPolicy::horizonGrid null).
    HorizonLattice horizons;
    HorizonLattice parentHorizons;
    /// The tessellation render mode's block errors of the drawn surface (base plus displacement), made with
    /// the node when that mode is on (DetailPolicy::tessellationBlockQuads); null otherwise.
    std::shared_ptr<const TessellationErrors> tessellation;
};

using NodePtr = std::shared_ptr<const NodeData>;
using ChildNodes = std::array<NodePtr, 4>;

/// A node's resident data (the streamer's cache: TerrainStreamer::node), null when it is not resident.
using ResidentNodeLookup = std::function<NodePtr(const NodeId&)>;

/// Where nodes come from: the map (static) and synthesis (dynamic).
class NodeSource {
public:
    virtual ~NodeSource() = default;
    virtual Expected<NodePtr> loadRoot() = 0;
    /// The four children of `parent` in NodeId::child() order. Called on worker threads, concurrently:
    /// implementations must be thread-safe, and the result must not depend on the thread or the order of
    /// calls. Errors name the file and node.
    virtual Expected<ChildNodes> loadChildren(const NodeData& parent) = 0;
};

}  // namespace terrain
