#include "lod/TessellationLevels.h"

#include "core/Check.h"
#include "core/Frustum.h"
#include "lod/LodSelector.h"
#include "quadtree/ChunkGeometry.h"

#include <algorithm>
#include <cmath>

namespace terrain {

std::uint16_t BlockLevels::code(int block) const
{
    const auto k = static_cast<std::size_t>(block);
    int code = level[k] | (culled[k] != 0 ? kBlockCulledBit : 0);
    for (int side = 0; side < 4; ++side) {
        code |= snap[4 * k + static_cast<std::size_t>(side)] << (kBlockSnapShift + side * kBlockSnapBits);
    }
    return static_cast<std::uint16_t>(code);
}

std::uint64_t BlockLevels::surfaceTriangles() const
{
    std::uint64_t triangles = 0;
    for (std::size_t k = 0; k < level.size(); ++k) {
        if (!culled[k]) {
            const std::uint64_t f = static_cast<std::uint64_t>(blockQuads) >> level[k];
            triangles += 2 * f * f;
        }
    }
    return triangles;
}

std::uint64_t BlockLevels::skirtTriangles() const
{
    std::uint64_t triangles = 0;
    const int b = blocksPerSide;
    for (int k = 0; k < b * b; ++k) {
        const int bx = k % b, by = k / b;
        const int borders = (bx == 0) + (bx == b - 1) + (by == 0) + (by == b - 1);
        if (borders > 0 && !culled[static_cast<std::size_t>(k)]) {
            triangles += static_cast<std::uint64_t>(borders) *
                         skirtPatchTriangles(blockQuads >> level[static_cast<std::size_t>(k)]);
        }
    }
    return triangles;
}

BlockLevels chooseBlockLevels(const TessellationErrors& errors, const Aabb& node, const Camera& camera, double pixels,
                              const BoxOccluded& occluded)
{
    const BlockErrors& lambda = errors.blocks;
    const int b = lambda.blocksPerSide;
    TERRAIN_EXPECTS(b >= 1 && lambda.levels >= 1, "block errors must come from computeTessellationErrors");
    // Eq. 3.3 per block: an error of delta metres is within the budget where lodDistance >= delta * C.
    const double c = lodDistanceFactor(camera, pixels);
    const double k = verticalErrorFactor(camera);
    const Frustum frustum = Frustum::fromCamera(camera);
    const double size = (node.hi.x - node.lo.x) / b;
    const auto blocks = static_cast<std::size_t>(b) * b;
    std::vector<double> distance(blocks);
    BlockLevels out;
    out.blocksPerSide = b;
    out.blockQuads = lambda.blockQuads;
    out.level.assign(blocks, 0);
    out.snap.assign(4 * blocks, 0);
    out.culled.assign(blocks, 0);
    std::vector<std::uint8_t> hidden(occluded ? blocks : 0, 0);  // drawn, and `occluded` says so
    TERRAIN_EXPECTS(!occluded || errors.top.size() == blocks, "the block tops come from computeTessellationErrors");
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            const Aabb box{{node.lo.x + bx * size, node.lo.y + by * size, node.lo.z},
                           {node.lo.x + (bx + 1) * size, node.lo.y + (by + 1) * size, node.hi.z}};
            const auto i = static_cast<std::size_t>(by * b + bx);
            distance[i] = lodDistance(camera, k, box);
            out.culled[i] = frustum.intersects(box) ? 0 : 1;
            int level = 0;
            while (level < lambda.levels && lambda.at(bx, by, level + 1) * c <= distance[i]) {
                ++level;  // lambda is non-decreasing in d: the first that does not fit ends the search
            }
            if (occluded && !out.culled[i]) {
                Aabb own = box;
                own.hi.z = std::max(static_cast<double>(errors.top[i]), own.lo.z);
                hidden[i] = occluded(own) ? 1 : 0;
            }
            out.level[i] = static_cast<std::uint8_t>(level);
        }
    }
    // The drawn neighbour across `side`, or -1 (the node's border, or a culled block: nothing is drawn there).
    auto neighbour = [&](int bx, int by, int side) {
        static constexpr int kDx[4] = {0, 1, 0, -1}, kDy[4] = {-1, 0, 1, 0};
        const int nx = bx + kDx[side], ny = by + kDy[side];
        if (nx < 0 || ny < 0 || nx >= b || ny >= b || out.culled[static_cast<std::size_t>(ny * b + nx)]) {
            return -1;
        }
        return ny * b + nx;
    };
    // A finer block snapped onto a coarser neighbour's lattice must stay within its budget; where it would
    // not, the neighbour gets finer. Levels only decrease, so this ends.
    for (bool changed = true; changed;) {
        changed = false;
        for (int by = 0; by < b; ++by) {
            for (int bx = 0; bx < b; ++bx) {
                const auto i = static_cast<std::size_t>(by * b + bx);
                if (out.culled[i]) {
                    continue;
                }
                for (int side = 0; side < 4; ++side) {
                    const int other = neighbour(bx, by, side);
                    if (other < 0 || out.level[static_cast<std::size_t>(other)] <= out.level[i]) {
                        continue;
                    }
                    const int e = out.level[static_cast<std::size_t>(other)];
                    if (errors.snapError(bx, by, side, out.level[i], e) * c > distance[i]) {
                        out.level[static_cast<std::size_t>(other)] = static_cast<std::uint8_t>(e - 1);
                        changed = true;
                    }
                }
            }
        }
    }
    // Occluded blocks with no visible block beside them go to the coarsest level. Those beside a visible one
    // keep theirs, so the visible block's sides, snapped to the coarser of the two, stay as they were: what
    // shows is drawn exactly as without the occlusion test. Between hidden blocks nothing shows.
    if (occluded) {
        std::vector<std::uint8_t> coarsen(blocks, 0);
        for (int by = 0; by < b; ++by) {
            for (int bx = 0; bx < b; ++bx) {
                const auto i = static_cast<std::size_t>(by * b + bx);
                if (!hidden[i]) {
                    continue;
                }
                bool besideVisible = false;
                for (int side = 0; side < 4; ++side) {
                    const int other = neighbour(bx, by, side);
                    besideVisible = besideVisible || (other >= 0 && !hidden[static_cast<std::size_t>(other)]);
                }
                coarsen[i] = besideVisible ? 0 : 1;
            }
        }
        for (std::size_t i = 0; i < blocks; ++i) {
            if (coarsen[i] && out.level[i] < lambda.levels) {
                out.level[i] = static_cast<std::uint8_t>(lambda.levels);
                ++out.occludedBlocks;
            }
        }
    }
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            const auto i = static_cast<std::size_t>(by * b + bx);
            for (int side = 0; side < 4; ++side) {
                const int other = neighbour(bx, by, side);
                out.snap[4 * i + static_cast<std::size_t>(side)] =
                    other < 0 ? out.level[i] : std::max(out.level[i], out.level[static_cast<std::size_t>(other)]);
            }
        }
    }
    return out;
}

