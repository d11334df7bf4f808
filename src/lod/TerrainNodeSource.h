// Where the runtime's nodes come from (paper 3.2.14, 3.4.3 "Creation of Dynamic Nodes", 4.2.4): static
// nodes are read and decoded from the .map; below the static leaves, dynamic nodes are synthesized from
// their parent (subdivision + material displacement, synthesis/DetailSynthesizer.h). Both get the
// material displacement, so a static leaf and its dynamic children nest exactly.
#pragma once

#include "light/Horizon.h"
#include "lod/NodeData.h"
#include "quadtree/MapFile.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/DetailSynthesizer.h"

#include <memory>

namespace terrain {

/// How far synthesis goes.
struct DetailPolicy {
    /// The synthesizer (detail_create_new_nodes on); null: the static map as stored, nothing synthesized.
    /// Needs a map with detail errors (MapHeader::hasDetailErrors) for the selection to refine below the
    /// static leaves. Must outlive the source.
    const DetailSynthesizer* synthesizer = nullptr;
    /// lod_minimum_spacing: no node, static or dynamic, with a sample spacing below this (metres, >= 0).
    double minimumSpacing = 0.0;
    /// > 0: every node gets its tessellation errors (NodeData::tessellation) for blocks of this many quads a
    /// side (render_mode = tessellation), made on the loading thread with the node.
    int tessellationBlockQuads = 0;
    /// dynamic_texture_size: > 0, every node gets a normal map of the surface below it (NodeData::normalMap,
    /// synthesis/NormalMap.h) of normalMapTexels(normalMapSize) texels a side, made on the loading thread
    /// with the node; 0: none (the renderer lights by vertex normals).
    int normalMapSize = 0;
    /// Whether dynamic nodes get their error bound (DetailErrorModel::boundFromChildren: the node's four
    /// children synthesized and measured, with the node). false: a source of reference surfaces that needs
    /// heights only (the error meter's, height queries), whose dynamic nodes carry their parent's delta_c /
    /// kErrorNesting, which bounds nothing; it saves the children's syntheses where no normal map shares them.
    bool bounds = true;
    /// The normal maps kept as RGTC2 blocks (NodeData::normalMapBlocks, lod/NodeTextures.h: half the bytes,
    /// what the renderer's compressed pools take as they are) instead of RG8 texels (NodeData::normalMap).
    bool compressNormalMaps = false;
    /// Non-null: every node gets the horizons of its surface over this grid (NodeData::horizons,
    /// lod/NodeHorizons.h; staticHeightGrid of the map), made on the loading thread with the node, searched with
    /// `horizonOptions`. Null: none (no shadows).
    std::shared_ptr<const HeightGrid> horizonGrid = nullptr;
    HorizonOptions horizonOptions{16, 20000.0, 0.2};
};

class TerrainNodeSource final : public NodeSource {
public:
    /// `map` must outlive the source. Precondition: the synthesizer's chunk size is the map's.
    TerrainNodeSource(const MapFile& map, DetailPolicy policy);

    Expected<NodePtr> loadRoot() override;
    /// Static children from the map, or four dynamic children of a static leaf or dynamic node. Fails
    /// (naming the node) for a node without children.
    Expected<ChildNodes> loadChildren(const NodeData& parent) override;

    /// Where a node's window lies in the world (windowPlacement, synthesis/DetailSynthesizer.h).
    WindowPlacement placement(const NodeId& id) const;
    /// The most the displacement moves the surface, metres (the bounding boxes grow by it).
    double displacementBound() const { return mDisplacementBound; }
    /// The model of a dynamic node's error (synthesis/DetailErrorModel.h); null without a synthesizer.
    const DetailErrorModel* errorModel() const { return mErrorModel.get(); }

private:
    Expected<NodePtr> loadStatic(const NodeId& id, const NodeData* parent) const;
    NodePtr synthesize(const NodeData& parent, int quadrant) const;
    bool childrenAllowed(const NodeId& id, bool hasStaticChildren) const;
    void addTessellationErrors(NodeData& data) const;
    /// The materials' cover over data.texture (synthesis coverTexture), the map's colours kept in mapTexture.
    void addCover(NodeData& data) const;
    void addNormalMap(NodeData& data, const WindowPlacement& where) const;
    /// NodeData::horizons of `data` at `where` and its parent's over its square (DetailPolicy::horizonGrid).
    void addHorizons(NodeData& data, const WindowPlacement& where, const NodeData* parent) const;
    /// Puts `map` into data.normalMap, or into data.normalMapBlocks as RGTC2 (DetailPolicy::compressNormalMaps).
    void keepNormalMap(NodeData& data, std::vector<std::int8_t> map) const;

    const MapFile& mMap;
    DetailPolicy mPolicy;
    double mDisplacementBound = 0.0;
    std::unique_ptr<const DetailErrorModel> mErrorModel;
    /// Makes the levels below for the normal maps without detail synthesis: subdivision alone.
    std::unique_ptr<const DetailSynthesizer> mSubdivisionOnly;
};

}  // namespace terrain
