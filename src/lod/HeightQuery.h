// Height queries: the surface exactly as the finest static level renders it, or as the viewer renders any
// level, synthesized detail included.
#pragma once

#include "core/Expected.h"
#include "lod/TerrainNodeSource.h"
#include "quadtree/MapFile.h"

#include <cstdint>
#include <optional>
#include <unordered_map>

namespace terrain {

/// A height and where it came from.
struct HeightSample {
    double height = 0.0;  ///< metres
    NodeId node;          ///< the finest static node containing the point
};

/// Height of the finest static level at world position (x, y) metres, interpolated along the template
/// triangulation (TemplateTriangulation.h) as it is rendered. Fails outside the input's valid region
/// (padding excluded) and when a node on the way cannot be read.
Expected<HeightSample> staticHeightAt(const MapFile& map, double x, double y);

/// Height of the rendered surface (static + synthesized: base + displacement) at world (x, y) metres, at
/// quadtree level `depth` (or the deepest level above it that `source` can make), interpolated along the
/// template triangulation: exactly what the viewer draws when that level is selected with morph factor 1.
/// Nodes come from `source` (its detail policy decides what is synthesized), so the query and the viewer
/// share one code path. Fails outside the input's valid region and when a node cannot be read.
Expected<HeightSample> surfaceHeightAt(const MapFile& map, TerrainNodeSource& source, double x, double y, int depth);

/// surfaceHeightAt for many points: the groups of children made on the way are kept (the least recently
/// used dropped beyond `cachedGroups`), so neighbouring points share their nodes instead of synthesizing
/// the path from the root again. The same heights as surfaceHeightAt, bit for bit.
class SurfaceSampler {
public:
    /// `map` and `source` must outlive the sampler. Preconditions: depth in [0, NodeId::kMaxLevel],
    /// cachedGroups >= 1.
    SurfaceSampler(const MapFile& map, TerrainNodeSource& source, int depth, std::size_t cachedGroups = 256);

    Expected<HeightSample> at(double x, double y);
    /// Groups of children made so far (statistics).
    std::uint64_t groupsMade() const { return mGroupsMade; }

private:
    struct CachedGroup {
        ChildNodes nodes;
        std::uint64_t used = 0;
    };
    Expected<const ChildNodes*> children(const NodeData& parent);

    const MapFile& mMap;
    TerrainNodeSource& mSource;
    int mDepth;
    std::size_t mCachedGroups;
    NodePtr mRoot;
    std::unordered_map<std::uint64_t, CachedGroup> mCache;
    std::uint64_t mStamp = 0;
    std::uint64_t mGroupsMade = 0;
};

/// The surface of `node` (N = `chunkSize` samples a side) at local grid position (lx, ly), in samples east
/// and north of its south-west corner (clamped to [0, N - 1]), interpolated along the template triangulation:
/// metres above the map's height offset.
double nodeSurfaceAt(const NodeData& node, int chunkSize, double lx, double ly);

class TerrainStreamer;

/// Height of the surface the viewer draws this frame at world (x, y) metres: the selected node containing
/// the point, its own surface blended with its parent's by its morph factor (eq. 3.4), both interpolated
/// along the template triangulation. Empty where no selected node covers the point or its data is not
/// resident. Needs no loading: for per-frame use (the free-flight camera's clearance).
std::optional<double> drawnHeightAt(const TerrainStreamer& streamer, const MapHeader& header, double x, double y);

}  // namespace terrain
