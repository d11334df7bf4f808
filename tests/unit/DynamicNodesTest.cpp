// Dynamic nodes end to end (paper 3.4): a map whose leaves carry detail errors (3.4.1), the node source
// that synthesizes below them, the streamer with its velocity limit (3.4.4), queue limit and
// lod_minimum_spacing, and the height query that returns what the viewer draws.
#include "MapTestSupport.h"

#include "lod/HeightQuery.h"
#include "lod/NodeServer.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/DetailSynthesizer.h"
#include "synthesis/LeafErrorEstimator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <random>

namespace terrain {
namespace {

class DynamicNodesTest : public ::testing::Test {
protected:
    static constexpr int kChunk = 17;

    void SetUp() override
    {
        mSynthesizer = test::grassAndRockSynthesizer(kChunk);
        mMap = test::detailErrorMap(test::hillyField(257, 257), 10.0, *mSynthesizer, mDir / "hills.map");
        ASSERT_TRUE(mMap);
        ASSERT_TRUE(mMap->header().hasDetailErrors());
    }

    /// A camera `height` metres above the middle of the map looking north and down.
    Camera lowCamera(double height) const
    {
        Camera camera;
        const double size = mMap->header().nodeSizeAt(0);
        auto ground = staticHeightAt(*mMap, size * 0.5, size * 0.4);
        camera.position = {size * 0.5, size * 0.4, ground->height + height};
        camera.pitch = -0.5;
        camera.farPlane = 100000;
        return camera;
    }

    /// Runs frames until the selection wants nothing more.
    static void settle(TerrainStreamer& streamer, const Camera& camera, double tau, double speed = 0.0)
    {
        streamer.settle(Settle::Complete, camera, tau, speed);
    }

    test::ScratchDir mDir;
    std::unique_ptr<const DetailSynthesizer> mSynthesizer;
    std::unique_ptr<MapFile> mMap;
};

bool sameBits(const std::vector<float>& a, const std::vector<float>& b)
{
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST_F(DynamicNodesTest, LeavesCarryNestedDetailErrors)
{
    int leaves = 0;
    for (const DirectoryEntry& e : mMap->directory()) {
        EXPECT_GE(e.detailDeltaC, e.deltaC) << e.id.toString();
        if (!e.hasChildren) {
            ++leaves;
            EXPECT_GT(e.detailDeltaC, 0.0f) << "a static leaf must refine into dynamic nodes: " << e.id.toString();
        }
    }
    EXPECT_EQ(leaves, 256);
}

TEST_F(DynamicNodesTest, ViewerGoesBelowTheStaticLeavesAndStaysWithinTheCache)
{
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.05});
    StreamerOptions options;
    options.cacheSize = 300;
    options.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok()) << streamer.error().message;
    const int staticLevels = static_cast<int>(mMap->header().levels);
    int deepest = 0;
    for (double height : {400.0, 100.0, 20.0, 5.0, 2.0}) {
        settle(**streamer, lowCamera(height), 1.0);
        for (const auto& selected : (*streamer)->selection().nodes) {
            deepest = std::max(deepest, selected.id.level);
            NodePtr node = (*streamer)->node(selected.id);
            ASSERT_TRUE(node);
            EXPECT_EQ(node->isStatic, selected.id.level < staticLevels) << selected.id.toString();
        }
        EXPECT_LE((*streamer)->cache().size(), options.cacheSize);
    }
    EXPECT_GE(deepest, staticLevels + 3) << "a camera 2 m above the ground sees centimetre detail";
}

TEST_F(DynamicNodesTest, FramesCountTheDynamicGroupsTheyTakeIn)
{
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.05});
    StreamerOptions options;
    options.cacheSize = 4000;  // nothing is evicted
    options.workers = 0;       // loads run in drain(), and drain() says what it took in
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok()) << streamer.error().message;
    std::size_t synthesized = 0, taken = 0;
    for (int round = 0; round < 200; ++round) {
        const FrameStats frame = (*streamer)->update(lowCamera(5.0), 1.0);
        const FrameStats drained = (*streamer)->drain();
        synthesized += frame.synthesized + drained.synthesized;
        taken += frame.inserted + frame.refused + drained.inserted + drained.refused;
        if (frame.requested == 0) {
            break;
        }
    }
    // The reference: walk the resident tree from the root and count the dynamic nodes, four a group.
    std::size_t dynamicNodes = 0, nodes = 0;
    std::vector<NodeId> stack{NodeId{}};
    while (!stack.empty()) {
        const NodeId id = stack.back();
        stack.pop_back();
        const NodePtr node = (*streamer)->node(id);
        if (!node) {
            continue;
        }
        ++nodes;
        dynamicNodes += node->isStatic ? 0 : 1;
        for (int q = 0; q < 4; ++q) {
            stack.push_back(id.child(q));
        }
    }
    EXPECT_GT(synthesized, 10u) << "5 m above the ground the viewer goes below the static leaves";
    EXPECT_EQ(synthesized * 4, dynamicNodes);
    EXPECT_EQ(taken * 4 + 1, nodes) << "every group taken in is resident, with the root";
}