BlockLevels drawnBlockLevels(const TessellationErrors& errors, const Aabb& node, const Camera& camera, double pixels,
                             bool hidden, const BoxOccluded& occluded)
{
    // An unbounded budget: every block at its coarsest (none of them showed).
    constexpr double kHiddenBlockPixels = 1e30;
    return hidden ? chooseBlockLevels(errors, node, camera, kHiddenBlockPixels)
                  : chooseBlockLevels(errors, node, camera, pixels, occluded);
}

std::pair<double, double> tessellatedHeights(std::span<const float> surface, int chunkSize, const BlockLevels& levels,
                                             double lx, double ly)
{
    const int n = chunkSize;
    const int q = levels.blockQuads, b = levels.blocksPerSide;
    TERRAIN_EXPECTS(q * b == n - 1, "levels must be for a node of this chunk size");
    lx = std::clamp(lx, 0.0, n - 1.0);
    ly = std::clamp(ly, 0.0, n - 1.0);
    const int bx = std::min(static_cast<int>(lx / q), b - 1), by = std::min(static_cast<int>(ly / q), b - 1);
    const auto block = static_cast<std::size_t>(by * b + bx);
    const int t = levels.level[block];
    const int s = 1 << t, f = q >> t;
    const int snap[4] = {levels.snap[4 * block], levels.snap[4 * block + 1], levels.snap[4 * block + 2],
                         levels.snap[4 * block + 3]};
    const double u = lx - bx * q, v = ly - by * q;
    const int a = std::min(static_cast<int>(u / s), f - 1), c = std::min(static_cast<int>(v / s), f - 1);
    auto h = [&](glm::ivec2 p) -> double { return surface[static_cast<std::size_t>(p.y) * n + p.x]; };
    // The value at (lx, ly) of triangle (p, q, r) when it holds the point.
    auto inside = [&](glm::ivec2 p, glm::ivec2 q2, glm::ivec2 r, double& value) {
        const double area2 =
            static_cast<double>(q2.x - p.x) * (r.y - p.y) - static_cast<double>(q2.y - p.y) * (r.x - p.x);
        if (area2 == 0.0) {
            return false;
        }
        const double wq = ((lx - p.x) * (r.y - p.y) - (ly - p.y) * (r.x - p.x)) / area2;
        const double wr = ((q2.x - p.x) * (ly - p.y) - (q2.y - p.y) * (lx - p.x)) / area2;
        constexpr double kSlack = -1e-9;
        if (wq < kSlack || wr < kSlack || 1.0 - wq - wr < kSlack) {
            return false;
        }
        value = h(p) + wq * (h(q2) - h(p)) + wr * (h(r) - h(p));
        return true;
    };
    auto cellHeights = [&](int ca, int cc, double& first, double& second, bool& foundFirst, bool& foundSecond) {
        const glm::ivec2 v00 = tessellatedVertex(q, bx, by, t, ca, cc, snap);
        const glm::ivec2 v10 = tessellatedVertex(q, bx, by, t, ca + 1, cc, snap);
        const glm::ivec2 v11 = tessellatedVertex(q, bx, by, t, ca + 1, cc + 1, snap);
        const glm::ivec2 v01 = tessellatedVertex(q, bx, by, t, ca, cc + 1, snap);
        if (!foundFirst) {
            foundFirst = inside(v00, v10, v11, first) || inside(v00, v11, v01, first);
        }
        if (!foundSecond) {
            foundSecond = inside(v00, v10, v01, second) || inside(v10, v11, v01, second);
        }
    };
    double first = 0.0, second = 0.0;
    bool foundFirst = false, foundSecond = false;
    const bool ring = a == 0 || c == 0 || a == f - 1 || c == f - 1;
    const bool snapped = snap[0] > t || snap[1] > t || snap[2] > t || snap[3] > t;
    if (!ring || !snapped) {
        cellHeights(a, c, first, second, foundFirst, foundSecond);
    } else {
        // Snapped vertices move along the block's sides: the ring of cells along them still tiles the ring,
        // but a point may lie in another of its cells.
        for (int cc = 0; cc < f && !(foundFirst && foundSecond); ++cc) {
            for (int ca = 0; ca < f && !(foundFirst && foundSecond); ++ca) {
                if (ca == 0 || cc == 0 || ca == f - 1 || cc == f - 1) {
                    cellHeights(ca, cc, first, second, foundFirst, foundSecond);
                }
            }
        }
    }
    TERRAIN_ASSERT(foundFirst && foundSecond);
    return {first, second};
}

