// The horizons of the quadtree's nodes (lod/NodeHorizons.h): the static map as one grid against the map's own
// nodes, every node's lattice against horizons searched from scratch at its samples, neighbours' shared edges,
// and children's copies of their parent's lattice.
#include "MapTestSupport.h"

#include "lod/NodeHorizons.h"
#include "lod/TerrainNodeSource.h"
#include "synthesis/LeafErrorEstimator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace terrain {
namespace {

class NodeHorizonsTest : public ::testing::Test {
protected:
    static constexpr int kChunk = 17;

    void SetUp() override
    {
        mSynthesizer = test::grassAndRockSynthesizer(kChunk);
        mMap = test::detailErrorMap(test::hillyField(129, 129), 10.0, *mSynthesizer, mDir / "hills.map");
        ASSERT_TRUE(mMap);
    }

    test::ScratchDir mDir;
    std::unique_ptr<const DetailSynthesizer> mSynthesizer;
    std::unique_ptr<MapFile> mMap;
};

TEST(NodeHorizonsLatticeTest, APointASampleUntilTheNodeIsFinerThanTheGridThenAsFineAsTheGrid)
{
    EXPECT_EQ(horizonLatticeSize(65, 360.0, 90.0), 65);
    EXPECT_EQ(horizonLatticeSize(65, 90.0, 90.0), 65);
    EXPECT_EQ(horizonLatticeSize(65, 45.0, 90.0), 33);  // every other sample: 90 m apart
    EXPECT_EQ(horizonLatticeSize(65, 60.0, 90.0), 65);  // two samples would be 120 m apart
    EXPECT_EQ(horizonLatticeSize(65, 22.5, 90.0), 17);
    EXPECT_EQ(horizonLatticeSize(65, 11.25, 90.0), 9);
    EXPECT_EQ(horizonLatticeSize(65, 0.01, 90.0), kMinHorizonLattice);
    EXPECT_EQ(horizonLatticeSize(5, 0.01, 90.0), 5);
    EXPECT_EQ(horizonLatticeSize(17, 1.0, 8.0), 9);
}

TEST_F(NodeHorizonsTest, TheGridIsTheFinestStaticLevelThatFits)
{
    const MapHeader& h = mMap->header();
    ASSERT_EQ(h.levels, 4u);  // 129 samples in 17-sample chunks: 8 x 8 leaves
    auto grid = staticHeightGrid(*mMap, 129);
    ASSERT_TRUE(grid.ok()) << grid.error().message;
    ASSERT_EQ(grid->width, 129);
    EXPECT_DOUBLE_EQ(grid->spacing, h.spacingAt(3));
    // Every leaf's samples, as the map decodes them, are the grid's.
    for (std::uint32_t y = 0; y < 8; ++y) {
        for (std::uint32_t x = 0; x < 8; ++x) {
            auto node = mMap->loadPath({3, x, y});
            ASSERT_TRUE(node.ok()) << node.error().message;
            const int w = h.windowSize();
            for (int j = 0; j < kChunk; ++j) {
                for (int i = 0; i < kChunk; ++i) {
                    const double want =
                        h.heightStep * node->heights[static_cast<std::size_t>((j + kBorder) * w + i + kBorder)];
                    const auto gi = static_cast<std::size_t>(x * 16 + static_cast<std::uint32_t>(i));
                    const auto gj = static_cast<std::size_t>(y * 16 + static_cast<std::uint32_t>(j));
                    ASSERT_FLOAT_EQ(grid->heights[gj * 129 + gi], static_cast<float>(want)) << x << " " << y;
                }
            }
        }
    }
    EXPECT_GE(grid->top, *std::max_element(grid->heights.begin(), grid->heights.end()));
    // A smaller grid is a coarser level: level 2's samples, every other leaf sample.
    auto coarse = staticHeightGrid(*mMap, 100);
    ASSERT_TRUE(coarse.ok());
    ASSERT_EQ(coarse->width, 65);
    EXPECT_DOUBLE_EQ(coarse->spacing, h.spacingAt(2));
    for (int j = 0; j < 65; j += 5) {
        for (int i = 0; i < 65; i += 3) {
            EXPECT_FLOAT_EQ(coarse->heights[static_cast<std::size_t>(j * 65 + i)],
                            grid->heights[static_cast<std::size_t>(2 * j * 129 + 2 * i)]);
        }
    }
}

// A damaged leaf does not stop the grid: its square gets its parent's samples (bilinear), and its error is kept.
TEST_F(NodeHorizonsTest, ADamagedNodeHasItsParentsSamplesAndItsErrorIsKept)
{
    const NodeId victim{3, 5, 2};
    const DirectoryEntry* entry = mMap->find(victim);
    ASSERT_NE(entry, nullptr);
    auto parent = mMap->loadPath(victim.parent());
    ASSERT_TRUE(parent.ok());
    const auto damaged = mDir / "damaged.map";
    std::filesystem::copy_file(mDir / "hills.map", damaged);
    ASSERT_TRUE(test::flipBits(damaged, entry->offset + entry->payloadBytes() / 3, 0x10));
    auto map = MapFile::open(damaged, ReaderKind::Stream);
    ASSERT_TRUE(map.ok()) << map.error().message;
    std::vector<std::string> unreadable;
    auto grid = staticHeightGrid(**map, 129, &unreadable);
    ASSERT_TRUE(grid.ok()) << grid.error().message;
    ASSERT_EQ(unreadable.size(), 1u);
    EXPECT_NE(unreadable[0].find("node " + victim.toString()), std::string::npos) << unreadable[0];
    auto sound = staticHeightGrid(*mMap, 129);
    ASSERT_TRUE(sound.ok());
    const MapHeader& h = mMap->header();
    const int w = h.windowSize();
    int differing = 0;
    for (int j = 0; j < 129; ++j) {
        for (int i = 0; i < 129; ++i) {
            const float got = grid->heights[static_cast<std::size_t>(j * 129 + i)];
            // Leaf (5, 2) covers samples 80-96 x 32-48; its edges are its sound neighbours' too (either may be there).
            const bool inside = i > 80 && i < 96 && j > 32 && j < 48;
            const bool edge = !inside && i >= 80 && i <= 96 && j >= 32 && j <= 48;
            if (edge) {
                continue;
            }
            if (!inside) {
                ASSERT_FLOAT_EQ(got, sound->heights[static_cast<std::size_t>(j * 129 + i)]) << i << " " << j;
                continue;
            }
            // Its parent, level 2's (2, 1), covers samples 64-96 x 32-64 at every other sample.
            const double u = (i - 64) / 2.0, v = (j - 32) / 2.0;
            const int u0 = std::min(static_cast<int>(u), kChunk - 2), v0 = std::min(static_cast<int>(v), kChunk - 2);
            auto at = [&](int a, int b) {
                return h.heightStep * parent->heights[static_cast<std::size_t>((b + kBorder) * w + a + kBorder)];
            };
            const double fu = u - u0, fv = v - v0;
            const double want = (1 - fv) * ((1 - fu) * at(u0, v0) + fu * at(u0 + 1, v0)) +
                                fv * ((1 - fu) * at(u0, v0 + 1) + fu * at(u0 + 1, v0 + 1));
            ASSERT_NEAR(got, want, 1e-3) << i << " " << j;
            differing += got != sound->heights[static_cast<std::size_t>(j * 129 + i)];
        }
    }
    EXPECT_GT(differing, 0) << "the leaf's own samples differ from its parent's interpolation somewhere";
}

// Through the source as the viewer makes its nodes: static and dynamic nodes carry lattices whose codes are the
// horizons at their samples; neighbours of a level agree on their shared edge; a child's parent lattice is its
// parent's quarter.
TEST_F(NodeHorizonsTest, NodesCarryTheirHorizonsSeamlesslyAndTheirParentsQuarter)
{
    auto grid = staticHeightGrid(*mMap, 2049);
    ASSERT_TRUE(grid.ok());
    DetailPolicy policy{mSynthesizer.get()};
    policy.horizonGrid = std::make_shared<const HeightGrid>(std::move(grid).value());
    policy.horizonOptions = {8, 3000.0, 0.2};
    TerrainNodeSource source(*mMap, policy);
    auto root = source.loadRoot();
    ASSERT_TRUE(root.ok()) << root.error().message;
    // Levels 0-3 static, 4-5 dynamic, below one corner at each level (every node of a level's children).
    std::map<std::uint64_t, NodePtr> nodes{{(*root)->id.key(), *root}};
    std::vector<NodePtr> level{*root};
    for (int depth = 1; depth <= 5; ++depth) {
        std::vector<NodePtr> next;
        for (const NodePtr& parent : level) {
            auto children = source.loadChildren(*parent);
            ASSERT_TRUE(children.ok()) << children.error().message;
            for (int q = 0; q < 4; ++q) {
                const NodePtr& child = (*children)[static_cast<std::size_t>(q)];
                ASSERT_EQ(child->horizons.size,
                          horizonLatticeSize(kChunk, child->spacing, policy.horizonGrid->spacing));
                const HorizonLattice quarter = latticeQuadrant(parent->horizons, q);
                EXPECT_EQ(child->parentHorizons.codes, quarter.codes) << child->id.toString();
                EXPECT_EQ(child->parentHorizons.size, quarter.size);
                nodes[child->id.key()] = child;
                next.push_back(child);
            }
        }
        // Past the static levels only the south-west node's children go on (4^5 nodes would be slow).
        level = depth < 3 ? next : std::vector<NodePtr>(next.begin(), next.begin() + 4);
    }
    int edges = 0, dynamicNodes = 0;
    for (const auto& [key, node] : nodes) {
        dynamicNodes += node->isStatic ? 0 : 1;
        // The lattice against horizons searched at the node's samples from scratch.
        std::vector<float> window(node->heights.base.size());
        node->heights.surface(window);
        const WindowPlacement where = source.placement(node->id);
        const HorizonLattice again =
            nodeHorizons(*policy.horizonGrid, where, window, kChunk, node->horizons.size, policy.horizonOptions);
        ASSERT_EQ(again.codes, node->horizons.codes) << node->id.toString();
        const int stride = (kChunk - 1) / (node->horizons.size - 1);
        const int l = node->horizons.size, a = node->horizons.azimuths;
        const int i = l / 2, w = node->heights.size;
        const double x = where.originX + static_cast<double>(where.gx0 + kBorder + i * stride) * where.spacing;
        const double y = where.originY + static_cast<double>(where.gy0 + kBorder) * where.spacing;
        const double z = window[static_cast<std::size_t>(kBorder * w + kBorder + i * stride)];
        const std::vector<float> t = horizonTangents(*policy.horizonGrid, x, y,
                                                     std::max(z, policy.horizonGrid->at(x, y)), policy.horizonOptions);
        for (int k = 0; k < a; ++k) {
            ASSERT_EQ(node->horizons.codes[static_cast<std::size_t>(i * a + k)],
                      encodeHorizon(t[static_cast<std::size_t>(k)]));
        }
        // The east neighbour at the same level, where made: its west edge is this node's east edge.
        const NodeId east{node->id.level, node->id.x + 1, node->id.y};
        if (auto it = nodes.find(east.key()); it != nodes.end() && it->second->id.level == east.level &&
                                              it->second->id.x == east.x && it->second->id.y == east.y) {
            for (int j = 0; j < l; ++j) {
                for (int k = 0; k < a; ++k) {
                    ASSERT_EQ(node->horizons.codes[static_cast<std::size_t>((j * l + l - 1) * a + k)],
                              it->second->horizons.codes[static_cast<std::size_t>((j * l) * a + k)])
                        << node->id.toString() << " row " << j;
                }
            }
            ++edges;
        }
    }
    EXPECT_GT(dynamicNodes, 8);
    EXPECT_GT(edges, 40);
}

}  // namespace
}  // namespace terrain