TEST_F(DynamicNodesTest, AdjacentSelectedNodesAgreeBitForBitOnTheirSharedSamples)
{
    // Every pair of selected neighbours, static/static, static/dynamic and dynamic/dynamic at any levels:
    // wherever both have a sample on their common edge, the base heights are the same, and so is the surface
    // (base + displacement) when both take their placement from the same static level (a static node its
    // own, a dynamic node its static leaf's: DetailSynthesizer::displace). Static nodes of different levels
    // place materials by their own slopes, so their displacement may differ there; the skirts, as deep as
    // the larger detail error, cover that step.
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.05});
    StreamerOptions options;
    options.cacheSize = 2000;
    options.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok());
    settle(**streamer, lowCamera(15.0), 1.0);
    const int n = kChunk, w = n + 2 * kBorder;
    // Samples on node edges by global position at the finest level present: key (level-free) = exact
    // position in units of the finest spacing.
    int deepest = 0;
    for (const auto& s : (*streamer)->selection().nodes) {
        deepest = std::max(deepest, s.id.level);
    }
    struct EdgeSample {
        float base;
        float surface;
        int placementLevel;
        std::string node;
    };
    std::map<std::pair<std::int64_t, std::int64_t>, EdgeSample> edgeSamples;
    int compared = 0, comparedSurfaces = 0, mismatches = 0;
    const int staticLevels = static_cast<int>(mMap->header().levels);
    for (const auto& s : (*streamer)->selection().nodes) {
        NodePtr node = (*streamer)->node(s.id);
        const std::int64_t scale = std::int64_t{1} << (deepest - s.id.level);
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                if (i != 0 && i != n - 1 && j != 0 && j != n - 1) {
                    continue;
                }
                const std::int64_t gx = (static_cast<std::int64_t>(s.id.x) * (n - 1) + i) * scale;
                const std::int64_t gy = (static_cast<std::int64_t>(s.id.y) * (n - 1) + j) * scale;
                const std::size_t k = static_cast<std::size_t>(j + kBorder) * w + i + kBorder;
                const EdgeSample here{node->heights.base[k], node->heights.height(k),
                                      std::min(s.id.level, staticLevels - 1), s.id.toString()};
                auto [it, inserted] = edgeSamples.try_emplace({gx, gy}, here);
                if (inserted) {
                    continue;
                }
                ++compared;
                const bool samePlacement = it->second.placementLevel == here.placementLevel;
                comparedSurfaces += samePlacement ? 1 : 0;
                if (std::memcmp(&it->second.base, &here.base, sizeof here.base) != 0 ||
                    (samePlacement && std::memcmp(&it->second.surface, &here.surface, sizeof here.surface) != 0)) {
                    ++mismatches;
                    ADD_FAILURE() << here.node << " and " << it->second.node << " differ at (" << gx << ", " << gy
                                  << "): " << here.surface << " vs " << it->second.surface;
                }
            }
        }
    }
    EXPECT_GT(compared, 500);
    EXPECT_GT(comparedSurfaces, 300);
    EXPECT_EQ(mismatches, 0);
}

