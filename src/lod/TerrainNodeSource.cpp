// Static and dynamic nodes (paper 3.2.14, 3.4.1, 3.4.3, 4.2.4).
#include "lod/TerrainNodeSource.h"

#include "lod/NodeTextures.h"

#include "core/Check.h"
#include "lod/NodeHorizons.h"
#include "synthesis/NormalMap.h"

#include <algorithm>
#include <cmath>

namespace terrain {

TerrainNodeSource::TerrainNodeSource(const MapFile& map, DetailPolicy policy) : mMap(map), mPolicy(policy)
{
    TERRAIN_EXPECTS(!policy.synthesizer || policy.synthesizer->chunkSize() == static_cast<int>(map.header().chunkSize),
                    "the synthesizer's chunk size must be the map's");
    TERRAIN_EXPECTS(policy.minimumSpacing >= 0.0, "lod_minimum_spacing must be >= 0");
    if (policy.synthesizer) {
        mDisplacementBound = policy.synthesizer->materialBound();
    }
    if (policy.synthesizer && policy.synthesizer->settings().roughness) {
        mDisplacementBound += policy.synthesizer->settings().roughness->bound(0);
    }
    if (policy.synthesizer) {
        mErrorModel = std::make_unique<const DetailErrorModel>(*policy.synthesizer, map.header().spacingAt(0));
    }
    TERRAIN_EXPECTS(
        policy.normalMapSize == 0 || isPowerOfTwo(policy.normalMapSize) || isPowerOfTwoPlusOne(policy.normalMapSize),
        "the normal map size must be 0, 2^k or 2^k + 1");
    if (policy.normalMapSize > 0 && !policy.synthesizer) {
        auto subdivision = DetailSynthesizer::create(static_cast<int>(map.header().chunkSize), DetailSettings{});
        TERRAIN_ASSERT(subdivision.ok());
        mSubdivisionOnly = std::move(subdivision).value();
    }
}

void TerrainNodeSource::addNormalMap(NodeData& data, const WindowPlacement& where) const
{
    if (mPolicy.normalMapSize <= 0) {
        return;
    }
    const DetailSynthesizer& below = mPolicy.synthesizer ? *mPolicy.synthesizer : *mSubdivisionOnly;
    keepNormalMap(data, makeNormalMap(below, data.heights, where, mPolicy.normalMapSize));
}

void TerrainNodeSource::keepNormalMap(NodeData& data, std::vector<std::int8_t> map) const
{
    if (mPolicy.compressNormalMaps) {
        data.normalMapBlocks = compressRgtc2(map, normalMapTexels(mPolicy.normalMapSize));
    } else {
        data.normalMap = std::move(map);
    }
}

WindowPlacement TerrainNodeSource::placement(const NodeId& id) const
{
    return windowPlacement(mMap.header(), id);
}

bool TerrainNodeSource::childrenAllowed(const NodeId& id, bool hasStaticChildren) const
{
    if (!hasStaticChildren && !mPolicy.synthesizer) {
        return false;
    }
    return id.level < NodeId::kMaxLevel && mMap.header().spacingAt(id.level + 1) >= mPolicy.minimumSpacing;
}

Expected<NodePtr> TerrainNodeSource::loadStatic(const NodeId& id, const NodeData* parent) const
{
    auto node =
        mMap.loadNode(id, parent ? std::span<const std::uint16_t>(parent->codes) : std::span<const std::uint16_t>());
    TERRAIN_TRY(node);
    const MapHeader& h = mMap.header();
    const DirectoryEntry* entry = mMap.find(id);
    TERRAIN_ASSERT(entry);
    const bool detail = mPolicy.synthesizer != nullptr;
    auto data = std::make_shared<NodeData>();
    data->id = id;
    data->isStatic = true;
    data->hasStaticChildren = entry->hasChildren;
    data->hasChildren = childrenAllowed(id, entry->hasChildren);
    // With detail, errors include what synthesis adds below the static leaves (3.4.1, estimated by prep).
    data->deltaC = detail && h.hasDetailErrors() ? entry->detailDeltaC : entry->deltaC;
    data->zMin = h.heightOf(entry->minCode) - mDisplacementBound;
    data->zMax = h.heightOf(entry->maxCode) + mDisplacementBound;
    data->spacing = h.spacingAt(id.level);
    data->codes = std::move(node->heights);
    DualHeightMap& map = data->heights;
    map.size = static_cast<int>(h.windowSize());
    map.base.resize(data->codes.size());
    for (std::size_t k = 0; k < data->codes.size(); ++k) {
        map.base[k] = static_cast<float>(h.heightStep * data->codes[k]);
    }
    if (detail) {
        const WindowPlacement where = placement(id);
        // Static nodes measure their own placement (DetailSynthesizer::displace): every sample is evaluated.
        mPolicy.synthesizer->displace(where, nullptr, 0, map);
        data->materialWeights = mPolicy.synthesizer->materialWeights(map);
    }
    data->texture = std::move(node->texture);
    addCover(*data);
    addTessellationErrors(*data);
    addNormalMap(*data, placement(id));
    addHorizons(*data, placement(id), parent);
    return NodePtr(std::move(data));
}

void TerrainNodeSource::addCover(NodeData& data) const
{
    if (!mPolicy.synthesizer || !mPolicy.synthesizer->settings().materials || data.materialWeights.empty()) {
        return;
    }
    const MapHeader& h = mMap.header();
    data.mapTexture = std::move(data.texture);
    data.texture = coverTexture(*mPolicy.synthesizer->settings().materials, data.mapTexture,
                                static_cast<int>(h.textureSize), data.materialWeights, static_cast<int>(h.chunkSize));
    // Only a node whose children are synthesized reads its map colours again.
    if (!data.hasChildren || data.hasStaticChildren) {
        data.mapTexture = {};
    }
}

void TerrainNodeSource::addHorizons(NodeData& data, const WindowPlacement& where, const NodeData* parent) const
{
    if (!mPolicy.horizonGrid) {
        return;
    }
    const int n = static_cast<int>(mMap.header().chunkSize);
    const int size = horizonLatticeSize(n, data.spacing, mPolicy.horizonGrid->spacing);
    if (parent && parent->horizons.size >= 3) {
        data.parentHorizons = latticeQuadrant(parent->horizons, data.id.quadrant());
    }
    if (!data.isStatic && data.parentHorizons.size == size) {
        // The lattice's points are all the parent's samples, where a dynamic node's surface is its parent's
        // (synthesis/DetailSynthesizer.h, "Nesting"): the same points, heights and grid, the same horizons.
        data.horizons = data.parentHorizons;
        return;
    }
    std::vector<float> window(data.heights.base.size());
    data.heights.surface(window);
    data.horizons = nodeHorizons(*mPolicy.horizonGrid, where, window, n, size, mPolicy.horizonOptions);
    if (!parent || parent->horizons.size < 3) {
        // The root (no parent drawn below it): its own lattice at every other point, as coarse as a parent's.
        const HorizonLattice& own = data.horizons;
        const int half = (own.size - 1) / 2 + 1;
        const auto a = static_cast<std::size_t>(own.azimuths);
        data.parentHorizons = {half, own.azimuths,
                               std::vector<std::uint8_t>(static_cast<std::size_t>(half) * half * a)};
        for (int j = 0; j < half; ++j) {
            for (int i = 0; i < half; ++i) {
                const auto from = (static_cast<std::size_t>(2 * j) * static_cast<std::size_t>(own.size) +
                                   static_cast<std::size_t>(2 * i)) *
                                  a;
                std::copy_n(own.codes.begin() + static_cast<std::ptrdiff_t>(from), a,
                            data.parentHorizons.codes.begin() +
                                static_cast<std::ptrdiff_t>((static_cast<std::size_t>(j) * half + i) * a));
            }
        }
    }
}

void TerrainNodeSource::addTessellationErrors(NodeData& data) const
{
    if (mPolicy.tessellationBlockQuads <= 0) {
        return;
    }
    const int n = static_cast<int>(mMap.header().chunkSize), w = data.heights.size;
    std::vector<float> window(data.heights.base.size());
    data.heights.surface(window);
    std::vector<float> surface(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            surface[static_cast<std::size_t>(j) * n + i] =
                window[static_cast<std::size_t>(j + kBorder) * w + i + kBorder];
        }
    }
    TessellationErrors errors = computeTessellationErrors(surface, n, mPolicy.tessellationBlockQuads);
    for (float& top : errors.top) {
        top += static_cast<float>(mMap.header().heightOffset);  // absolute, like the node's box
    }
    data.tessellation = std::make_shared<const TessellationErrors>(std::move(errors));
}

