#include "gpudata/BlockTriangles.h"

#include "core/Check.h"
#include "gpudata/TemplateMesh.h"
#include "lod/BlockErrors.h"

#include <array>
#include <bit>

namespace terrain {

BlockTriangles::BlockTriangles(int chunkSize, int blockQuads) : mChunkSize(chunkSize), mBlockQuads(blockQuads)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "a valid chunk size");
    TERRAIN_EXPECTS(
        blockQuads >= 2 && std::has_single_bit(static_cast<unsigned>(blockQuads)) && (chunkSize - 1) % blockQuads == 0,
        "blocks must be a power of two >= 2 quads a side that divides N - 1");
    mLevels = std::countr_zero(static_cast<unsigned>(blockQuads));
    TERRAIN_EXPECTS(mLevels <= kBlockLevelMask, "a block's levels fit a block code");
    const auto levels = static_cast<std::size_t>(mLevels + 1);
    mPatternStart.assign(levels * levels * levels * levels * levels + 1, 0);
    const auto n = static_cast<std::uint32_t>(chunkSize);
    auto offset = [n](glm::ivec2 v) { return static_cast<std::uint32_t>(v.y) * n + static_cast<std::uint32_t>(v.x); };
    // Every index in order, so the patterns of the combinations that cannot occur (a side below t) stay empty.
    for (std::size_t k = 0; k + 1 < mPatternStart.size(); ++k) {
        mPatternStart[k] = mPatterns.size();
        std::size_t rest = k;
        const int t = static_cast<int>(rest % levels);
        int snap[4];
        bool valid = true;
        for (int& side : snap) {
            rest /= levels;
            side = static_cast<int>(rest % levels);
            valid = valid && side >= t;
        }
        if (!valid) {
            continue;
        }
        const int f = blockQuads >> t;
        for (int c = 0; c < f; ++c) {
            for (int a = 0; a < f; ++a) {
                const glm::ivec2 v00 = tessellatedVertex(blockQuads, 0, 0, t, a, c, snap);
                const glm::ivec2 v10 = tessellatedVertex(blockQuads, 0, 0, t, a + 1, c, snap);
                const glm::ivec2 v11 = tessellatedVertex(blockQuads, 0, 0, t, a + 1, c + 1, snap);
                const glm::ivec2 v01 = tessellatedVertex(blockQuads, 0, 0, t, a, c + 1, snap);
                for (const auto& [p, q, r] : {std::array{v00, v10, v11}, std::array{v00, v11, v01}}) {
                    const long area2 =
                        static_cast<long>(q.x - p.x) * (r.y - p.y) - static_cast<long>(q.y - p.y) * (r.x - p.x);
                    if (area2 != 0) {
                        TERRAIN_ASSERT(area2 > 0);
                        mPatterns.insert(mPatterns.end(), {offset(p), offset(q), offset(r)});
                    }
                }
            }
        }
    }
    mPatternStart.back() = mPatterns.size();
}

std::size_t BlockTriangles::patternIndex(int t, const int snap[4]) const
{
    const int levels = mLevels + 1;
    TERRAIN_EXPECTS(t >= 0 && t <= mLevels, "block level out of range");
    std::size_t k = 0;
    for (int side = 3; side >= 0; --side) {
        TERRAIN_EXPECTS(snap[side] >= t && snap[side] <= mLevels, "a side's lattice is between t and the coarsest");
        k = k * static_cast<std::size_t>(levels) + static_cast<std::size_t>(snap[side]);
    }
    return k * static_cast<std::size_t>(levels) + static_cast<std::size_t>(t);
}

std::uint64_t BlockTriangles::surfaceTriangles(int t, const int snap[4]) const
{
    const std::size_t k = patternIndex(t, snap);
    return (mPatternStart[k + 1] - mPatternStart[k]) / 3;
}

std::uint64_t BlockTriangles::append(const BlockLevels& levels, std::vector<std::uint32_t>& out) const
{
    const int b = levels.blocksPerSide, q = mBlockQuads, n = mChunkSize;
    TERRAIN_EXPECTS(levels.blockQuads == q && b * q == n - 1, "levels must be for this chunk and block size");
    const int side = n - 1, ring = skirtRingLength(n);
    const std::size_t before = out.size();
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            const auto block = static_cast<std::size_t>(by * b + bx);
            if (levels.culled[block]) {
                continue;
            }
            const int t = levels.level[block];
            const int snap[4] = {levels.snap[4 * block], levels.snap[4 * block + 1], levels.snap[4 * block + 2],
                                 levels.snap[4 * block + 3]};
            const std::size_t k = patternIndex(t, snap);
            const std::uint32_t base = gridVertexIndex(n, bx * q, by * q);
            for (std::size_t i = mPatternStart[k]; i < mPatternStart[k + 1]; ++i) {
                out.push_back(base + mPatterns[i]);
            }
            // Skirts along the node's border: the ring runs counter-clockwise seen from above (south going east,
            // east going north, north going west, west going south), its outside to the right.
            const int s = 1 << t, f = q >> t;
            auto skirt = [&](int first) {
                for (int c = 0; c < f; ++c) {
                    const int a = first + c * s, e = (a + s) % ring;
                    const GridCoord ca = skirtRingCoord(n, a), ce = skirtRingCoord(n, e);
                    const std::uint32_t ta = gridVertexIndex(n, ca.i, ca.j), te = gridVertexIndex(n, ce.i, ce.j);
                    const std::uint32_t sa = skirtVertexIndex(n, a), se = skirtVertexIndex(n, e);
                    out.insert(out.end(), {ta, sa, te, te, sa, se});
                }
            };
            if (by == 0) {
                skirt(bx * q);
            }
            if (bx == b - 1) {
                skirt(side + by * q);
            }
            if (by == b - 1) {
                skirt(2 * side + (side - (bx + 1) * q));
            }
            if (bx == 0) {
                skirt(3 * side + (side - (by + 1) * q));
            }
        }
    }
    return (out.size() - before) / 3;
}

}  // namespace terrain