TEST_F(DynamicNodesTest, NodeColoursAreTheMapsUnderTheCoverTakenOnce)
{
    // Every resident node's colours are its map colours under its materials' cover; a dynamic node's map colours
    // are its parent's map colours upsampled (not the parent's covered ones: the cover would compound level by
    // level).
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.05});
    StreamerOptions options;
    options.cacheSize = 2000;
    options.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok());
    settle(**streamer, lowCamera(15.0), 1.0);
    const MapHeader& h = mMap->header();
    const MaterialSet& materials = *mSynthesizer->settings().materials;
    int dynamic = 0, changed = 0;
    for (const auto& s : (*streamer)->selection().nodes) {
        for (NodeId id = s.id; id.level > 0; id = id.parent()) {
            NodePtr node = (*streamer)->node(id);
            ASSERT_TRUE(node);
            // Map colours are kept where children are synthesized from them.
            ASSERT_EQ(node->mapTexture.empty(), !node->hasChildren || node->hasStaticChildren) << id.toString();
            if (!node->mapTexture.empty()) {
                EXPECT_EQ(node->texture, coverTexture(materials, node->mapTexture, static_cast<int>(h.textureSize),
                                                      node->materialWeights, static_cast<int>(h.chunkSize)))
                    << id.toString();
                changed += node->texture != node->mapTexture;
            }
            if (!node->isStatic) {
                NodePtr parent = (*streamer)->node(id.parent());
                ASSERT_TRUE(parent);
                const auto upsampled =
                    upsampleTexture(parent->mapTexture, static_cast<int>(h.textureSize), id.quadrant());
                EXPECT_EQ(node->texture, coverTexture(materials, upsampled, static_cast<int>(h.textureSize),
                                                      node->materialWeights, static_cast<int>(h.chunkSize)))
                    << id.toString();
                if (!node->mapTexture.empty()) {
                    EXPECT_EQ(node->mapTexture, upsampled) << id.toString();
                }
                ++dynamic;
            }
        }
    }
    EXPECT_GT(dynamic, 20);
    EXPECT_GT(changed, 20);
}

TEST_F(DynamicNodesTest, SynthesisIsTheSameWithAnyThreadsAndAnyOrder)
{
    // Synthesize the same subtree inline, and with two threads racing over it in shuffled orders.
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.0});
    const int staticLevels = static_cast<int>(mMap->header().levels);
    auto collect = [&](int threads, std::uint32_t seed) {
        std::map<std::uint64_t, NodePtr> nodes;
        std::vector<NodePtr> frontier{source.loadRoot().value()};
        // Descend along one path of static nodes to a leaf, then take all dynamic nodes 2 levels below.
        while (frontier.front()->id.level < staticLevels - 1) {
            frontier = {source.loadChildren(*frontier.front()).value()[1]};
        }
        std::vector<NodePtr> parents{frontier.front()};
        for (int level = 0; level < 2; ++level) {
            std::vector<NodePtr> next;
            std::mt19937 random(seed + static_cast<std::uint32_t>(level));
            std::shuffle(parents.begin(), parents.end(), random);
            std::vector<ChildNodes> results(parents.size());
            std::vector<std::thread> pool;
            for (int t = 0; t < threads; ++t) {
                pool.emplace_back([&, t] {
                    for (std::size_t k = static_cast<std::size_t>(t); k < parents.size();
                         k += static_cast<std::size_t>(threads)) {
                        results[k] = source.loadChildren(*parents[k]).value();
                    }
                });
            }
            for (auto& thread : pool) {
                thread.join();
            }
            for (const auto& group : results) {
                for (const auto& child : group) {
                    nodes[child->id.key()] = child;
                    next.push_back(child);
                }
            }
            parents = std::move(next);
        }
        return nodes;
    };
    auto one = collect(1, 1), two = collect(2, 7);
    ASSERT_EQ(one.size(), 4u + 16u);
    ASSERT_EQ(one.size(), two.size());
    for (const auto& [key, node] : one) {
        const NodePtr& other = two.at(key);
        EXPECT_FALSE(node->isStatic);
        EXPECT_TRUE(sameBits(node->heights.base, other->heights.base)) << node->id.toString();
        EXPECT_TRUE(sameBits(node->heights.displacement, other->heights.displacement)) << node->id.toString();
        EXPECT_EQ(node->texture, other->texture);
        EXPECT_EQ(node->materialWeights, other->materialWeights);
        EXPECT_EQ(node->deltaC, other->deltaC);
    }
}

