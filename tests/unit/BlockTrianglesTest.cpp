// Tessellation blocks as template index lists (gpudata/BlockTriangles.h), checked over many random block levels:
// the drawn blocks tile their squares exactly with no T-junction (every inner edge met once each way, every border
// edge by a skirt), their surface is the one the error meter evaluates (tessellatedHeights), level 0 everywhere is
// the template's own triangulation (the zigzag index buffer), and culled blocks give nothing.
#include "MapTestSupport.h"

#include "gpudata/BlockTriangles.h"
#include "gpudata/TemplateMesh.h"
#include "gpudata/ZigzagIndexBuffer.h"
#include "lod/TessellationLevels.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

namespace terrain {
namespace {

/// Random block levels as chooseBlockLevels makes them: each side's lattice the coarser of the two blocks' (the
/// block's own on the node's border and beside a culled block).
BlockLevels randomLevels(int n, int q, std::mt19937& random, double culledShare)
{
    BlockLevels levels;
    levels.blockQuads = q;
    levels.blocksPerSide = (n - 1) / q;
    const int b = levels.blocksPerSide, most = std::countr_zero(static_cast<unsigned>(q));
    const auto blocks = static_cast<std::size_t>(b) * b;
    levels.level.resize(blocks);
    levels.culled.resize(blocks);
    levels.snap.resize(4 * blocks);
    std::uniform_int_distribution<int> level(0, most);
    std::bernoulli_distribution culled(culledShare);
    for (std::size_t k = 0; k < blocks; ++k) {
        levels.level[k] = static_cast<std::uint8_t>(level(random));
        levels.culled[k] = culled(random) ? 1 : 0;
    }
    static constexpr int kDx[4] = {0, 1, 0, -1}, kDy[4] = {-1, 0, 1, 0};
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            const auto k = static_cast<std::size_t>(by * b + bx);
            for (int side = 0; side < 4; ++side) {
                const int nx = bx + kDx[side], ny = by + kDy[side];
                const bool drawn =
                    nx >= 0 && ny >= 0 && nx < b && ny < b && !levels.culled[static_cast<std::size_t>(ny * b + nx)];
                levels.snap[4 * k + static_cast<std::size_t>(side)] =
                    drawn ? std::max(levels.level[k], levels.level[static_cast<std::size_t>(ny * b + nx)])
                          : levels.level[k];
            }
        }
    }
    return levels;
}

struct Point {
    double x = 0.0, y = 0.0;
};

/// A template vertex's grid position; skirt vertices have their edge vertex's.
Point positionOf(const TemplateMesh& mesh, std::uint32_t index)
{
    const TemplateVertex& v = mesh.vertices.at(index);
    return {static_cast<double>(v.i), static_cast<double>(v.j)};
}

bool isSkirt(const TemplateMesh& mesh, std::uint32_t index)
{
    return mesh.vertices.at(index).skirt != 0;
}

class BlockTrianglesTest : public ::testing::TestWithParam<std::pair<int, int>> {};

