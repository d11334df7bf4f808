// Weight-map pruning (paper 3.2.13): a gray image over the terrain says how deep the static tree must go.
#pragma once

#include "heightfield/Image.h"
#include "quadtree/MapFormat.h"

namespace terrain {

/// A weight w in [0, 1] (pixel / 255) asks for static levels down to round(w * (levels - 1)) at that spot:
/// white keeps the full input resolution, black keeps only the root. The image is stretched over the
/// input's valid region like a texture (row 0 north).
class WeightMap {
public:
    WeightMap(Image gray, const MapHeader& header);

    /// The deepest level any pixel under node `id`'s square asks for. A node keeps its four children
    /// when this exceeds its level (the four go together: 3.2.13, a node has four children or none).
    int deepestLevelWanted(const NodeId& id) const;

private:
    Image mImage;
    const MapHeader& mHeader;
};

}  // namespace terrain