TEST_F(DynamicNodesTest, DynamicErrorsFollowTheSynthesisModelBoundWhatIsBelowAndBoxesNest)
{
    // Issue 12: a dynamic node's error is DetailErrorModel::boundFromChildren of its heights and children, never above
    // its parent's; and it bounds what synthesis really adds below it: the node's surface against every
    // sample of its 16 grandchildren (made by the same source), along a chain of nodes down from the root.
    // Static leaves carry prep's bound (the same model), checked against the paper's stochastic estimate.
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.0});
    ASSERT_NE(source.errorModel(), nullptr);
    const int n = kChunk, w = n + 2 * kBorder;
    NodePtr node = source.loadRoot().value();
    int dynamicChecked = 0;
    double tightest = 0.0;
    while (node->id.level < static_cast<int>(mMap->header().levels) + 4) {
        ChildNodes children = source.loadChildren(*node).value();
        for (const auto& child : children) {
            EXPECT_LE(child->zMin, child->zMax);
            EXPECT_GE(child->zMin, node->zMin) << child->id.toString();
            EXPECT_LE(child->zMax, node->zMax) << child->id.toString();
            EXPECT_LE(child->deltaC, node->deltaC) << child->id.toString();
            if (child->isStatic) {
                continue;
            }
            const WindowPlacement where = source.placement(child->id);
            EXPECT_EQ(child->deltaC,
                      std::min(node->deltaC / kErrorNesting,
                               source.errorModel()->boundFromChildren(
                                   child->heights, mSynthesizer->synthesizeChildren(child->heights, where), where,
                                   child->id.level)));
            double worst = 0.0;
            const ChildNodes grandchildren = source.loadChildren(*child).value();
            for (const auto& grand : grandchildren) {
                const ChildNodes greats = source.loadChildren(*grand).value();
                for (const auto& great : greats) {
                    const double scale = 0.25;
                    const double x0 = ((great->id.x - (child->id.x << 2)) * (n - 1)) * scale;
                    const double y0 = ((great->id.y - (child->id.y << 2)) * (n - 1)) * scale;
                    for (int j = 0; j < n; ++j) {
                        for (int i = 0; i < n; ++i) {
                            const double z =
                                great->heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
                            worst =
                                std::max(worst, std::abs(z - nodeSurfaceAt(*child, n, x0 + i * scale, y0 + j * scale)));
                        }
                    }
                }
            }
            EXPECT_LE(worst, child->deltaC) << child->id.toString();
            tightest = std::max(tightest, worst / child->deltaC);
            ++dynamicChecked;
        }
        node = children[3];
    }
    EXPECT_GE(dynamicChecked, 16);
    EXPECT_GT(tightest, 0.3) << "the bound should not be far above what is really added";

    const int leafLevel = static_cast<int>(mMap->header().levels) - 1;
    int leaves = 0;
    for (const DirectoryEntry& entry : mMap->directory()) {
        if (entry.hasChildren || (entry.id.x + entry.id.y) % 5 != 0) {
            continue;
        }
        ASSERT_EQ(entry.id.level, leafLevel);
        auto leaf = mMap->loadPath(entry.id);
        ASSERT_TRUE(leaf.ok());
        DualHeightMap heights;
        heights.size = w;
        for (std::uint16_t code : leaf->heights) {
            heights.base.push_back(static_cast<float>(mMap->header().heightStep * code));
        }
        const float estimate = estimateLeafDetailError(std::move(heights), windowPlacement(mMap->header(), entry.id),
                                                       *mSynthesizer, entry.id.key());
        EXPECT_LE(estimate, entry.detailDeltaC) << entry.id.toString();
        ++leaves;
    }
    EXPECT_GT(leaves, 5);
}

TEST_F(DynamicNodesTest, MinimumSpacingStopsSynthesis)
{
    const double minimum = 1.0;  // 10 m leaves: dynamic levels of 5, 2.5 and 1.25 m, not 0.625
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), minimum});
    StreamerOptions options;
    options.cacheSize = 2000;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok());
    settle(**streamer, lowCamera(1.0), 0.5);
    int deepest = 0;
    for (const auto& s : (*streamer)->selection().nodes) {
        deepest = std::max(deepest, s.id.level);
        EXPECT_GE(mMap->header().spacingAt(s.id.level), minimum) << s.id.toString();
    }
    EXPECT_EQ(deepest, static_cast<int>(mMap->header().levels) - 1 + 3);
}

