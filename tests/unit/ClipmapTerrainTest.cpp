// Clipmap ring data from the quadtree (lod/ClipmapTerrain.h): once the nodes the windows want are resident,
// every window sample holds its node's height (against the decoded map, independently of the node server)
// and texel; toroidal updates over a flight end where a fresh fill at the last position does; rings below the
// static levels hold the synthesized dynamic nodes; missing nodes are upsampled from the coarser ring.
#include "lod/ClipmapTerrain.h"

#include "MapTestSupport.h"
#include "lod/NodeHorizons.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "synthesis/NormalMap.h"

#include <gtest/gtest.h>

#include <array>
#include <numbers>

namespace terrain {
namespace {

class ClipmapTerrainTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        // 257 x 257 at 2 m, chunks of 17: 5 static levels, root 512 m.
        BuildOptions options = test::testOptions(17);
        options.leafDetailError = test::fakeLeafDetailError;
        auto built = buildMap(test::hillyField(257, 257, 3), options, mDir / "c.map");
        ASSERT_TRUE(built.ok()) << built.error().message;
        mMap = test::openMap(mDir / "c.map");
        ASSERT_TRUE(mMap);
        auto tree = test::decodeTree(*mMap);
        ASSERT_TRUE(tree.ok()) << tree.error().message;
        mTree = std::move(tree.value());
    }

    /// A streamer over `source` loading inline (in drain()), with a cache of `cacheSize` nodes; null on failure.
    std::unique_ptr<TerrainStreamer> inlineStreamer(TerrainNodeSource& source, std::size_t cacheSize) const
    {
        StreamerOptions options;
        options.cacheSize = cacheSize;
        options.workers = 0;
        auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
        EXPECT_TRUE(streamer.ok()) << streamer.error().message;
        return streamer.ok() ? std::move(streamer).value() : nullptr;
    }

    /// Moves to (x, y) and loads until the windows want nothing more; returns the rounds it took.
    static int settle(ClipmapLayout& layout, ClipmapTerrain& terrain, TerrainStreamer& streamer, double x, double y)
    {
        const ResidentNodeLookup lookup = [&streamer](const NodeId& id) { return streamer.node(id); };
        terrain.update(layout, layout.moveTo(x, y), lookup);
        const std::vector<std::vector<LatticeRect>> none(static_cast<std::size_t>(layout.ringCount()));
        for (int round = 0; round < 100; ++round) {
            const FrameStats stats = streamer.updateFor(terrain.wanted(layout));
            streamer.drain();
            terrain.update(layout, none, lookup);
            if (stats.requested == 0) {
                return round;
            }
        }
        return 100;
    }

    /// Loads, in rounds all at time `now` (as video mode's rounds of one frame), until no node of the rings is
    /// upsampled any more; returns how many still are after 20 rounds (0 when all arrived).
    static std::size_t loadAt(const ClipmapLayout& layout, ClipmapTerrain& terrain, TerrainStreamer& streamer,
                              double now)
    {
        const ResidentNodeLookup lookup = [&streamer](const NodeId& id) { return streamer.node(id); };
        const std::vector<std::vector<LatticeRect>> none(static_cast<std::size_t>(layout.ringCount()));
        for (int round = 0; round < 20 && terrain.upsampledNodes() > 0; ++round) {
            streamer.updateFor(terrain.wanted(layout));
            streamer.drain();
            terrain.update(layout, none, lookup, now);
        }
        return terrain.upsampledNodes();
    }

