#include "lod/HeightQuery.h"

#include "lod/TerrainStreamer.h"
#include "quadtree/TemplateTriangulation.h"

#include <algorithm>
#include <cmath>

namespace terrain {

Expected<HeightSample> staticHeightAt(const MapFile& map, double x, double y)
{
    const MapHeader& h = map.header();
    // Position in samples of the finest static grid.
    const double gx = (x - h.originX) / h.sampleSpacing;
    const double gy = (y - h.originY) / h.sampleSpacing;
    const double eps = 1e-9;
    if (!(gx >= h.validX0 - eps && gx <= h.validX0 + h.validWidth - 1 + eps && gy >= h.validY0 - eps &&
          gy <= h.validY0 + h.validHeight - 1 + eps)) {
        return makeError(map.name(), ": position (", x, ", ", y, ") is outside the terrain, which spans x ",
                         h.originX + h.validX0 * h.sampleSpacing, " .. ",
                         h.originX + (h.validX0 + h.validWidth - 1) * h.sampleSpacing, " and y ",
                         h.originY + h.validY0 * h.sampleSpacing, " .. ",
                         h.originY + (h.validY0 + h.validHeight - 1) * h.sampleSpacing, " m");
    }
    // Descend to the finest static node containing the point.
    const double leafCells = static_cast<double>(h.gridSize() - 1);
    NodeId id = NodeId::root();
    auto node = map.loadNode(id, {});
    TERRAIN_TRY(node);
    while (true) {
        const DirectoryEntry* entry = map.find(id);
        if (!entry || !entry->hasChildren) {
            break;
        }
        const double half = leafCells / std::ldexp(1.0, id.level + 1);
        const double cx = (id.x * 2 + 1) * half, cy = (id.y * 2 + 1) * half;
        int quadrant = (gx >= cx ? 1 : 0) | (gy >= cy ? 2 : 0);
        // A point on the line between children lies in both: take the one whose subtree goes deeper (the
        // other may be a leaf pruned early, e.g. a node wholly in the padding).
        const int tieX = gx == cx ? 1 : 0, tieY = gy == cy ? 2 : 0;
        if (tieX | tieY) {
            for (int other : {quadrant ^ tieX, quadrant ^ tieY, quadrant ^ tieX ^ tieY}) {
                const DirectoryEntry* candidate = map.find(id.child(quadrant));
                if (candidate && candidate->hasChildren) {
                    break;
                }
                quadrant = other;
            }
            const DirectoryEntry* chosen = map.find(id.child(quadrant));
            if (!chosen || !chosen->hasChildren) {
                quadrant = (gx >= cx ? 1 : 0) | (gy >= cy ? 2 : 0);
            }
        }
        NodeId child = id.child(quadrant);
        auto next = map.loadNode(child, node->heights);
        TERRAIN_TRY(next);
        node = std::move(next);
        id = child;
    }
    // Interpolate inside the node's window.
    const double stride = std::ldexp(1.0, static_cast<int>(h.levels) - 1 - id.level);
    const double n1 = h.chunkSize - 1.0;
    const double lx = std::clamp(gx / stride - id.x * n1, 0.0, n1);
    const double ly = std::clamp(gy / stride - id.y * n1, 0.0, n1);
    const int ix = std::min(static_cast<int>(lx), static_cast<int>(n1) - 1);
    const int iy = std::min(static_cast<int>(ly), static_cast<int>(n1) - 1);
    const int w = map.window().size();
    auto code = [&](int i, int j) -> double {
        return node->heights[static_cast<std::size_t>(j + kBorder) * w + i + kBorder];
    };
    double c =
        interpolateQuad(code(ix, iy), code(ix + 1, iy), code(ix, iy + 1), code(ix + 1, iy + 1), lx - ix, ly - iy);
    return HeightSample{h.heightOffset + h.heightStep * c, id};
}

Expected<HeightSample> surfaceHeightAt(const MapFile& map, TerrainNodeSource& source, double x, double y, int depth)
{
    SurfaceSampler sampler(map, source, depth, 1);
    return sampler.at(x, y);
}

SurfaceSampler::SurfaceSampler(const MapFile& map, TerrainNodeSource& source, int depth, std::size_t cachedGroups)
    : mMap(map), mSource(source), mDepth(depth), mCachedGroups(cachedGroups)
{
    TERRAIN_EXPECTS(depth >= 0 && depth <= NodeId::kMaxLevel, "depth must be in [0, NodeId::kMaxLevel]");
    TERRAIN_EXPECTS(cachedGroups >= 1, "the sampler keeps at least one group");
}

Expected<const ChildNodes*> SurfaceSampler::children(const NodeData& parent)
{
    const std::uint64_t key = parent.id.key();
    auto it = mCache.find(key);
    if (it == mCache.end()) {
        if (mCache.size() >= mCachedGroups) {
            auto oldest = std::min_element(mCache.begin(), mCache.end(),
                                           [](const auto& a, const auto& b) { return a.second.used < b.second.used; });
            mCache.erase(oldest);
        }
        auto group = mSource.loadChildren(parent);
        TERRAIN_TRY(group);
        ++mGroupsMade;
        it = mCache.emplace(key, CachedGroup{std::move(group).value(), 0}).first;
    }
    it->second.used = ++mStamp;
    return &it->second.nodes;
}

Expected<HeightSample> SurfaceSampler::at(double x, double y)
{
    const MapHeader& h = mMap.header();
    const double gx = (x - h.originX) / h.sampleSpacing;
    const double gy = (y - h.originY) / h.sampleSpacing;
    const double eps = 1e-9;
    if (!(gx >= h.validX0 - eps && gx <= h.validX0 + h.validWidth - 1 + eps && gy >= h.validY0 - eps &&
          gy <= h.validY0 + h.validHeight - 1 + eps)) {
        return makeError(mMap.name(), ": position (", x, ", ", y, ") is outside the terrain");
    }
    if (!mRoot) {
        auto root = mSource.loadRoot();
        TERRAIN_TRY(root);
        mRoot = std::move(root).value();
    }
    NodePtr node = mRoot;
    // Position in units of root nodes (0..1 over the root's square).
    const double rootSize = h.nodeSizeAt(0);
    const double ux = (x - h.originX) / rootSize, uy = (y - h.originY) / rootSize;
    while (node->id.level < mDepth && node->hasChildren) {
        const double cells = std::ldexp(1.0, node->id.level + 1);
        const int qx = std::clamp(static_cast<int>(std::floor(ux * cells)) - 2 * static_cast<int>(node->id.x), 0, 1);
        const int qy = std::clamp(static_cast<int>(std::floor(uy * cells)) - 2 * static_cast<int>(node->id.y), 0, 1);
        auto group = children(*node);
        TERRAIN_TRY(group);
        node = (**group)[static_cast<std::size_t>(qx | (qy << 1))];
    }
    const double n1 = h.chunkSize - 1.0;
    const double cells = std::ldexp(1.0, node->id.level);
    const double lx = std::clamp((ux * cells - node->id.x) * n1, 0.0, n1);
    const double ly = std::clamp((uy * cells - node->id.y) * n1, 0.0, n1);
    const int ix = std::min(static_cast<int>(lx), static_cast<int>(n1) - 1);
    const int iy = std::min(static_cast<int>(ly), static_cast<int>(n1) - 1);
    const int w = node->heights.size;
    auto at = [&](int i, int j) -> double {
        return node->heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
    };
    const double z = interpolateQuad(at(ix, iy), at(ix + 1, iy), at(ix, iy + 1), at(ix + 1, iy + 1), lx - ix, ly - iy);
    return HeightSample{h.heightOffset + z, node->id};
}

double nodeSurfaceAt(const NodeData& node, int chunkSize, double lx, double ly)
{
    const double n1 = chunkSize - 1.0;
    lx = std::clamp(lx, 0.0, n1);
    ly = std::clamp(ly, 0.0, n1);
    const int ix = std::min(static_cast<int>(lx), static_cast<int>(n1) - 1);
    const int iy = std::min(static_cast<int>(ly), static_cast<int>(n1) - 1);
    const int w = node.heights.size;
    auto at = [&](int i, int j) -> double {
        return node.heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
    };
    return interpolateQuad(at(ix, iy), at(ix + 1, iy), at(ix, iy + 1), at(ix + 1, iy + 1), lx - ix, ly - iy);
}

namespace {

/// The node's surface at world (x, y) (metres above the map's height offset); the point is clamped into
/// the node's square.
double nodeSurfaceAt(const NodeData& node, const QuadtreeExtent& extent, int chunkSize, double x, double y)
{
    const double size = extent.nodeSize(node.id.level);
    const double n1 = chunkSize - 1.0;
    return nodeSurfaceAt(node, chunkSize, (x - extent.originX - node.id.x * size) / size * n1,
                         (y - extent.originY - node.id.y * size) / size * n1);
}

}  // namespace

std::optional<double> drawnHeightAt(const TerrainStreamer& streamer, const MapHeader& header, double x, double y)
{
    const QuadtreeExtent extent = extentOf(header);
    for (const SelectedNode& selected : streamer.selection().nodes) {
        const double size = extent.nodeSize(selected.id.level);
        const double x0 = extent.originX + selected.id.x * size, y0 = extent.originY + selected.id.y * size;
        if (x < x0 || x > x0 + size || y < y0 || y > y0 + size) {
            continue;
        }
        const NodePtr node = streamer.node(selected.id);
        if (!node || node->heights.size == 0) {
            return std::nullopt;
        }
        const int n = static_cast<int>(header.chunkSize);
        double z = nodeSurfaceAt(*node, extent, n, x, y);
        if (selected.morph < 1.0f && !selected.id.isRoot()) {
            if (const NodePtr parent = streamer.node(selected.id.parent()); parent && parent->heights.size != 0) {
                const double f = selected.morph;
                z = f * z + (1.0 - f) * nodeSurfaceAt(*parent, extent, n, x, y);
            }
        }
        return header.heightOffset + z;
    }
    return std::nullopt;
}

}  // namespace terrain
