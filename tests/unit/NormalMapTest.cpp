// Per-node normal maps (synthesis/NormalMap.h, issue 14): the surface below a node against the nodes the
// source makes at those levels and against the height query's surface, the texel normals against planes
// (closed form) and against central differences of queried heights, and neighbouring nodes' maps on their
// shared edges.
#include "MapTestSupport.h"

#include "lod/HeightQuery.h"
#include "lod/TerrainNodeSource.h"
#include "synthesis/LeafErrorEstimator.h"
#include "synthesis/NormalMap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace terrain {
namespace {

constexpr int kChunk = 17;

TEST(NormalMapSizeTest, CellsTexelsAndDepth)
{
    EXPECT_EQ(normalMapCells(128), 128);
    EXPECT_EQ(normalMapCells(129), 128);
    EXPECT_EQ(normalMapTexels(16), 17);
    EXPECT_EQ(normalMapTexels(17), 17);
    // N = 65: 64 cells are the node's own samples, 128 one level below, 256 and more two.
    EXPECT_EQ(normalMapDepth(32, 65), 0);
    EXPECT_EQ(normalMapDepth(64, 65), 0);
    EXPECT_EQ(normalMapDepth(128, 65), 1);
    EXPECT_EQ(normalMapDepth(256, 65), 2);
    EXPECT_EQ(normalMapDepth(4096, 65), 2);
}

/// A window of `cells` + 1 + 2 kBorder samples a side of z = c + a x + b y (x, y in metres).
std::vector<float> planeWindow(int cells, double spacing, double a, double b)
{
    const int w = cells + 1 + 2 * kBorder;
    std::vector<float> window(static_cast<std::size_t>(w) * w);
    for (int j = 0; j < w; ++j) {
        for (int i = 0; i < w; ++i) {
            window[static_cast<std::size_t>(j) * w + i] =
                static_cast<float>(300.0 + a * (i - kBorder) * spacing + b * (j - kBorder) * spacing);
        }
    }
    return window;
}

TEST(NormalMapTest, APlaneHasItsNormalAtEveryTexel)
{
    const double a = 0.37, b = -0.81, spacing = 2.5;
    const double length = std::sqrt(a * a + b * b + 1.0);
    // Fewer texels than samples (8 cells over 32), as many, and more (64 over 16: interpolated).
    for (const auto& [cells, texels] : {std::pair{32, 9}, std::pair{32, 33}, std::pair{16, 65}}) {
        const std::vector<std::int8_t> map = normalMapOf(planeWindow(cells, spacing, a, b), cells, spacing, texels);
        ASSERT_EQ(map.size(), static_cast<std::size_t>(texels) * texels * 2);
        for (std::size_t k = 0; k < map.size(); k += 2) {
            // The float heights round by up to 2^-15 m at 300 m: a 1e-4 slack over the 8-bit rounding.
            ASSERT_NEAR(map[k] / 127.0, -a / length, 0.5 / 127.0 + 1e-4) << cells << " cells, " << texels;
            ASSERT_NEAR(map[k + 1] / 127.0, -b / length, 0.5 / 127.0 + 1e-4) << cells << " cells, " << texels;
        }
    }
}

TEST(NormalMapTest, BetweenSamplesTheGradientsAreInterpolated)
{
    // z = x^2 / 100 over 4 cells of 10 m, 4 texels a cell: the gradient (x / 50, central differences are exact
    // for a parabola) interpolated linearly is exact too.
    const int cells = 4, w = cells + 1 + 2 * kBorder, texels = 17;
    const double spacing = 10.0;
    std::vector<float> window(static_cast<std::size_t>(w) * w);
    for (int j = 0; j < w; ++j) {
        for (int i = 0; i < w; ++i) {
            const double x = (i - kBorder) * spacing;
            window[static_cast<std::size_t>(j) * w + i] = static_cast<float>(x * x / 100.0);
        }
    }
    const std::vector<std::int8_t> map = normalMapOf(window, cells, spacing, texels);
    for (int t = 0; t < texels; ++t) {
        const double x = t * cells * spacing / (texels - 1);
        const double g = x / 50.0;
        EXPECT_NEAR(map[static_cast<std::size_t>(3 * texels + t) * 2] / 127.0, -g / std::sqrt(g * g + 1.0),
                    0.5 / 127.0 + 1e-4)
            << "texel " << t;
        EXPECT_EQ(map[static_cast<std::size_t>(3 * texels + t) * 2 + 1], 0);
    }
}

class NormalMapNodesTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        auto materials = test::grassAndRockSynthesizer(kChunk)->settings().materials;
        BuildOptions options;
        options.chunkSize = kChunk;
        options.spacing = 10.0;
        options.threads = 2;
        // The map's detail errors are not what is tested here: the estimate without roughness will do.
        mPlain = test::grassAndRockSynthesizer(kChunk);
        options.leafDetailError = leafDetailErrorFunction(*mPlain);
        auto report = buildMap(test::hillyField(129, 129), options, mDir / "hills.map");
        ASSERT_TRUE(report.ok()) << report.error().message;
        mMap = test::openMap(mDir / "hills.map", ReaderKind::MemoryMapped);
        ASSERT_TRUE(mMap);
        // As the viewer synthesizes over the map: the roughness continued, the materials relative to it.
        const DetailSettings settings = settingsForMap({"kobbelt", 1.0, materials}, mMap->header(), true);
        ASSERT_TRUE(settings.roughness) << "the map measured its roughness";
        ASSERT_TRUE(settings.materials->hasRelative());
        auto synthesizer = DetailSynthesizer::create(kChunk, settings);
        ASSERT_TRUE(synthesizer.ok()) << synthesizer.error().message;
        mSynthesizer = std::move(synthesizer).value();
    }

    /// The static leaf reached from the root by the south-west child, then north-east ones: towards the map's
    /// centre, not on its border.
    static NodePtr staticLeaf(TerrainNodeSource& source)
    {
        NodePtr at = source.loadRoot().value();
        while (at->hasStaticChildren) {
            at = (*source.loadChildren(*at))[at->id.isRoot() ? 0 : 3];
        }
        return at;
    }

    test::ScratchDir mDir;
    std::unique_ptr<const DetailSynthesizer> mPlain;
    std::unique_ptr<MapFile> mMap;
    std::unique_ptr<const DetailSynthesizer> mSynthesizer;
};