    /// Ring `r`'s samples against the decoded static map: height and colour at every window sample (clamped to
    /// the terrain, as the clipmap reads it).
    void expectStaticRing(const ClipmapLayout& layout, const ClipmapTerrain& terrain, int r) const
    {
        const MapHeader& h = mMap->header();
        const int n = layout.samples(), cells = static_cast<int>(h.chunkSize) - 1;
        const ClipmapWindow& w = layout.window(r);
        const std::int64_t last = std::int64_t{cells} << w.level;
        int mismatches = 0;
        for (std::int64_t gy = w.y0; gy < w.y0 + n; ++gy) {
            for (std::int64_t gx = w.x0; gx < w.x0 + n; ++gx) {
                const std::int64_t cx = std::clamp<std::int64_t>(gx, 0, last),
                                   cy = std::clamp<std::int64_t>(gy, 0, last);
                const auto nx = static_cast<std::uint32_t>(std::min<std::int64_t>(cx / cells, (1 << w.level) - 1));
                const auto ny = static_cast<std::uint32_t>(std::min<std::int64_t>(cy / cells, (1 << w.level) - 1));
                const StaticNode* node = mTree.find({w.level, nx, ny});
                ASSERT_NE(node, nullptr);
                const int u = static_cast<int>(cx - std::int64_t{nx} * cells);
                const int v = static_cast<int>(cy - std::int64_t{ny} * cells);
                const double expected = h.heightOf(test::windowCode(h, *node, u, v)) - h.heightOffset;
                const std::size_t t = static_cast<std::size_t>(toroidalTexel(gy, n)) * n + toroidalTexel(gx, n);
                const ClipmapRing& ring = terrain.ring(r);
                if (std::abs(ring.heights[t] - expected) > 1e-3 && ++mismatches <= 3) {
                    ADD_FAILURE() << "ring " << r << " sample (" << gx << ", " << gy << "): " << ring.heights[t]
                                  << " m, node " << node->id.toString() << " has " << expected << " m";
                }
                const std::size_t k = (static_cast<std::size_t>(v) * h.textureSize + u) * 3;  // T = N here
                for (int c = 0; c < 3; ++c) {
                    if (ring.colour[t * 4 + c] != node->texture[k + c] && ++mismatches <= 3) {
                        ADD_FAILURE() << "ring " << r << " sample (" << gx << ", " << gy << ") colour " << c;
                    }
                }
            }
        }
        EXPECT_EQ(mismatches, 0) << "ring " << r;
    }

    test::ScratchDir mDir;
    std::unique_ptr<MapFile> mMap;
    test::DecodedTree mTree;
};

TEST_F(ClipmapTerrainTest, SettledRingsHoldTheirNodesSamplesAlongAFlight)
{
    TerrainNodeSource source(*mMap, {});
    auto streamer = inlineStreamer(source, 400);
    ASSERT_TRUE(streamer);
    ClipmapLayout layout(extentOf(mMap->header()), 17, 31, 4, 0);
    ClipmapTerrain terrain(layout, 17, 17);
    EXPECT_EQ(terrain.bytes(), std::size_t{5} * 31 * 31 * 22);
    // Small steps, a jump, the edge of the terrain and beyond.
    const std::pair<double, double> flight[] = {{200, 300}, {203, 301}, {211, 290}, {260, 250},
                                                {20, 500},  {-30, 530}, {400, 100}, {401.5, 99}};
    for (auto [x, y] : flight) {
        const int rounds = settle(layout, terrain, *streamer, x, y);
        EXPECT_LT(rounds, 100) << "at " << x << ", " << y;
        EXPECT_EQ(terrain.upsampledNodes(), 0u) << "every static node the windows want exists";
        for (int r = 0; r < layout.ringCount(); ++r) {
            expectStaticRing(layout, terrain, r);
        }
    }
    // A fresh clipmap at the last position holds the same bits: the toroidal updates lose nothing.
    ClipmapLayout freshLayout(extentOf(mMap->header()), 17, 31, 4, 0);
    ClipmapTerrain fresh(freshLayout, 17, 17);
    settle(freshLayout, fresh, *streamer, flight[std::size(flight) - 1].first, flight[std::size(flight) - 1].second);
    for (int r = 0; r < layout.ringCount(); ++r) {
        EXPECT_EQ(fresh.ring(r).heights, terrain.ring(r).heights) << "ring " << r;
        EXPECT_EQ(fresh.ring(r).colour, terrain.ring(r).colour) << "ring " << r;
    }
}

