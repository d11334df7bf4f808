// Geomipmapping simplification error, eq. 3.1's delta_m (De Boer 2000; paper 3.2.3 and 3.2.5).
#include "quadtree/SimplificationError.h"

#include "core/Check.h"
#include "quadtree/TemplateTriangulation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace terrain {

double simplificationErrorCodes(const QuantizedGrid& grid, const MapHeader& header, const NodeId& id)
{
    TERRAIN_EXPECTS(id.level + 1 < static_cast<int>(header.levels), "a leaf has no removed samples");
    const std::uint64_t n = header.chunkSize;
    const std::uint64_t stride = std::uint64_t{1} << (header.levels - 2 - static_cast<std::uint32_t>(id.level));
    const std::uint64_t x0 = std::uint64_t{id.x} * 2 * (n - 1);
    const std::uint64_t y0 = std::uint64_t{id.y} * 2 * (n - 1);
    return simplificationErrorCodes(static_cast<int>(n), [&](int a, int b) -> std::int32_t {
        return grid.at((x0 + static_cast<std::uint64_t>(a)) * stride, (y0 + static_cast<std::uint64_t>(b)) * stride);
    });
}

double directErrorCodes(const QuantizedGrid& grid, const MapHeader& header, const NodeId& id,
                        const std::function<bool(const NodeId&)>& hasChildren)
{
    return hasChildren(id) ? directErrorCodesWithin(grid, header, id, id, hasChildren) : 0.0;
}

double directErrorCodesWithin(const QuantizedGrid& grid, const MapHeader& header, const NodeId& id,
                              const NodeId& within, const std::function<bool(const NodeId&)>& hasChildren)
{
    TERRAIN_EXPECTS(within.level >= id.level && (within.x >> (within.level - id.level)) == id.x &&
                        (within.y >> (within.level - id.level)) == id.y,
                    "`within` must be `id` or below it");
    const std::uint64_t cells = header.chunkSize - 1, side = cells + 1;
    auto shiftOf = [&](int level) { return header.levels - 1 - static_cast<std::uint32_t>(level); };
    const std::uint32_t shift = shiftOf(id.level);
    const std::uint64_t stride = std::uint64_t{1} << shift;
    const double inverseStride = 1.0 / static_cast<double>(stride);  // exact: stride is a power of two
    const std::uint64_t x0 = std::uint64_t{id.x} * cells * stride, y0 = std::uint64_t{id.y} * cells * stride;
    // The node's own codes over the cells that `within` covers, read once; the node's surface at
    // finest-grid position (gx, gy) interpolates them. Only those codes: `within` may be one subtree of a
    // large out-of-core map, whose pages outside it must not be touched. A vertex on the far edge of the
    // covered cells interpolates with weight 0 across it, so the column and row past the edge (kept to
    // index without a branch) hold 0 instead of codes read from beyond `within`.
    const std::uint64_t withinSide = cells << shiftOf(within.level);
    const std::uint64_t wx = std::uint64_t{within.x} * withinSide - x0, wy = std::uint64_t{within.y} * withinSide - y0;
    const std::uint64_t cx0 = wx >> shift, cy0 = wy >> shift;
    const std::uint64_t cx1 = std::min(cells, ((wx + withinSide) >> shift) + 1);
    const std::uint64_t cy1 = std::min(cells, ((wy + withinSide) >> shift) + 1);
    const std::uint64_t readX1 = std::min(cells, (wx + withinSide + stride - 1) >> shift);
    const std::uint64_t readY1 = std::min(cells, (wy + withinSide + stride - 1) >> shift);
    const std::uint64_t span = cx1 - cx0 + 1;
    std::vector<double> node(span * (cy1 - cy0 + 1), 0.0);
    for (std::uint64_t j = cy0; j <= readY1; ++j) {
        for (std::uint64_t i = cx0; i <= readX1; ++i) {
            node[(j - cy0) * span + (i - cx0)] = grid.at(x0 + i * stride, y0 + j * stride);
        }
    }
    std::vector<std::uint64_t> cellX(side);
    std::vector<double> fractionX(side);
    double worst = 0.0;
    std::vector<NodeId> stack{within};
    while (!stack.empty()) {
        const NodeId at = stack.back();
        stack.pop_back();
        if (hasChildren(at)) {
            for (int q = 0; q < 4; ++q) {
                stack.push_back(at.child(q));
            }
            continue;
        }
        const std::uint64_t s = std::uint64_t{1} << shiftOf(at.level);
        const std::uint64_t lx0 = std::uint64_t{at.x} * cells * s, ly0 = std::uint64_t{at.y} * cells * s;
        for (std::uint64_t i = 0; i < side; ++i) {
            const std::uint64_t ux = lx0 + i * s - x0;
            const std::uint64_t ix = std::min(ux >> shift, cells - 1);
            cellX[i] = ix - cx0;
            fractionX[i] = static_cast<double>(ux - ix * stride) * inverseStride;
        }
        for (std::uint64_t j = 0; j < side; ++j) {
            const std::uint64_t gy = ly0 + j * s, uy = gy - y0;
            const std::uint64_t iy = std::min(uy >> shift, cells - 1);
            const double fy = static_cast<double>(uy - iy * stride) * inverseStride;
            const double* row0 = node.data() + (iy - cy0) * span;
            const double* row1 = row0 + span;
            for (std::uint64_t i = 0; i < side; ++i) {
                const std::uint64_t ix = cellX[i];
                const double surface =
                    interpolateQuad(row0[ix], row0[ix + 1], row1[ix], row1[ix + 1], fractionX[i], fy);
                worst = std::max(worst, std::abs(static_cast<double>(grid.at(lx0 + i * s, gy)) - surface));
            }
        }
    }
    return worst;
}

}  // namespace terrain
