#include "quadtree/WeightMap.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>

namespace terrain {

WeightMap::WeightMap(Image gray, const MapHeader& header) : mImage(std::move(gray)), mHeader(header)
{
    TERRAIN_EXPECTS(mImage.channels == 1 && mImage.width >= 1 && mImage.height >= 1, "weight map must be gray");
}

int WeightMap::deepestLevelWanted(const NodeId& id) const
{
    const double stride = std::ldexp(1.0, static_cast<int>(mHeader.levels) - 1 - id.level);
    const double size = (mHeader.chunkSize - 1) * stride;
    const double scaleX = mHeader.validWidth > 1 ? (mImage.width - 1.0) / (mHeader.validWidth - 1.0) : 0.0;
    const double scaleY = mHeader.validHeight > 1 ? (mImage.height - 1.0) / (mHeader.validHeight - 1.0) : 0.0;
    // The node's square in image pixel coordinates (x east, row 0 north), widened to whole pixels.
    double gx0 = id.x * size - mHeader.validX0, gx1 = gx0 + size;
    double gy0 = id.y * size - mHeader.validY0, gy1 = gy0 + size;
    auto px0 = static_cast<int>(std::floor(gx0 * scaleX)), px1 = static_cast<int>(std::ceil(gx1 * scaleX));
    auto row0 = static_cast<int>(std::floor((mImage.height - 1) - gy1 * scaleY));
    auto row1 = static_cast<int>(std::ceil((mImage.height - 1) - gy0 * scaleY));
    px0 = std::clamp(px0, 0, mImage.width - 1);
    px1 = std::clamp(px1, 0, mImage.width - 1);
    row0 = std::clamp(row0, 0, mImage.height - 1);
    row1 = std::clamp(row1, 0, mImage.height - 1);
    int brightest = 0;
    for (int row = row0; row <= row1; ++row) {
        for (int px = px0; px <= px1; ++px) {
            brightest = std::max<int>(brightest, *mImage.pixel(px, row));
        }
    }
    return static_cast<int>(std::lround(brightest / 255.0 * (mHeader.levels - 1)));
}

}  // namespace terrain