TEST_F(ClipmapTerrainTest, DrawnSurfaceIsContinuousWhereRingsMeet)
{
    // On each ring's perimeter its surface (blended all the way to the coarser ring) is the coarser ring's own
    // surface there: the shader's geometry (ClipmapTerrain::ringSurface) meets without a step.
    TerrainNodeSource source(*mMap, {});
    auto streamer = inlineStreamer(source, 400);
    ASSERT_TRUE(streamer);
    ClipmapLayout layout(extentOf(mMap->header()), 17, 31, 4, 0);
    ClipmapTerrain terrain(layout, 17, 17);
    settle(layout, terrain, *streamer, 261.3, 247.9);
    int checked = 0;
    double largestStep = 0.0;
    for (int r = 0; r + 1 < layout.ringCount(); ++r) {
        const ClipmapWindow& w = layout.window(r);
        for (int k = 0; k < 400; ++k) {
            // A point on the perimeter, anywhere along it (between vertices too).
            const double t = (31 - 1) * test::unitNoise(21, k, r);
            const int side = k % 4;
            const double gx = static_cast<double>(w.x0) + (side == 0 ? t : side == 1 ? 30.0 : side == 2 ? t : 0.0);
            const double gy = static_cast<double>(w.y0) + (side == 0 ? 0.0 : side == 1 ? t : side == 2 ? 30.0 : t);
            const double x = layout.worldX(r, gx), y = layout.worldY(r, gy);
            const auto fine = terrain.ringSurface(layout, r, x, y);
            const auto coarse = terrain.ringSurface(layout, r + 1, x, y);
            ASSERT_TRUE(fine && coarse) << r;
            largestStep = std::max(largestStep, std::abs(*fine - *coarse));
            ++checked;
            // Just inside, the drawn surface is this ring's.
            const double ix = layout.worldX(r, static_cast<double>(w.x0) + 15.0),
                         iy = layout.worldY(r, static_cast<double>(w.y0) + 15.0);
            EXPECT_EQ(terrain.drawnHeight(layout, r, ix, iy), terrain.ringSurface(layout, r, ix, iy));
        }
    }
    EXPECT_EQ(checked, 4 * 400);
    EXPECT_LT(largestStep, 1e-3) << "metres between rings on a perimeter";
    // And the blend is not idle: inside the transition region a ring differs from its own samples somewhere.
    const ClipmapWindow& w0 = layout.window(0);
    double blended = 0.0;
    for (int k = 0; k < 30; ++k) {
        const double x = layout.worldX(0, static_cast<double>(w0.x0) + k),
                     y = layout.worldY(0, static_cast<double>(w0.y0) + 1.0);
        const std::size_t t =
            static_cast<std::size_t>(toroidalTexel(w0.y0 + 1, 31)) * 31 + toroidalTexel(w0.x0 + k, 31);
        blended = std::max(blended, std::abs(*terrain.ringSurface(layout, 0, x, y) - terrain.ring(0).heights[t]));
    }
    EXPECT_GT(blended, 0.01);
}

TEST_F(ClipmapTerrainTest, MissingNodesAreUpsampledFromTheCoarserRingUntilTheyArrive)
{
    TerrainNodeSource source(*mMap, {});
    auto streamer = inlineStreamer(source, StreamerOptions{}.cacheSize);
    ASSERT_TRUE(streamer);
    ClipmapLayout layout(extentOf(mMap->header()), 17, 31, 2, 0);
    ClipmapTerrain terrain(layout, 17, 17);
    const ResidentNodeLookup lookup = [&](const NodeId& id) { return streamer->node(id); };
    terrain.update(layout, layout.moveTo(250.0, 260.0), lookup);
    // Only the root is resident: rings 1 and 0 are the root's surface, bilinearly upsampled.
    EXPECT_GT(terrain.upsampledNodes(), 0u);
    const int n = 31;
    const ClipmapRing& coarse = terrain.ring(2);
    const ClipmapRing& fine = terrain.ring(1);
    const ClipmapWindow& w = layout.window(1);
    for (std::int64_t gy = w.y0; gy < w.y0 + n; ++gy) {
        for (std::int64_t gx = w.x0; gx < w.x0 + n; ++gx) {
            auto at = [&](std::int64_t x, std::int64_t y) {
                return coarse.heights[static_cast<std::size_t>(toroidalTexel(y, n)) * n + toroidalTexel(x, n)];
            };
            const double expected = 0.25 * (at(gx >> 1, gy >> 1) + at((gx + 1) >> 1, gy >> 1) +
                                            at(gx >> 1, (gy + 1) >> 1) + at((gx + 1) >> 1, (gy + 1) >> 1));
            EXPECT_NEAR(fine.heights[static_cast<std::size_t>(toroidalTexel(gy, n)) * n + toroidalTexel(gx, n)],
                        expected, 1e-3)
                << gx << ", " << gy;
        }
    }
    settle(layout, terrain, *streamer, 250.0, 260.0);
    EXPECT_EQ(terrain.upsampledNodes(), 0u);
    for (int r = 0; r < layout.ringCount(); ++r) {
        expectStaticRing(layout, terrain, r);
    }
}

