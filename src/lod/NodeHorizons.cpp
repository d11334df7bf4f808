// The horizons of the quadtree's nodes over the static map's height grid (NodeHorizons.h).
#include "lod/NodeHorizons.h"

#include "core/Check.h"
#include "quadtree/ChunkGeometry.h"
#include "synthesis/DualHeightMap.h"

#include <algorithm>
#include <cmath>

namespace terrain {

namespace {

/// Writes the inner N x N samples of `codes` (a node's window at `id`) into `grid` at `level`, each node sample
/// spread bilinearly over 2^(level - id.level) grid samples when the node is coarser than the grid; only over
/// quadrant `quadrant` of the node's square when it is 0..3.
void writeNode(const MapHeader& h, const NodeId& id, std::span<const std::uint16_t> codes, int level, HeightGrid& grid,
               int quadrant = -1)
{
    const int n = static_cast<int>(h.chunkSize), w = h.windowSize();
    const int scale = 1 << (level - static_cast<int>(id.level));
    const std::int64_t x0 = static_cast<std::int64_t>(id.x) * (n - 1) * scale;
    const std::int64_t y0 = static_cast<std::int64_t>(id.y) * (n - 1) * scale;
    auto at = [&](int i, int j) {
        return h.heightStep * codes[static_cast<std::size_t>(j + kBorder) * static_cast<std::size_t>(w) +
                                    static_cast<std::size_t>(i + kBorder)];
    };
    const int side = (n - 1) * scale + 1, half = (n - 1) * scale / 2;
    const int i0 = quadrant < 0 ? 0 : (quadrant & 1) * half, j0 = quadrant < 0 ? 0 : (quadrant >> 1) * half;
    const int i1 = quadrant < 0 ? side : i0 + half + 1, j1 = quadrant < 0 ? side : j0 + half + 1;
    for (int j = j0; j < j1; ++j) {
        const int sj = std::min(j / scale, n - 2);
        const double fy = static_cast<double>(j - sj * scale) / scale;
        for (int i = i0; i < i1; ++i) {
            const int si = std::min(i / scale, n - 2);
            const double fx = static_cast<double>(i - si * scale) / scale;
            const double v = (1.0 - fy) * ((1.0 - fx) * at(si, sj) + fx * at(si + 1, sj)) +
                             fy * ((1.0 - fx) * at(si, sj + 1) + fx * at(si + 1, sj + 1));
            grid.heights[static_cast<std::size_t>(y0 + j) * static_cast<std::size_t>(grid.width) +
                         static_cast<std::size_t>(x0 + i)] = static_cast<float>(v);
        }
    }
}

/// Writes the node `id` (decoded from `parentCodes`, the parent's window) and its descendants down to `level`.
/// A node that cannot be read has its parent's samples over its square, and its error in `unreadable`.
void visit(const MapFile& map, const NodeId& id, std::span<const std::uint16_t> parentCodes, int level,
           HeightGrid& grid, std::vector<std::string>& unreadable)
{
    auto node = map.loadNode(id, parentCodes);
    if (!node.ok()) {
        unreadable.push_back(node.error().message);
        writeNode(map.header(), id.parent(), parentCodes, level, grid, id.quadrant());
        return;
    }
    const DirectoryEntry* entry = map.find(id);
    TERRAIN_ASSERT(entry);
    if (static_cast<int>(id.level) == level || !entry->hasChildren) {
        writeNode(map.header(), id, node->heights, level, grid);
        return;
    }
    for (int q = 0; q < 4; ++q) {
        visit(map, id.child(q), node->heights, level, grid, unreadable);
    }
}

}  // namespace

int staticHeightGridLevel(const MapHeader& h, int maxSide)
{
    TERRAIN_EXPECTS(maxSide >= 2, "a grid of at least 2 samples a side");
    const std::int64_t cells = h.chunkSize - 1;
    int level = 0;
    while (level + 1 < static_cast<int>(h.levels) && (cells << (level + 1)) + 1 <= maxSide) {
        ++level;
    }
    return level;
}

Expected<HeightGrid> staticHeightGrid(const MapFile& map, int maxSide, std::vector<std::string>* unreadable)
{
    const MapHeader& h = map.header();
    const std::int64_t cells = h.chunkSize - 1;
    const int level = staticHeightGridLevel(h, maxSide);
    HeightGrid grid;
    grid.width = grid.height = static_cast<int>((cells << level) + 1);
    grid.originX = h.originX;
    grid.originY = h.originY;
    grid.spacing = h.spacingAt(level);
    grid.heights.assign(static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height), 0.0f);
    auto root = map.loadNode(NodeId{}, {});
    TERRAIN_TRY(root);
    std::vector<std::string> errors;
    if (level == 0 || !map.find(NodeId{})->hasChildren) {
        writeNode(h, NodeId{}, root->heights, level, grid);
    } else {
        for (int q = 0; q < 4; ++q) {
            visit(map, NodeId{}.child(q), root->heights, level, grid, errors);
        }
    }
    if (unreadable) {
        *unreadable = std::move(errors);
    }
    grid.setTop();
    return grid;
}

int horizonLatticeSize(int chunkSize, double spacing, double gridSpacing)
{
    TERRAIN_EXPECTS(chunkSize >= 3 && ((chunkSize - 1) & (chunkSize - 2)) == 0 && spacing > 0.0 && gridSpacing > 0.0,
                    "a chunk of 2^k + 1 samples and spacings > 0");
    int size = chunkSize;
    while (size > kMinHorizonLattice && 2.0 * spacing * (chunkSize - 1) / (size - 1) <= gridSpacing) {
        size = (size - 1) / 2 + 1;
    }
    return size;
}

HorizonLattice nodeHorizons(const HeightGrid& grid, const WindowPlacement& where, std::span<const float> window,
                            int chunkSize, int latticeSize, const HorizonOptions& options)
{
    const int n = chunkSize, w = windowSize(n);
    TERRAIN_EXPECTS(latticeSize >= 2 && (n - 1) % (latticeSize - 1) == 0 &&
                        window.size() == static_cast<std::size_t>(w) * static_cast<std::size_t>(w),
                    "a lattice dividing the node's cells, and the node's window");
    const int stride = (n - 1) / (latticeSize - 1);
    const auto a = static_cast<std::size_t>(options.azimuths);
    HorizonLattice lattice{latticeSize, options.azimuths,
                           std::vector<std::uint8_t>(static_cast<std::size_t>(latticeSize) * latticeSize * a)};
    std::vector<float> tangents(a);
    for (int j = 0; j < latticeSize; ++j) {
        for (int i = 0; i < latticeSize; ++i) {
            const int si = kBorder + i * stride, sj = kBorder + j * stride;
            const double x = where.originX + static_cast<double>(where.gx0 + si) * where.spacing;
            const double y = where.originY + static_cast<double>(where.gy0 + sj) * where.spacing;
            const double z =
                window[static_cast<std::size_t>(sj) * static_cast<std::size_t>(w) + static_cast<std::size_t>(si)];
            horizonTangents(grid, x, y, std::max(z, grid.at(x, y)), options, tangents);
            const auto at =
                (static_cast<std::size_t>(j) * static_cast<std::size_t>(latticeSize) + static_cast<std::size_t>(i)) * a;
            for (std::size_t k = 0; k < a; ++k) {
                lattice.codes[at + k] = encodeHorizon(tangents[k]);
            }
        }
    }
    return lattice;
}

}  // namespace terrain