std::vector<float> morphedSamples(const NodeData& node, int chunkSize, float morph)
{
    const int n = chunkSize, w = node.heights.size;
    TERRAIN_EXPECTS(w == windowSize(n), "the node's window must be for this chunk size");
    auto at = [&](int i, int j) -> double {
        return node.heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
    };
    std::vector<float> out(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const int dx = i & 1, dy = j & 1;
            const double parent = 0.5 * (at(i - dx, j - dy) + at(i + dx, j + dy));
            out[static_cast<std::size_t>(j) * n + i] = static_cast<float>(morph * at(i, j) + (1.0 - morph) * parent);
        }
    }
    return out;
}

void levelSwitches(std::span<const float> surface, int chunkSize, const BlockLevels& before, const BlockLevels& after,
                   std::vector<LevelSwitch>& out)
{
    TERRAIN_EXPECTS(before.blocksPerSide == after.blocksPerSide && before.blockQuads == after.blockQuads,
                    "levels of the same node");
    const int b = after.blocksPerSide, q = after.blockQuads;
    for (int k = 0; k < b * b; ++k) {
        if (before.code(k) == after.code(k) || after.culled[static_cast<std::size_t>(k)] ||
            before.culled[static_cast<std::size_t>(k)]) {
            continue;
        }
        const int bx = k % b, by = k / b;
        for (int y = 0; y <= 2 * q; ++y) {
            for (int x = 0; x <= 2 * q; ++x) {
                if ((x & 1) != (y & 1)) {
                    continue;  // samples (both even) and quad centres (both odd)
                }
                const double lx = bx * q + x / 2.0, ly = by * q + y / 2.0;
                const auto [b1, b2] = tessellatedHeights(surface, chunkSize, before, lx, ly);
                const auto [a1, a2] = tessellatedHeights(surface, chunkSize, after, lx, ly);
                const double change = std::max(std::abs(a1 - b1), std::abs(a2 - b2));
                if (change > 0.0) {
                    out.push_back({lx, ly, change});
                }
            }
        }
    }
}

}  // namespace terrain