TEST_F(ClipmapTerrainTest, ArrivingNodesMorphFromTheUpsampledSurfaceTheViewerSaw)
{
    TerrainNodeSource source(*mMap, {});
    auto streamer = inlineStreamer(source, StreamerOptions{}.cacheSize);
    ASSERT_TRUE(streamer);
    ClipmapLayout layout(extentOf(mMap->header()), 17, 31, 2, 0);
    constexpr double kMorph = 0.5;
    ClipmapTerrain terrain(layout, 17, 17, false, 0, kMorph);
    const ResidentNodeLookup lookup = [&](const NodeId& id) { return streamer->node(id); };
    const std::vector<std::vector<LatticeRect>> none(static_cast<std::size_t>(layout.ringCount()));
    // The drawn surface of every ring on a grid of points (as ErrorMeter and the shader see it).
    auto surface = [&] {
        std::vector<double> z;
        for (int r = 0; r < layout.ringCount(); ++r) {
            for (double y = 100.0; y <= 420.0; y += 7.3) {
                for (double x = 90.0; x <= 410.0; x += 6.9) {
                    z.push_back(terrain.ringSurface(layout, r, x, y).value_or(-1.0));
                }
            }
        }
        return z;
    };
    // Time 0: only the root is resident; the finer rings are drawn upsampled.
    terrain.update(layout, layout.moveTo(250.0, 260.0), lookup, 0.0);
    ASSERT_GT(terrain.upsampledNodes(), 0u);
    const std::vector<double> seen = surface();
    // The nodes arrive at time 1 (all loading rounds at that time).
    ASSERT_EQ(loadAt(layout, terrain, *streamer, 1.0), 0u);
    // No pop: at the moment they arrive, the surface is the one drawn before.
    const std::vector<double> arrived = surface();
    double largest = 0.0, changing = 0.0;
    for (std::size_t i = 0; i < seen.size(); ++i) {
        largest = std::max(largest, std::abs(arrived[i] - seen[i]));
    }
    EXPECT_LT(largest, 1e-3) << "metres the surface jumped when the nodes arrived";
    // Once the morph is over, every sample is its node's; halfway, the surface is halfway (the morph and the
    // transition blend are both linear in the heights).
    terrain.update(layout, none, lookup, 1.0 + 0.5 * kMorph);
    const std::vector<double> halfway = surface();
    terrain.update(layout, none, lookup, 1.0 + 1.5 * kMorph);
    const std::vector<double> settled = surface();
    for (std::size_t i = 0; i < seen.size(); ++i) {
        changing = std::max(changing, std::abs(settled[i] - seen[i]));
        EXPECT_NEAR(halfway[i], 0.5 * (arrived[i] + settled[i]), 1e-3) << "point " << i;
    }
    EXPECT_GT(changing, 1.0) << "the nodes change the surface by metres: the test would see a pop";
    for (int r = 0; r < layout.ringCount(); ++r) {
        expectStaticRing(layout, terrain, r);
        for (std::size_t t = 0; t < terrain.ring(r).heights.size(); ++t) {
            ASSERT_EQ(terrain.drawnSample(r, t), terrain.ring(r).heights[t]) << "ring " << r << " texel " << t;
        }
    }

    // Nodes that arrive while the frame that first wants them still loads (video mode's rounds, one time) were
    // never drawn upsampled: no morph.
    auto second = inlineStreamer(source, StreamerOptions{}.cacheSize);
    ASSERT_TRUE(second);
    const ResidentNodeLookup secondLookup = [&](const NodeId& id) { return second->node(id); };
    ClipmapLayout secondLayout(extentOf(mMap->header()), 17, 31, 2, 0);
    ClipmapTerrain fresh(secondLayout, 17, 17, false, 0, kMorph);
    fresh.update(secondLayout, secondLayout.moveTo(250.0, 260.0), secondLookup, 2.0);
    ASSERT_GT(fresh.upsampledNodes(), 0u);
    ASSERT_EQ(loadAt(secondLayout, fresh, *second, 2.0), 0u);
    for (int r = 0; r < layout.ringCount(); ++r) {
        for (std::size_t t = 0; t < fresh.ring(r).heights.size(); ++t) {
            ASSERT_EQ(fresh.drawnSample(r, t), fresh.ring(r).heights[t]) << "ring " << r << " texel " << t;
        }
    }
}

