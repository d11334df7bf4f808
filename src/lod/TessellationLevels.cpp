#include "lod/TessellationLevels.h"

#include "core/Check.h"
#include "lod/LodSelector.h"

#include <algorithm>

namespace terrain {

BlockLevels chooseBlockLevels(const BlockErrors& errors, const Aabb& node, const Camera& camera, double pixels)
{
    const int b = errors.blocksPerSide;
    TERRAIN_EXPECTS(b >= 1 && errors.levels >= 1, "block errors must come from computeBlockErrors");
    // Eq. 3.3 per block: level d is within the budget when lodDistance >= lambda(d) * C.
    const double c = lodDistanceFactor(camera, pixels);
    const double k = verticalErrorFactor(camera);
    const double size = (node.hi.x - node.lo.x) / b;
    std::vector<double> distance(static_cast<std::size_t>(b) * b);
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            const Aabb block{{node.lo.x + bx * size, node.lo.y + by * size, node.lo.z},
                             {node.lo.x + (bx + 1) * size, node.lo.y + (by + 1) * size, node.hi.z}};
            distance[static_cast<std::size_t>(by * b + bx)] = lodDistance(camera, k, block);
        }
    }
    // The coarsest level at which every block of the edge (one or two) is within the budget at the nearer
    // of their distances.
    auto edgeLevel = [&](int ax, int ay, int cx, int cy) {
        const bool first = ax >= 0 && ax < b && ay >= 0 && ay < b;
        const bool second = cx >= 0 && cx < b && cy >= 0 && cy < b;
        TERRAIN_ASSERT(first || second);
        double d = 1e300;
        if (first) {
            d = std::min(d, distance[static_cast<std::size_t>(ay * b + ax)]);
        }
        if (second) {
            d = std::min(d, distance[static_cast<std::size_t>(cy * b + cx)]);
        }
        int level = 0;
        for (int next = 1; next <= errors.levels; ++next) {
            double lambda = 0.0;
            if (first) {
                lambda = std::max(lambda, static_cast<double>(errors.at(ax, ay, next)));
            }
            if (second) {
                lambda = std::max(lambda, static_cast<double>(errors.at(cx, cy, next)));
            }
            if (d < lambda * c) {
                break;  // lambda is non-decreasing in d: no coarser level fits either
            }
            level = next;
        }
        return static_cast<std::uint8_t>(level);
    };
    BlockLevels out;
    out.blocksPerSide = b;
    out.northEdges.resize(static_cast<std::size_t>(b) * (b + 1));
    out.eastEdges.resize(static_cast<std::size_t>(b + 1) * b);
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx <= b; ++bx) {
            out.northEdges[static_cast<std::size_t>(by * (b + 1) + bx)] = edgeLevel(bx - 1, by, bx, by);
        }
    }
    for (int by = 0; by <= b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            out.eastEdges[static_cast<std::size_t>(by * b + bx)] = edgeLevel(bx, by - 1, bx, by);
        }
    }
    out.interior.resize(static_cast<std::size_t>(b) * b);
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            out.interior[static_cast<std::size_t>(by * b + bx)] =
                std::min({out.northEdges[static_cast<std::size_t>(by * (b + 1) + bx)],
                          out.northEdges[static_cast<std::size_t>(by * (b + 1) + bx + 1)],
                          out.eastEdges[static_cast<std::size_t>(by * b + bx)],
                          out.eastEdges[static_cast<std::size_t>((by + 1) * b + bx)]});
        }
    }
    return out;
}

}  // namespace terrain
