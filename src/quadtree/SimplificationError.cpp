// Geomipmapping simplification error, eq. 3.1's delta_m (De Boer 2000; paper 3.2.3 and 3.2.5).
#include "quadtree/SimplificationError.h"

#include "core/Check.h"
#include "quadtree/TemplateTriangulation.h"

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
    const std::uint64_t cells = header.chunkSize - 1;
    auto strideOf = [&](int level) {
        return std::uint64_t{1} << (header.levels - 1 - static_cast<std::uint32_t>(level));
    };
    const std::uint64_t stride = strideOf(id.level);
    const std::uint64_t x0 = std::uint64_t{id.x} * cells * stride, y0 = std::uint64_t{id.y} * cells * stride;
    // The node's surface at finest-grid position (gx, gy) inside its square.
    auto surface = [&](std::uint64_t gx, std::uint64_t gy) {
        const std::uint64_t ux = gx - x0, uy = gy - y0;
        const std::uint64_t ix = std::min(ux / stride, cells - 1), iy = std::min(uy / stride, cells - 1);
        const double fx = static_cast<double>(ux - ix * stride) / static_cast<double>(stride);
        const double fy = static_cast<double>(uy - iy * stride) / static_cast<double>(stride);
        auto code = [&](std::uint64_t i, std::uint64_t j) -> double {
            return grid.at(x0 + i * stride, y0 + j * stride);
        };
        return interpolateQuad(code(ix, iy), code(ix + 1, iy), code(ix, iy + 1), code(ix + 1, iy + 1), fx, fy);
    };
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
        const std::uint64_t s = strideOf(at.level);
        const std::uint64_t lx0 = std::uint64_t{at.x} * cells * s, ly0 = std::uint64_t{at.y} * cells * s;
        for (std::uint64_t j = 0; j <= cells; ++j) {
            for (std::uint64_t i = 0; i <= cells; ++i) {
                const std::uint64_t gx = lx0 + i * s, gy = ly0 + j * s;
                worst = std::max(worst, std::abs(static_cast<double>(grid.at(gx, gy)) - surface(gx, gy)));
            }
        }
    }
    return worst;
}

}  // namespace terrain