TEST_F(ClipmapTerrainTest, ArrivingNodesColoursWeightsAndNormalsStartFromWhatWasDrawn)
{
    // Synthesized levels below the map (material weights) and normal maps of 2 texels a cell.
    const auto synthesizer = test::grassAndRockSynthesizer(17);
    DetailPolicy policy{synthesizer.get(), 0.05};
    policy.normalMapSize = 32;
    TerrainNodeSource source(*mMap, policy);
    auto streamer = inlineStreamer(source, 600);
    ASSERT_TRUE(streamer);
    const int n = 31;
    ClipmapLayout layout(extentOf(mMap->header()), 17, n, 6, 0);
    constexpr double kMorph = 0.5;
    ClipmapTerrain terrain(layout, 17, 17, /*materials=*/true, normalMapTexels(32), kMorph);
    const ResidentNodeLookup lookup = [&](const NodeId& id) { return streamer->node(id); };
    const std::vector<std::vector<LatticeRect>> none(static_cast<std::size_t>(layout.ringCount()));
    // Time 0: the root alone; what every ring shows (no morph under way: the current layers).
    terrain.update(layout, layout.moveTo(130.0, 170.0), lookup, 0.0);
    ASSERT_GT(terrain.upsampledNodes(), 0u);
    std::vector<ClipmapRing> seen;
    for (int r = 0; r < layout.ringCount(); ++r) {
        seen.push_back(terrain.ring(r));
    }
    ASSERT_EQ(loadAt(layout, terrain, *streamer, 1.0), 0u);
    // At their arrival every sample's morph starts from what was drawn: the previous layers are the layers seen.
    std::size_t changedColours = 0, changedWeights = 0, changedNormals = 0;
    for (int r = 0; r < layout.ringCount(); ++r) {
        const ClipmapRing& ring = terrain.ring(r);
        const ClipmapRing& before = seen[static_cast<std::size_t>(r)];
        EXPECT_EQ(ring.previousColour, before.colour) << "ring " << r;
        EXPECT_EQ(ring.previousMaterials, before.materials) << "ring " << r;
        EXPECT_EQ(ring.previousNormals, before.normals) << "ring " << r;
        changedColours += ring.colour != before.colour ? 1 : 0;
        changedWeights += ring.materials != before.materials ? 1 : 0;
        changedNormals += ring.normals != before.normals ? 1 : 0;
    }
    EXPECT_GT(changedColours, 0u) << "the nodes change colours: the test would see them pop";
    EXPECT_GT(changedWeights, 0u);
    EXPECT_GT(changedNormals, 0u);
    // Once over, nothing is morphing and the current layers are drawn.
    terrain.update(layout, none, lookup, 1.0 + 1.5 * kMorph);
    for (int r = 0; r < layout.ringCount(); ++r) {
        for (std::size_t t = 0; t < terrain.ring(r).heights.size(); ++t) {
            ASSERT_EQ(terrain.morphDone(r, t), 1.0f);
            ASSERT_EQ(terrain.drawnSample(r, t), terrain.ring(r).heights[t]);
        }
    }
}

TEST_F(ClipmapTerrainTest, RingsBelowTheStaticLevelsHoldTheSynthesizedNodes)
{
    const auto synthesizer = test::grassAndRockSynthesizer(17);
    TerrainNodeSource source(*mMap, {synthesizer.get(), 0.05});
    auto streamer = inlineStreamer(source, 600);
    ASSERT_TRUE(streamer);
    ClipmapLayout layout(extentOf(mMap->header()), 17, 31, 6, 0);  // two levels of dynamic nodes
    ClipmapTerrain terrain(layout, 17, 17, /*materials=*/true);
    EXPECT_EQ(terrain.bytes(), std::size_t{7} * 31 * 31 * 30);
    settle(layout, terrain, *streamer, 130.0, 170.0);
    EXPECT_EQ(terrain.upsampledNodes(), 0u);
    int materialMismatches = 0;
    const int n = 31, w = windowSize(17);
    for (int r = 0; r < 2; ++r) {
        const ClipmapWindow& win = layout.window(r);
        for (std::int64_t gy = win.y0; gy < win.y0 + n; ++gy) {
            for (std::int64_t gx = win.x0; gx < win.x0 + n; ++gx) {
                const NodeId id{win.level, static_cast<std::uint32_t>(gx / 16), static_cast<std::uint32_t>(gy / 16)};
                NodePtr node = streamer->node(id);
                ASSERT_TRUE(node) << id.toString();
                ASSERT_FALSE(node->isStatic);
                const auto k = static_cast<std::size_t>(gy - std::int64_t{id.y} * 16 + kBorder) * w +
                               static_cast<std::size_t>(gx - std::int64_t{id.x} * 16 + kBorder);
                EXPECT_EQ(
                    terrain.ring(r).heights[static_cast<std::size_t>(toroidalTexel(gy, n)) * n + toroidalTexel(gx, n)],
                    node->heights.height(k))
                    << "ring " << r << " (" << gx << ", " << gy << ")";
                // The node's material weights at the sample (what the detail textures are weighted by).
                ASSERT_EQ(node->materialWeights.size(), std::size_t{17} * 17 * 4);
                const std::size_t t = static_cast<std::size_t>(toroidalTexel(gy, n)) * n + toroidalTexel(gx, n);
                const std::size_t m = (static_cast<std::size_t>(gy - std::int64_t{id.y} * 16) * 17 +
                                       static_cast<std::size_t>(gx - std::int64_t{id.x} * 16)) *
                                      4;
                for (int c = 0; c < 4; ++c) {
                    materialMismatches += terrain.ring(r).materials[t * 4 + c] != node->materialWeights[m + c];
                }
            }
        }
    }
    EXPECT_EQ(materialMismatches, 0);
    // Both materials show somewhere (the weights are not all one material, nor all zero).
    std::array<int, 2> seen = {0, 0};
    for (int r = 0; r < layout.ringCount(); ++r) {
        for (std::size_t t = 0; t < terrain.ring(r).materials.size(); t += 4) {
            seen[0] += terrain.ring(r).materials[t] > 0;
            seen[1] += terrain.ring(r).materials[t + 1] > 0;
        }
    }
    std::printf("samples with grass %d, with rock %d\n", seen[0], seen[1]);
    EXPECT_GT(seen[0], 0);
    EXPECT_GT(seen[1], 0);
}