TEST_P(BlockTrianglesTest, DrawnBlocksTileTheirSquaresWithoutTJunctions)
{
    const auto [n, q] = GetParam();
    const TemplateMesh mesh = buildTemplateMesh(n);
    const BlockTriangles triangles(n, q);
    std::mt19937 random(static_cast<unsigned>(n * 31 + q));
    for (int trial = 0; trial < 200; ++trial) {
        const BlockLevels levels = randomLevels(n, q, random, 0.0);
        std::vector<std::uint32_t> indices = {7, 7, 7};  // appended after what is there
        const std::uint64_t count = triangles.append(levels, indices);
        ASSERT_EQ(indices.size(), 3 + 3 * count);
        std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
        double area = 0.0;
        std::uint64_t skirtTriangles = 0, expectedSkirts = 0, expectedSurface = 0;
        for (std::size_t k = 3; k < indices.size(); k += 3) {
            const std::array<std::uint32_t, 3> t = {indices[k], indices[k + 1], indices[k + 2]};
            for (int e = 0; e < 3; ++e) {
                ++edges[{t[static_cast<std::size_t>(e)], t[static_cast<std::size_t>((e + 1) % 3)]}];
            }
            if (isSkirt(mesh, t[0]) || isSkirt(mesh, t[1]) || isSkirt(mesh, t[2])) {
                ++skirtTriangles;
                continue;
            }
            const Point a = positionOf(mesh, t[0]), b = positionOf(mesh, t[1]), c = positionOf(mesh, t[2]);
            const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
            ASSERT_GT(area2, 0.0) << "surface triangles are counter-clockwise from above, none degenerate";
            area += 0.5 * area2;
        }
        const int b = levels.blocksPerSide;
        for (int by = 0; by < b; ++by) {
            for (int bx = 0; bx < b; ++bx) {
                const auto k = static_cast<std::size_t>(by * b + bx);
                const int f = q >> levels.level[k];
                const int borders = (bx == 0) + (by == 0) + (bx == b - 1) + (by == b - 1);
                expectedSkirts += static_cast<std::uint64_t>(2 * f * borders);
                const int snap[4] = {levels.snap[4 * k], levels.snap[4 * k + 1], levels.snap[4 * k + 2],
                                     levels.snap[4 * k + 3]};
                // The cells' two triangles each, less those the snapping collapses (two corners made one).
                std::uint64_t cells = 0;
                for (int c = 0; c < f; ++c) {
                    for (int a = 0; a < f; ++a) {
                        const int t = levels.level[k];
                        const glm::ivec2 v00 = tessellatedVertex(q, bx, by, t, a, c, snap);
                        const glm::ivec2 v10 = tessellatedVertex(q, bx, by, t, a + 1, c, snap);
                        const glm::ivec2 v11 = tessellatedVertex(q, bx, by, t, a + 1, c + 1, snap);
                        const glm::ivec2 v01 = tessellatedVertex(q, bx, by, t, a, c + 1, snap);
                        cells += (v00 != v10 && v10 != v11 && v00 != v11) ? 1 : 0;
                        cells += (v11 != v01 && v01 != v00 && v00 != v11) ? 1 : 0;
                    }
                }
                EXPECT_EQ(triangles.surfaceTriangles(levels.level[k], snap), cells);
                expectedSurface += cells;
            }
        }
        EXPECT_DOUBLE_EQ(area, static_cast<double>(n - 1) * (n - 1)) << "the surface covers the node once";
        EXPECT_EQ(skirtTriangles, expectedSkirts) << "two triangles a border cell";
        EXPECT_EQ(count, expectedSurface + expectedSkirts);
        // Every directed edge once, and met by its reverse, except the skirts' free edges: along the bottom and
        // down the node's corners (the ring's vertices meet there, so those close too) none is left.
        for (const auto& [edge, uses] : edges) {
            ASSERT_EQ(uses, 1) << "edge " << edge.first << " -> " << edge.second;
            const bool bottom = isSkirt(mesh, edge.first) && isSkirt(mesh, edge.second);
            if (!bottom) {
                EXPECT_EQ(edges.count({edge.second, edge.first}), 1u)
                    << "edge " << edge.first << " -> " << edge.second << " has no neighbour: a crack";
            }
        }
    }
}

