// What a resident node costs (lod/NodeMemory.h): the cache is sized by memory_budget over the root's CPU bytes
// plus a GPU slot, which holds only if no node the source makes costs more than the root; the slot's bytes
// against the formats' sizes; the budget's arithmetic at its extremes.
#include "MapTestSupport.h"

#include "lod/NodeMemory.h"
#include "lod/TerrainNodeSource.h"
#include "synthesis/LeafErrorEstimator.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <utility>

namespace terrain {
namespace {

constexpr int kChunk = 17;

TEST(NodeMemoryTest, NoNodeCostsMoreThanTheRootWithEveryKindOfNodeData)
{
    // Static and dynamic nodes over a map with detail: materials, slopes, normal maps two levels below and
    // tessellation errors, as the viewer's source makes them.
    test::ScratchDir dir;
    auto plain = test::grassAndRockSynthesizer(kChunk);
    BuildOptions options;
    options.chunkSize = kChunk;
    options.spacing = 10.0;
    options.threads = 2;
    options.leafDetailError = leafDetailErrorFunction(*plain);
    auto report = buildMap(test::hillyField(129, 129), options, dir / "hills.map");
    ASSERT_TRUE(report.ok()) << report.error().message;
    auto map = test::openMap(dir / "hills.map", ReaderKind::MemoryMapped);
    ASSERT_TRUE(map);
    for (const auto& [normalMapSize, compressed] :
         {std::pair{0, false}, {4 * (kChunk - 1), false}, {4 * (kChunk - 1), true}}) {
        TerrainNodeSource source(*map, {plain.get(), 0.0, 8, normalMapSize, true, compressed});
        EXPECT_EQ(source.loadRoot().value()->normalMapBlocks.size(), compressed ? std::size_t{68} * 68 : 0u);
        const NodePtr root = source.loadRoot().value();
        const std::size_t rootBytes = residentBytes(*root);
        // The arrays' own sizes are a floor of what the root holds.
        std::size_t arrays = root->codes.size() * 2 + root->heights.base.size() * 4 +
                             root->heights.displacement.size() * 4 + root->heights.slope.size() * 4 +
                             root->materialWeights.size() + root->texture.size() + root->normalMap.size() +
                             root->normalMapBlocks.size();
        EXPECT_GE(rootBytes, arrays + sizeof(NodeData));
        EXPECT_LE(rootBytes, 2 * arrays + sizeof(NodeData) + 64 * 1024) << "a node's tessellation errors are small";
        std::mt19937 random(7);
        int dynamicNodes = 0;
        for (int walk = 0; walk < 6; ++walk) {
            NodePtr node = root;
            for (int depth = 0; depth < 7 && node->hasChildren; ++depth) {
                auto children = source.loadChildren(*node);
                ASSERT_TRUE(children.ok()) << children.error().message;
                for (const NodePtr& child : *children) {
                    EXPECT_LE(residentBytes(*child), rootBytes)
                        << "node " << child->id.toString() << (child->isStatic ? " (static)" : " (dynamic)");
                    dynamicNodes += child->isStatic ? 0 : 1;
                }
                node = (*children)[random() % 4];
            }
        }
        EXPECT_GT(dynamicNodes, 20) << "the walks must reach the synthesized levels";
    }
}

TEST(NodeMemoryTest, SlotBytesAreTheFormatsSizes)
{
    MapHeader header;
    header.chunkSize = 65;
    header.textureSize = 65;
    // RGTC2 normal maps of 129 texels pad to 132, DXT1 colour of 65 to 68; RG8 and RGB8 do not pad.
    const SlotBytes compact = poolSlotBytes(header, {129, true, true, 2});
    EXPECT_EQ(compact.heights, 67u * 67 * 2);
    EXPECT_EQ(compact.normals, 0u);
    EXPECT_EQ(compact.colour, 68u * 68 / 2);
    EXPECT_EQ(compact.weights, 65u * 65 * 2);
    EXPECT_EQ(compact.normalMap, 132u * 132);
    EXPECT_EQ(compact.constants, 5u * 16);
    const SlotBytes plainSlot = poolSlotBytes(header, {0, false, false, 0});
    EXPECT_EQ(plainSlot.normals, 33u * 33 * 2);
    EXPECT_EQ(plainSlot.colour, 65u * 65 * 3);
    EXPECT_EQ(plainSlot.weights, 0u);
    EXPECT_EQ(plainSlot.normalMap, 0u);
    EXPECT_EQ(plainSlot.total(), 67u * 67 * 2 + 33u * 33 * 2 + 65u * 65 * 3 + 3u * 16);
    EXPECT_EQ(poolSlotBytes(header, {129, false, false, 0}).normalMap, 129u * 129 * 2);
    // With shadows the colour is RGBA8 (the sun's visibility in alpha), DXT1 or not, and the sky's visibility RG8.
    const SlotBytes shadowed = poolSlotBytes(header, {129, true, true, 2, true});
    EXPECT_EQ(shadowed.colour, 65u * 65 * 4);
    EXPECT_EQ(shadowed.light, 65u * 65 * 2);
}

TEST(NodeMemoryTest, TheBudgetHoldsWhatItPaysForWithinTheCachesLimits)
{
    constexpr std::uint64_t kMiB = 1024 * 1024;
    const CacheSizing s = sizeCache(180 * kMiB, 184934, 2048);
    EXPECT_EQ(s.nodes, 180 * kMiB / 184934);
    EXPECT_FALSE(s.limitedByMaxNodes);
    EXPECT_FALSE(s.belowMinimum);
    EXPECT_LE(s.nodes * s.bytesPerNode, 180 * kMiB);
    const CacheSizing big = sizeCache(UINT64_MAX, 1, 2048);
    EXPECT_EQ(big.nodes, 2048u);
    EXPECT_TRUE(big.limitedByMaxNodes);
    const CacheSizing tiny = sizeCache(0, SIZE_MAX, 2048);
    EXPECT_EQ(tiny.nodes, 5u);
    EXPECT_TRUE(tiny.belowMinimum);
    EXPECT_EQ(defaultMemoryBudget(0), 128 * kMiB);
    EXPECT_EQ(defaultMemoryBudget(24ull << 30), 1536 * kMiB);
    EXPECT_EQ(defaultMemoryBudget(UINT64_MAX), 4096 * kMiB);
    EXPECT_GT(physicalMemoryBytes(), 64 * kMiB) << "sysconf says how much memory this machine has";
}

}  // namespace
}  // namespace terrain