TEST_F(ClipmapTerrainTest, RingsHoldTheNodesNormalMapsAtTheirTexels)
{
    // dynamic_texture_size 32 on nodes of 16 cells: maps of 33 texels, 2 a cell. Every texel of every ring's
    // window is its node's normal map texel at the same point (static rings too: their nodes get maps).
    const auto synthesizer = test::grassAndRockSynthesizer(17);
    DetailPolicy policy{synthesizer.get(), 0.05};
    policy.normalMapSize = 32;
    TerrainNodeSource source(*mMap, policy);
    auto streamer = inlineStreamer(source, 600);
    ASSERT_TRUE(streamer);
    const int n = 31;
    ClipmapLayout layout(extentOf(mMap->header()), 17, n, 5, 0);
    ClipmapTerrain terrain(layout, 17, 17, false, normalMapTexels(32));
    ASSERT_EQ(terrain.normalTexelsPerCell(), 2);
    EXPECT_EQ(terrain.bytes(), std::size_t{6} * n * n * (22 + 4 * 4));
    settle(layout, terrain, *streamer, 140.0, 90.0);
    ASSERT_EQ(terrain.upsampledNodes(), 0u);
    const int side = 2 * n;
    int checked = 0, mismatches = 0, tilted = 0;
    for (int r = 0; r < layout.ringCount(); ++r) {
        const ClipmapWindow& win = layout.window(r);
        const std::int64_t last = std::int64_t{16} << win.level;
        for (std::int64_t ty = 2 * win.y0; ty <= 2 * (win.y0 + n - 1); ++ty) {
            for (std::int64_t tx = 2 * win.x0; tx <= 2 * (win.x0 + n - 1); ++tx) {
                if (tx < 0 || ty < 0 || tx > 2 * last || ty > 2 * last) {
                    continue;  // outside the terrain: clamped
                }
                // The node holding texel (tx, ty): east / north one on shared edges but the last.
                const auto nx = static_cast<std::uint32_t>(std::min<std::int64_t>(tx / 32, (1 << win.level) - 1));
                const auto ny = static_cast<std::uint32_t>(std::min<std::int64_t>(ty / 32, (1 << win.level) - 1));
                NodePtr node = streamer->node({win.level, nx, ny});
                ASSERT_TRUE(node && node->normalMap.size() == std::size_t{33} * 33 * 2);
                const std::size_t k = (static_cast<std::size_t>(ty - std::int64_t{ny} * 32) * 33 +
                                       static_cast<std::size_t>(tx - std::int64_t{nx} * 32)) *
                                      2;
                const std::size_t t =
                    (static_cast<std::size_t>(toroidalTexel(ty, side)) * side + toroidalTexel(tx, side)) * 2;
                const ClipmapRing& ring = terrain.ring(r);
                if ((ring.normals[t] != node->normalMap[k] || ring.normals[t + 1] != node->normalMap[k + 1]) &&
                    ++mismatches <= 3) {
                    ADD_FAILURE() << "ring " << r << " texel (" << tx << ", " << ty << ") of node "
                                  << node->id.toString();
                }
                tilted += std::abs(ring.normals[t]) + std::abs(ring.normals[t + 1]) > 10;
                ++checked;
            }
        }
    }
    EXPECT_EQ(mismatches, 0);
    EXPECT_GT(checked, 6 * 40 * 40);
    EXPECT_GT(tilted, checked / 10) << "the hills' normals are not all flat";
}

