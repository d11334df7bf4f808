// delta_m (paper 3.2.5, figure 3.4): how far the samples a node's children add lie from the node's own
// triangulated surface (geomipmapping: every other row and column removed, 3.2.3).
#pragma once

#include "quadtree/MapFormat.h"
#include "quadtree/QuantizedGrid.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <functional>

namespace terrain {

/// delta_m in codes from the node's square at its children's resolution: `sample(a, b)` returns the code at
/// (a, b), a and b in [0, 2 (N - 1)], a east, b north. The even samples are the node's own; every odd one
/// is compared with the node's surface along the template triangulation (TemplateTriangulation.h: the
/// centre of a quad lies on its south-west to north-east diagonal).
template <class Sample>
double simplificationErrorCodes(int chunkSize, Sample&& sample)
{
    const int last = 2 * (chunkSize - 1);
    std::int64_t worst2 = 0;  // twice the error, to stay in integers
    for (int b = 0; b <= last; ++b) {
        for (int a = (b & 1) ? 0 : 1; a <= last; a += (b & 1) ? 1 : 2) {
            std::int64_t twiceSurface = 0;
            if ((a & 1) && (b & 1)) {
                twiceSurface = std::int64_t{sample(a - 1, b - 1)} + sample(a + 1, b + 1);
            } else if (a & 1) {
                twiceSurface = std::int64_t{sample(a - 1, b)} + sample(a + 1, b);
            } else {
                twiceSurface = std::int64_t{sample(a, b - 1)} + sample(a, b + 1);
            }
            worst2 = std::max(worst2, std::abs(2 * std::int64_t{sample(a, b)} - twiceSurface));
        }
    }
    return static_cast<double>(worst2) / 2.0;
}

/// delta_m in codes of static node `id` from the quantized grid. Requires id.level + 1 < header.levels.
double simplificationErrorCodes(const QuantizedGrid& grid, const MapHeader& header, const NodeId& id);

/// The measured error of static node `id` in codes (in place of eq. 3.1's sum): the largest vertical
/// distance from the node's surface (its samples of `grid`, along the template triangulation) to the finest
/// surface stored below it, the stored leaves (`hasChildren` tells which nodes have children). The leaves'
/// grids nest in the node's, so both surfaces are linear on the leaves' triangles and the largest distance is
/// at a leaf sample: every sample of every leaf below is compared. 0 for a leaf.
double directErrorCodes(const QuantizedGrid& grid, const MapHeader& header, const NodeId& id,
                        const std::function<bool(const NodeId&)>& hasChildren);
/// The same over the stored leaves in the subtree of `within` only (`within` is `id` or below it; a leaf
/// itself counts): the build takes the largest over the subtrees below a level, each measured while its
/// region of the grid is at hand.
double directErrorCodesWithin(const QuantizedGrid& grid, const MapHeader& header, const NodeId& id,
                              const NodeId& within, const std::function<bool(const NodeId&)>& hasChildren);

}  // namespace terrain