TEST_F(NormalMapNodesTest, TheSurfaceBelowIsWhatTheDescendantsDraw)
{
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.0, 0, 0});
    const NodePtr leaf = staticLeaf(source);
    ASSERT_FALSE(leaf->hasStaticChildren);
    const int cells = kChunk - 1, w = windowSize(kChunk);
    for (const NodePtr& node : {leaf, (*source.loadChildren(*leaf))[1]}) {
        const WindowPlacement where = source.placement(node->id);
        for (int depth = 0; depth <= kMaxNormalMapDepth; ++depth) {
            const std::vector<float> below = surfaceBelow(*mSynthesizer, node->heights, where, depth);
            const int fine = cells << depth, fw = fine + 1 + 2 * kBorder;
            ASSERT_EQ(below.size(), static_cast<std::size_t>(fw) * fw);
            // Every descendant at that depth: its inner samples (edges shared with its neighbours included) are
            // the window's, bit for bit.
            std::vector<NodePtr> level{node};
            for (int d = 0; d < depth; ++d) {
                std::vector<NodePtr> next;
                for (const NodePtr& parent : level) {
                    auto children = source.loadChildren(*parent);
                    ASSERT_TRUE(children.ok()) << children.error().message;
                    next.insert(next.end(), children->begin(), children->end());
                }
                level = std::move(next);
            }
            for (const NodePtr& descendant : level) {
                const int ox = static_cast<int>(descendant->id.x - (node->id.x << depth)) * cells;
                const int oy = static_cast<int>(descendant->id.y - (node->id.y << depth)) * cells;
                std::vector<float> surface(descendant->heights.base.size());
                descendant->heights.surface(surface);
                for (int j = 0; j < kChunk; ++j) {
                    for (int i = 0; i < kChunk; ++i) {
                        const float expected = surface[static_cast<std::size_t>(j + kBorder) * w + i + kBorder];
                        const float got = below[static_cast<std::size_t>(oy + j + kBorder) * fw + ox + i + kBorder];
                        ASSERT_EQ(std::memcmp(&expected, &got, sizeof(float)), 0)
                            << descendant->id.toString() << " sample " << i << "," << j << " depth " << depth;
                    }
                }
            }
        }
    }
}