NodePtr TerrainNodeSource::synthesize(const NodeData& parent, int quadrant) const
{
    const MapHeader& h = mMap.header();
    const DetailSynthesizer& synthesizer = *mPolicy.synthesizer;
    const NodeId id = parent.id.child(quadrant);
    const WindowPlacement where = placement(id);
    auto data = std::make_shared<NodeData>();
    data->id = id;
    data->isStatic = false;
    data->hasStaticChildren = false;
    data->hasChildren = childrenAllowed(id, false);
    data->spacing = where.spacing;
    data->heights = synthesizer.synthesizeChild(parent.heights, quadrant, where);
    data->materialWeights = synthesizer.materialWeights(data->heights);
    // The node's children, made here once: its error is measured on them (DetailErrorModel::boundFromChildren,
    // instead of 3.4.1's "half the error of their parent") and its normal map shades with them. At most the
    // parent's / kErrorNesting, so errors nest with a geomorph range.
    std::array<DualHeightMap, 4> children;
    if (mPolicy.bounds || mPolicy.normalMapSize > 0) {
        children = synthesizer.synthesizeChildren(data->heights, where, ShownWeights::Skip);
    }
    // The bound, before the nesting cap: the box below needs what is true, the selection what nests.
    const double bound =
        mPolicy.bounds ? mErrorModel->boundFromChildren(data->heights, children, where, id.level) : 0.0;
    data->deltaC = parent.deltaC / kErrorNesting;
    if (mPolicy.bounds) {
        data->deltaC = std::min(data->deltaC, static_cast<float>(bound));
    }
    data->texture = upsampleTexture(parent.uncoveredTexture(), static_cast<int>(h.textureSize), quadrant);
    addCover(*data);
    // The box, kept inside the parent's so boxes stay nested (3.2.12). With the bound: the node's surface
    // samples (its triangles lie between them) widened by it, since every finer surface lies within the bound
    // of the node's triangles and the finer levels' triangles interpolate such points. Without: the base
    // samples plus whatever displacement may be added anywhere on the map.
    const int n = static_cast<int>(h.chunkSize), w = data->heights.size;
    const bool surface = mPolicy.bounds;
    auto at = [&](int i, int j) {
        const auto k = static_cast<std::size_t>(j) * w + i;
        return surface ? data->heights.height(k) : data->heights.base[k];
    };
    float lo = at(kBorder, kBorder), hi = lo;
    for (int j = kBorder; j < kBorder + n; ++j) {
        for (int i = kBorder; i < kBorder + n; ++i) {
            lo = std::min(lo, at(i, j));
            hi = std::max(hi, at(i, j));
        }
    }
    const double widen = surface ? bound : mDisplacementBound;
    data->zMin = std::clamp(h.heightOffset + lo - widen, parent.zMin, parent.zMax);
    data->zMax = std::clamp(h.heightOffset + hi + widen, data->zMin, parent.zMax);
    addTessellationErrors(*data);
    if (mPolicy.normalMapSize > 0) {
        keepNormalMap(*data, makeNormalMap(synthesizer, data->heights, children, where, mPolicy.normalMapSize));
    }
    addHorizons(*data, where, &parent);
    return data;
}

Expected<NodePtr> TerrainNodeSource::loadRoot()
{
    return loadStatic(NodeId::root(), nullptr);
}

Expected<ChildNodes> TerrainNodeSource::loadChildren(const NodeData& parent)
{
    if (!parent.hasChildren) {
        return makeError(mMap.name(), ": node ", parent.id.toString(), " has no children");
    }
    ChildNodes children;
    for (int q = 0; q < 4; ++q) {
        if (parent.hasStaticChildren) {
            auto child = loadStatic(parent.id.child(q), &parent);
            TERRAIN_TRY(child);
            children[static_cast<std::size_t>(q)] = std::move(child.value());
        } else {
            children[static_cast<std::size_t>(q)] = synthesize(parent, q);
        }
    }
    return children;
}

}  // namespace terrain