TEST_F(ClipmapTerrainTest, RingsHoldTheSunsAndTheSkysVisibilityOfTheirNodesSamples)
{
    // Under a low sun every sample's colour alpha is its node's sun visibility there and its sky layer the sky's
    // (latticeVisibility of the node's horizons, both current and drawn before: nothing morphs); without a sun
    // both stay 255.
    auto grid = staticHeightGrid(*mMap, 2049);
    ASSERT_TRUE(grid.ok()) << grid.error().message;
    DetailPolicy policy;
    policy.horizonGrid = std::make_shared<const HeightGrid>(std::move(grid).value());
    TerrainNodeSource source(*mMap, policy);
    auto streamer = inlineStreamer(source, 600);
    ASSERT_TRUE(streamer);
    const int n = 31;
    const ClipmapSun sun{0.6, 60.0 * std::numbers::pi / 180};
    ClipmapLayout layout(extentOf(mMap->header()), 17, n, 4, 0);
    ClipmapTerrain terrain(layout, 17, 17, false, 0, 0.0, sun);
    ClipmapLayout plainLayout(extentOf(mMap->header()), 17, n, 4, 0);
    ClipmapTerrain plain(plainLayout, 17, 17);
    settle(layout, terrain, *streamer, 140.0, 90.0);
    settle(plainLayout, plain, *streamer, 140.0, 90.0);
    ASSERT_EQ(terrain.upsampledNodes(), 0u);
    int checked = 0, mismatches = 0, shadowed = 0, hidden = 0;
    for (int r = 0; r < layout.ringCount(); ++r) {
        const ClipmapWindow& win = layout.window(r);
        const std::int64_t last = std::int64_t{16} << win.level;
        for (std::int64_t gy = win.y0; gy < win.y0 + n; ++gy) {
            for (std::int64_t gx = win.x0; gx < win.x0 + n; ++gx) {
                if (gx < 0 || gy < 0 || gx > last || gy > last) {
                    continue;  // outside the terrain: clamped
                }
                const auto nx = static_cast<std::uint32_t>(std::min<std::int64_t>(gx / 16, (1 << win.level) - 1));
                const auto ny = static_cast<std::uint32_t>(std::min<std::int64_t>(gy / 16, (1 << win.level) - 1));
                NodePtr node = streamer->node({win.level, nx, ny});
                ASSERT_TRUE(node && node->horizons.size >= 2);
                std::vector<std::uint8_t> visibility(17 * 17 * 2);
                latticeVisibility(node->horizons, sun.azimuth, sun.elevation, kShadowSoftness, 17, visibility, 2, 0);
                const auto u = static_cast<std::size_t>(gx - std::int64_t{nx} * 16);
                const auto v = static_cast<std::size_t>(gy - std::int64_t{ny} * 16);
                const std::size_t t =
                    (static_cast<std::size_t>(toroidalTexel(gy, n)) * n + toroidalTexel(gx, n)) * 4 + 3;
                const std::uint8_t want = visibility[(v * 17 + u) * 2];
                if (terrain.ring(r).colour[t] != want && ++mismatches <= 3) {
                    ADD_FAILURE() << "ring " << r << " sample (" << gx << ", " << gy << ") of node "
                                  << node->id.toString() << ": " << int{terrain.ring(r).colour[t]} << ", not "
                                  << int{want};
                }
                const std::size_t s = (static_cast<std::size_t>(toroidalTexel(gy, n)) * n + toroidalTexel(gx, n)) * 2;
                const std::uint8_t sky = visibility[(v * 17 + u) * 2 + 1];
                if ((terrain.ring(r).sky[s] != sky || terrain.ring(r).sky[s + 1] != sky) && ++mismatches <= 3) {
                    ADD_FAILURE() << "ring " << r << " sample (" << gx << ", " << gy
                                  << ")'s sky: " << int{terrain.ring(r).sky[s]} << " and "
                                  << int{terrain.ring(r).sky[s + 1]} << ", not " << int{sky};
                }
                ASSERT_EQ(plain.ring(r).colour[t], 255);
                ASSERT_EQ(plain.ring(r).sky[s], 255);
                ASSERT_EQ(plain.ring(r).sky[s + 1], 255);
                shadowed += want < 128;
                hidden += sky < 230;
                ++checked;
            }
        }
    }
    EXPECT_EQ(mismatches, 0);
    EXPECT_GT(checked, 4 * 25 * 25);
    EXPECT_GT(shadowed, checked / 50)
        << "a 60 degree sun over the steep hills (60 m bumps 36 m apart) leaves some samples in shadow";
    EXPECT_GT(checked - shadowed, checked / 50) << "and some in the sun";
    EXPECT_GT(hidden, checked / 50) << "and some samples in hollows that see less of the sky";
}