TEST_F(NormalMapNodesTest, TexelNormalsAreTheQueriedSurfacesNormals)
{
    // A map of 4x the node's cells samples the surface two levels below: its texels' normals against central
    // differences of surfaceHeightAt at that level (the height query's own path from the root, SurfaceSampler).
    const int size = 4 * (kChunk - 1);
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.0, 0, size});
    const NodePtr leaf = staticLeaf(source);
    const NodePtr node = (*source.loadChildren(*leaf))[2];
    ASSERT_EQ(node->normalMap.size(), static_cast<std::size_t>(size + 1) * (size + 1) * 2);
    const WindowPlacement where = source.placement(node->id);
    const double fine = where.spacing / 4.0;
    const double x0 = where.originX + static_cast<double>(where.gx0 + kBorder) * where.spacing;
    const double y0 = where.originY + static_cast<double>(where.gy0 + kBorder) * where.spacing;
    // The queries through a source of their own, which makes no normal maps.
    TerrainNodeSource plain(*mMap, {mSynthesizer.get(), 0.0, 0, 0});
    SurfaceSampler sampler(*mMap, plain, node->id.level + 2);
    double worst = 0.0;
    for (int tj = 0; tj <= size; tj += 2) {
        for (int ti = 0; ti <= size; ti += 1) {
            const double x = x0 + ti * fine, y = y0 + tj * fine;
            auto h = [&](double px, double py) {
                auto sample = sampler.at(px, py);
                EXPECT_TRUE(sample.ok()) << sample.error().message;
                return sample.ok() ? sample->height : 0.0;
            };
            const double gx = (h(x + fine, y) - h(x - fine, y)) / (2.0 * fine);
            const double gy = (h(x, y + fine) - h(x, y - fine)) / (2.0 * fine);
            const double length = std::sqrt(gx * gx + gy * gy + 1.0);
            const std::int8_t* texel = node->normalMap.data() + (static_cast<std::size_t>(tj) * (size + 1) + ti) * 2;
            worst =
                std::max({worst, std::abs(texel[0] / 127.0 + gx / length), std::abs(texel[1] / 127.0 + gy / length)});
        }
    }
    // 8-bit rounding (0.5 / 127) and the float heights. rounding over a 0.625 m difference.
    EXPECT_LE(worst, 0.5 / 127.0 + 1e-4);
    std::printf("normal map texels against the queried surface: worst %.5f\n", worst);
    // And the map is not flat: the detail below shows.
    int tilted = 0;
    for (std::size_t k = 0; k < node->normalMap.size(); k += 2) {
        tilted += std::abs(node->normalMap[k]) > 6 ? 1 : 0;
    }
    EXPECT_GT(tilted, 10);
}

TEST_F(NormalMapNodesTest, NeighboursAgreeOnTheirSharedEdge)
{
    // Siblings and cousins (across two static leaves), one and two levels below the leaves: the texels on a
    // shared edge are the same bits, so the lighting has no seam between nodes of one level.
    const int size = 2 * (kChunk - 1);
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.0, 0, size});
    const NodePtr leaf = staticLeaf(source);
    ASSERT_TRUE(leaf->id.x > 0);
    auto parent = source.loadRoot();
    ASSERT_TRUE(parent.ok());
    // The leaf's west neighbour, found from the root.
    const NodeId westId{leaf->id.level, leaf->id.x - 1, leaf->id.y};
    NodePtr west = parent.value();
    while (west->id.level < westId.level) {
        const int shift = westId.level - west->id.level - 1;
        const int q = static_cast<int>(((westId.x >> shift) & 1u) | (((westId.y >> shift) & 1u) << 1));
        west = (*source.loadChildren(*west))[static_cast<std::size_t>(q)];
    }
    ASSERT_EQ(west->id, westId);
    const int t = size + 1;
    auto edgeEqual = [&](const NodeData& a, const NodeData& b, const char* what) {
        // a lies west of b: a's east column is b's west column.
        ASSERT_EQ(a.normalMap.size(), b.normalMap.size());
        for (int j = 0; j < t; ++j) {
            for (int c = 0; c < 2; ++c) {
                ASSERT_EQ(a.normalMap[(static_cast<std::size_t>(j) * t + t - 1) * 2 + c],
                          b.normalMap[(static_cast<std::size_t>(j) * t) * 2 + c])
                    << what << " texel row " << j;
            }
        }
    };
    const ChildNodes own = *source.loadChildren(*leaf);
    const ChildNodes theirs = *source.loadChildren(*west);
    edgeEqual(*own[0], *own[1], "siblings");
    edgeEqual(*theirs[1], *own[0], "cousins");
    const ChildNodes ownBelow = *source.loadChildren(*own[0]);
    const ChildNodes theirsBelow = *source.loadChildren(*theirs[1]);
    edgeEqual(*theirsBelow[1], *ownBelow[0], "cousins one level deeper");
}

TEST_F(NormalMapNodesTest, WithoutDetailTheMapIsOfTheSubdividedData)
{
    TerrainNodeSource none(*mMap, {nullptr, 0.0, 0, 0});
    EXPECT_TRUE(none.loadRoot().value()->normalMap.empty());
    TerrainNodeSource source(*mMap, {nullptr, 0.0, 0, 32});
    const NodePtr root = source.loadRoot().value();
    ASSERT_EQ(root->normalMap.size(), static_cast<std::size_t>(33 * 33 * 2));
    // Subdivision alone: the normals of the Kobbelt-subdivided static surface.
    auto kobbelt = DetailSynthesizer::create(kChunk, DetailSettings{}).value();
    const std::vector<float> below = surfaceBelow(*kobbelt, root->heights, source.placement(root->id), 1);
    EXPECT_EQ(root->normalMap, normalMapOf(below, 2 * (kChunk - 1), root->spacing / 2.0, 33));
}

}  // namespace
}  // namespace terrain