TEST_P(BlockTrianglesTest, SurfaceIsWhatTheErrorMeterEvaluates)
{
    const auto [n, q] = GetParam();
    const TemplateMesh mesh = buildTemplateMesh(n);
    const BlockTriangles triangles(n, q);
    std::vector<float> surface(static_cast<std::size_t>(n) * n);
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            surface[static_cast<std::size_t>(j) * n + i] = static_cast<float>(100.0 * test::unitNoise(5, i, j));
        }
    }
    std::mt19937 random(static_cast<unsigned>(n + q));
    std::uniform_real_distribution<double> coordinate(0.0, n - 1.0);
    for (int trial = 0; trial < 50; ++trial) {
        const BlockLevels levels = randomLevels(n, q, random, 0.0);
        std::vector<std::uint32_t> indices;
        triangles.append(levels, indices);
        for (int point = 0; point < 200; ++point) {
            const double x = coordinate(random), y = coordinate(random);
            int found = 0;
            double height = 0.0;
            for (std::size_t k = 0; k < indices.size(); k += 3) {
                if (isSkirt(mesh, indices[k]) || isSkirt(mesh, indices[k + 1]) || isSkirt(mesh, indices[k + 2])) {
                    continue;
                }
                const Point a = positionOf(mesh, indices[k]), b = positionOf(mesh, indices[k + 1]),
                            c = positionOf(mesh, indices[k + 2]);
                const double area2 = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
                const double wb = ((x - a.x) * (c.y - a.y) - (y - a.y) * (c.x - a.x)) / area2;
                const double wc = ((b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)) / area2;
                if (wb < 0.0 || wc < 0.0 || wb + wc > 1.0) {
                    continue;
                }
                ++found;
                auto h = [&](std::uint32_t v) { return double{surface[v]}; };
                height = (1.0 - wb - wc) * h(indices[k]) + wb * h(indices[k + 1]) + wc * h(indices[k + 2]);
            }
            ASSERT_EQ(found, 1) << "a random point inside the node lies in one triangle";
            EXPECT_NEAR(height, tessellatedHeights(surface, n, levels, x, y).first, 1e-9)
                << "the south-west to north-east split, as the error meter's first diagonal";
        }
    }
}

TEST_P(BlockTrianglesTest, FinestLevelIsTheTemplateTriangulation)
{
    const auto [n, q] = GetParam();
    const BlockTriangles triangles(n, q);
    BlockLevels levels;
    levels.blockQuads = q;
    levels.blocksPerSide = (n - 1) / q;
    const auto blocks = static_cast<std::size_t>(levels.blocksPerSide) * levels.blocksPerSide;
    levels.level.assign(blocks, 0);
    levels.snap.assign(4 * blocks, 0);
    levels.culled.assign(blocks, 0);
    std::vector<std::uint32_t> indices;
    triangles.append(levels, indices);
    // As sets of triangles, each rotated to start at its smallest index (the winding kept).
    auto triangleSet = [](const std::vector<std::uint32_t>& list) {
        std::multiset<std::array<std::uint32_t, 3>> out;
        for (std::size_t k = 0; k < list.size(); k += 3) {
            std::array<std::uint32_t, 3> t = {list[k], list[k + 1], list[k + 2]};
            std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
            out.insert(t);
        }
        return out;
    };
    EXPECT_EQ(triangleSet(indices), triangleSet(buildZigzagIndices(n, 16, /*withSkirts=*/true)));
}

TEST_P(BlockTrianglesTest, CulledBlocksGiveNothing)
{
    const auto [n, q] = GetParam();
    const BlockTriangles triangles(n, q);
    std::mt19937 random(static_cast<unsigned>(3 * n + q));
    for (int trial = 0; trial < 50; ++trial) {
        const BlockLevels levels = randomLevels(n, q, random, 0.4);
        BlockLevels drawnOnly = levels;
        std::vector<std::uint32_t> all, none;
        triangles.append(levels, all);
        double area = 0.0;
        const TemplateMesh mesh = buildTemplateMesh(n);
        for (std::size_t k = 0; k < all.size(); k += 3) {
            if (isSkirt(mesh, all[k]) || isSkirt(mesh, all[k + 1]) || isSkirt(mesh, all[k + 2])) {
                continue;
            }
            const Point a = positionOf(mesh, all[k]), b = positionOf(mesh, all[k + 1]),
                        c = positionOf(mesh, all[k + 2]);
            area += 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
        }
        const auto drawn = static_cast<double>(std::count(levels.culled.begin(), levels.culled.end(), 0));
        EXPECT_DOUBLE_EQ(area, drawn * q * q);
        std::fill(drawnOnly.culled.begin(), drawnOnly.culled.end(), 1);
        EXPECT_EQ(triangles.append(drawnOnly, none), 0u);
        EXPECT_TRUE(none.empty());
    }
}

INSTANTIATE_TEST_SUITE_P(ChunkAndBlockSizes, BlockTrianglesTest,
                         ::testing::Values(std::pair{65, 8}, std::pair{33, 4}, std::pair{17, 2}, std::pair{129, 8}));

}  // namespace
}  // namespace terrain
