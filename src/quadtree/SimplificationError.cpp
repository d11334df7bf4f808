// Geomipmapping simplification error, eq. 3.1's delta_m (De Boer 2000; paper 3.2.3 and 3.2.5).
#include "quadtree/SimplificationError.h"

#include "core/Check.h"

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

}  // namespace terrain