TEST_F(ClipmapTerrainTest, MemoryIsBoundedByTheClipmapSizeOverALongFlight)
{
    // Issue 17: memory bounded by the clipmap, not by the path. A window of n samples meets at most
    // (n - 1) / (N - 1) + 2 nodes a side, so at most (that / 2 + 1)^2 sibling groups of its level; the coarser
    // rings hold every ancestor. A cache of exactly that many groups (plus the root) serves the whole flight:
    // every window settles with nothing upsampled (a smaller cache would refuse a wanted group: the cache never
    // overfills, NodeCache.h), the rings' bytes never change, and what the rings keep
    // for the renderer (changed rectangles, upsampled nodes) does not pile up.
    const auto synthesizer = test::grassAndRockSynthesizer(17);
    TerrainNodeSource source(*mMap, {synthesizer.get(), 0.05});
    const int n = 31, finest = 6;  // two levels of dynamic nodes below the map's four
    const std::size_t nodesASide = (n - 1) / 16 + 2;
    const std::size_t groupsPerRing = (nodesASide / 2 + 1) * (nodesASide / 2 + 1);
    const std::size_t bound = 1 + 4 * groupsPerRing * static_cast<std::size_t>(finest);  // level 0: the root
    auto streamer = inlineStreamer(source, bound);
    ASSERT_TRUE(streamer);
    ClipmapLayout layout(extentOf(mMap->header()), 17, n, finest, 0);
    ClipmapTerrain terrain(layout, 17, 17);
    const std::size_t bytes = terrain.bytes();
    EXPECT_EQ(bytes, std::size_t{finest + 1} * n * n * 22);
    // A long flight: three laps of a figure of eight over the whole terrain (5.9 km in 3 to 10 m steps).
    std::size_t largestCache = 0, largestWanted = 0, evictionsBefore = 0;
    constexpr int steps = 900;
    auto at = [](int s) {
        const double t = 6.0 * 3.14159265358979 * s / steps;
        return std::pair{256.0 + 230.0 * std::sin(t), 256.0 + 200.0 * std::sin(2.0 * t)};
    };
    for (int s = 0; s <= steps; ++s) {
        const auto [x, y] = at(s);
        const int rounds = settle(layout, terrain, *streamer, x, y);
        ASSERT_LT(rounds, 100) << "step " << s << ": the windows never settled in a cache of " << bound;
        ASSERT_EQ(terrain.upsampledNodes(), 0u) << "step " << s << ": a wanted node did not fit";
        const std::vector<NodeId> wanted = terrain.wanted(layout);
        largestWanted = std::max(largestWanted, wanted.size());
        largestCache = std::max(largestCache, streamer->cache().size());
        for (int r = 0; r < layout.ringCount(); ++r) {
            EXPECT_LE(terrain.changed(r).size(), 64u) << "step " << s << " ring " << r;
        }
        terrain.clearChanges();
        EXPECT_EQ(terrain.bytes(), bytes);
        if (s == steps / 3) {
            evictionsBefore = streamer->cache().evictions();
        }
    }
    std::printf("long flight: largest working set %zu nodes (bound %zu), cache %zu nodes (bound %zu), %llu evictions\n",
                largestWanted, nodesASide * nodesASide * static_cast<std::size_t>(finest) + 1, largestCache, bound,
                static_cast<unsigned long long>(streamer->cache().evictions()));
    EXPECT_LE(largestWanted, nodesASide * nodesASide * static_cast<std::size_t>(finest) + 1);
    // The flight did move the working set: later laps evict (and reload) what the first one loaded.
    EXPECT_GT(streamer->cache().evictions(), evictionsBefore);
    // And after the whole flight the rings hold what a fresh clipmap at the last position holds.
    ClipmapLayout freshLayout(extentOf(mMap->header()), 17, n, finest, 0);
    ClipmapTerrain fresh(freshLayout, 17, 17);
    settle(freshLayout, fresh, *streamer, at(steps).first, at(steps).second);
    for (int r = 0; r < layout.ringCount(); ++r) {
        EXPECT_EQ(fresh.ring(r).heights, terrain.ring(r).heights) << "ring " << r;
        EXPECT_EQ(fresh.ring(r).colour, terrain.ring(r).colour) << "ring " << r;
    }
}

}  // namespace
}  // namespace terrain