TEST_F(DynamicNodesTest, VelocityLimitRefusesFineDynamicNodesWhileFastButNotStaticOnes)
{
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.05});
    StreamerOptions options;
    options.cacheSize = 2000;
    options.velocityLimit = 10.0;  // new nodes' samples per second
    const int leafLevel = static_cast<int>(mMap->header().levels) - 1;
    auto deepestAt = [&](double speed, std::size_t& tooFast) {
        auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options).value();
        settle(*streamer, lowCamera(3.0), 1.0, speed);
        tooFast = streamer->update(lowCamera(3.0), 1.0, speed).tooFast;
        int deepest = 0;
        for (const auto& s : streamer->selection().nodes) {
            deepest = std::max(deepest, s.id.level);
        }
        return deepest;
    };
    std::size_t tooFastStill = 0, tooFastMoving = 0, tooFastFlying = 0;
    const int still = deepestAt(0.0, tooFastStill);
    // 30 m/s: new nodes need a spacing of at least 3 m: the 5 m level is made, the 2.5 m one is not.
    const int moving = deepestAt(30.0, tooFastMoving);
    // 1000 m/s: no dynamic node at all; static nodes still load to the leaves.
    const int flying = deepestAt(1000.0, tooFastFlying);
    EXPECT_GT(still, leafLevel + 2);
    EXPECT_EQ(tooFastStill, 0u);
    EXPECT_EQ(moving, leafLevel + 1);
    EXPECT_GT(tooFastMoving, 0u);
    EXPECT_EQ(flying, leafLevel);
    EXPECT_GT(tooFastFlying, 0u);
}

TEST_F(DynamicNodesTest, RequestQueueStaysWithinItsLimitWhileDiving)
{
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.05});
    StreamerOptions options;
    options.cacheSize = 500;
    options.queueLimit = 4;
    options.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok());
    std::size_t dynamicSeen = 0;
    for (int frame = 0; frame < 300; ++frame) {
        const double height = 800.0 * std::exp(-frame / 40.0) + 1.0;
        (*streamer)->update(lowCamera(height), 1.0);
        const NodeServerStats stats = (*streamer)->serverStats();
        EXPECT_LE(stats.queued, options.queueLimit);
        for (const auto& s : (*streamer)->selection().nodes) {
            dynamicSeen += (*streamer)->node(s.id)->isStatic ? 0 : 1;
        }
        std::this_thread::yield();
    }
    // However slow the workers (a sanitizer build), the dive ends with detail drawn once the loads arrive.
    settle(**streamer, lowCamera(1.0), 1.0);
    EXPECT_LE((*streamer)->serverStats().queued, options.queueLimit);
    for (const auto& s : (*streamer)->selection().nodes) {
        dynamicSeen += (*streamer)->node(s.id)->isStatic ? 0 : 1;
    }
    EXPECT_GT(dynamicSeen, 0u);
}

TEST_F(DynamicNodesTest, HeightQueryReturnsTheSurfaceTheViewerDraws)
{
    TerrainNodeSource source(*mMap, {mSynthesizer.get(), 0.0});
    const MapHeader& h = mMap->header();
    const int depth = static_cast<int>(h.levels) + 2;
    // Walk to one dynamic node and compare the query at its samples and between them with its surface.
    NodePtr node = source.loadRoot().value();
    while (node->id.level < depth) {
        node = source.loadChildren(*node).value()[2];
    }
    const double spacing = h.spacingAt(depth);
    const double x0 = h.originX + node->id.x * h.nodeSizeAt(depth);
    const double y0 = h.originY + node->id.y * h.nodeSizeAt(depth);
    const int w = node->heights.size;
    for (int j = 1; j < kChunk - 1; j += 5) {
        for (int i = 1; i < kChunk - 1; i += 3) {
            auto sample = surfaceHeightAt(*mMap, source, x0 + i * spacing, y0 + j * spacing, depth);
            ASSERT_TRUE(sample.ok()) << sample.error().message;
            EXPECT_EQ(sample->node, node->id);
            const double expected =
                h.heightOffset + node->heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder);
            EXPECT_NEAR(sample->height, expected, 1e-6);
            // Half-way along the SW-NE diagonal of a cell: the mean of its two ends (the drawn triangle edge).
            auto between = surfaceHeightAt(*mMap, source, x0 + (i + 0.5) * spacing, y0 + (j + 0.5) * spacing, depth);
            ASSERT_TRUE(between.ok());
            const double ne =
                h.heightOffset + node->heights.height(static_cast<std::size_t>(j + 1 + kBorder) * w + i + 1 + kBorder);
            EXPECT_NEAR(between->height, 0.5 * (expected + ne), 1e-6);
        }
    }
    // Without detail at the finest static level the query is the static height query.
    TerrainNodeSource plain(*mMap, {});
    for (double x : {123.4, 1000.0, 2222.2}) {
        auto a = surfaceHeightAt(*mMap, plain, x, 1500.5, static_cast<int>(h.levels) - 1);
        auto b = staticHeightAt(*mMap, x, 1500.5);
        ASSERT_TRUE(a.ok() && b.ok());
        EXPECT_NEAR(a->height, b->height, 1e-6) << x;
    }
}

}  // namespace
}  // namespace terrain
