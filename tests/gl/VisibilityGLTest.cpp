// Visible-pixel counts per drawn node (issue 16, PoolOptions::pixelCounts) on the GL itself, in both render
// modes: against a per-pixel reference made by drawing every node alone and comparing its depth with the
// frame's, a node that owns a visible pixel of the frame is never counted 0, and the counts exceed what the
// nodes own only by the fragments that a nearer node drawn later covered again (few: front to back). Then the
// read-back's timing: counts come two frames late, in order, and what is not taken is dropped.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Camera.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "lod/TessellationLevels.h"
#include "quadtree/MapFile.h"
#include "render/GlWindow.h"
#include "render/TerrainRenderer.h"

#include <gtest/gtest.h>

#include <numbers>

namespace terrain {
namespace {

std::vector<float> readDepth(int width, int height)
{
    std::vector<float> depth(static_cast<std::size_t>(width) * height);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    return depth;
}

enum class RenderMode { Chunks, Tessellation, BlocksInSmallArrays };

class VisibilityGLTest : public ::testing::TestWithParam<RenderMode> {};

TEST_P(VisibilityGLTest, EveryNodeOwningAVisiblePixelIsCountedAndCountsMatchThePixelsOwned)
{
    const RenderMode mode = GetParam();
    const bool tessellation = mode != RenderMode::Chunks;  // block levels chosen
    auto scene = test::openDemoScene(480, 270);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    ASSERT_TRUE(TerrainRenderer::pixelCountsSupported()) << (*scene)->window->description();
    const MapHeader& header = (*scene)->map->header();
    TerrainNodeSource source(*(*scene)->map, {nullptr, 0.0, tessellation ? kTessellationBlockQuads : 0});
    StreamerOptions streamerOptions;
    streamerOptions.cacheSize = mode == RenderMode::BlocksInSmallArrays ? 400 : 2048;
    streamerOptions.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(header), streamerOptions);
    ASSERT_TRUE(streamer.ok());
    PoolOptions pools;
    pools.slots = streamerOptions.cacheSize;
    pools.tessellation = tessellation;
    pools.blockIndices = mode == RenderMode::BlocksInSmallArrays;
    // Pools of 3-layer arrays draw a group per pair of arrays, in an order that is not the list's: the counts must
    // follow the drawing order.
    pools.layersPerArray = mode == RenderMode::BlocksInSmallArrays ? 3 : 0;
    pools.pixelCounts = true;
    auto renderer = TerrainRenderer::create(TERRAIN_SHADER_DIR, header, 16, pools);
    ASSERT_TRUE(renderer.ok()) << renderer.error().message;

    // Low in a valley looking along it: ridges hide much of what the selection refines behind them.
    Camera camera;
    camera.viewportWidth = 480;
    camera.viewportHeight = 270;
    camera.nearPlane = 1.0;
    camera.farPlane = 150000.0;
    camera.position = {15000.0, 12000.0, 2496.0};
    camera.yaw = 47.7 * std::numbers::pi / 180;
    camera.pitch = -8.0 * std::numbers::pi / 180;
    const double nodePixels = 1.0, blockPixels = 1.0;
    (*streamer)->settle(Settle::Complete, camera, nodePixels);
    const TerrainStreamer& s = **streamer;
    const ResidentNodeLookup resident = [&s](const NodeId& id) { return s.node(id); };
    const LodSelection& selection = s.selection();
    ASSERT_GT(selection.nodes.size(), 20u);
    SceneStyle style;
    style.drawSky = false;
    (*renderer)->draw(makeDrawList(selection, s, camera, tessellation ? blockPixels : 0.0), style);
    PixelCounts counts;
    ASSERT_TRUE((*renderer)->takePixelCounts(counts, 0));
    ASSERT_EQ(counts.nodes.size(), selection.nodes.size());
    ASSERT_EQ(counts.pixels.size(), counts.nodes.size());
    const int w = camera.viewportWidth, h = camera.viewportHeight;
    const std::vector<float> frame = readDepth(w, h);

    // The reference: a pixel belongs to the node whose depth there, drawn alone, is the frame's (with GL_LESS the
    // first fragment at the final depth is the one that passed). Where several nodes reach that depth, the pixel
    // goes to whichever drew it first, which depends on how the renderer splits its draws: such a pixel counts
    // as owned by the first in the list for the sums, and for none of them node by node.
    std::vector<std::size_t> owned(counts.nodes.size(), 0);
    std::vector<std::size_t> ownedAlone(counts.nodes.size(), 0);
    std::vector<int> owners(frame.size(), 0);
    std::vector<std::size_t> firstOwner(frame.size(), 0);
    std::vector<bool> taken(frame.size(), false);
    std::size_t terrainPixels = 0;
    for (float d : frame) {
        terrainPixels += d < 1.0f ? 1 : 0;
    }
    LodSelection alone;
    for (std::size_t i = 0; i < counts.nodes.size(); ++i) {
        const auto it = std::find_if(selection.nodes.begin(), selection.nodes.end(),
                                     [&](const SelectedNode& n) { return n.id == counts.nodes[i]; });
        ASSERT_NE(it, selection.nodes.end()) << "counted node " << counts.nodes[i].toString() << " was not selected";
        alone.nodes.assign(1, *it);
        (*renderer)->draw(makeDrawList(alone, s, camera, tessellation ? blockPixels : 0.0), style);
        const std::vector<float> depth = readDepth(w, h);
        for (std::size_t p = 0; p < depth.size(); ++p) {
            if (depth[p] < 1.0f && depth[p] == frame[p]) {
                owners[p] += 1;
                if (!taken[p]) {
                    taken[p] = true;
                    firstOwner[p] = i;
                    ++owned[i];
                }
            }
        }
        PixelCounts single;
        ASSERT_TRUE((*renderer)->takePixelCounts(single, 0));
        ASSERT_EQ(single.nodes.size(), 1u);
    }
    std::size_t tied = 0;
    for (std::size_t p = 0; p < frame.size(); ++p) {
        if (owners[p] == 1) {
            ++ownedAlone[firstOwner[p]];
        }
        tied += owners[p] > 1 ? 1 : 0;
    }
    EXPECT_LT(tied, frame.size() / 1000) << "nodes tie in depth at only a few pixels (shared edges)";
    std::size_t visible = 0, hidden = 0, countedSum = 0, ownedSum = 0;
    for (std::size_t i = 0; i < owned.size(); ++i) {
        if (ownedAlone[i] > 0) {
            EXPECT_GT(counts.pixels[i], 0u)
                << counts.nodes[i].toString() << " owns " << ownedAlone[i] << " visible pixels but was counted 0";
        }
        EXPECT_GE(counts.pixels[i], ownedAlone[i]) << counts.nodes[i].toString();
        (counts.pixels[i] > 0 ? visible : hidden) += 1;
        countedSum += counts.pixels[i];
        ownedSum += owned[i];
    }
    EXPECT_EQ(ownedSum, terrainPixels) << "every terrain pixel is owned by a node";
    EXPECT_LE(countedSum, ownedSum + ownedSum / 10) << "front to back, few fragments are covered again";
    EXPECT_GE(countedSum, terrainPixels);
    EXPECT_GT(visible, 5u);
    // Small arrays draw group by group, not front to back: a hidden node drawn before what hides it shows pixels.
    EXPECT_GT(hidden, mode == RenderMode::BlocksInSmallArrays ? 1u : 5u)
        << "the valley view hides nodes behind its ridges";
    std::printf(
        "%s: %zu nodes, %zu with visible pixels, %zu hidden; %zu fragments counted, %zu pixels owned (%zu tied), "
        "%zu terrain pixels\n",
        mode == RenderMode::Chunks         ? "chunks"
        : mode == RenderMode::Tessellation ? "tessellation"
                                           : "blocks, small arrays",
        owned.size(), visible, hidden, countedSum, ownedSum, tied, terrainPixels);
}

TEST_P(VisibilityGLTest, CountsComeTwoFramesLateInOrderAndUntakenOnesAreDropped)
{
    const RenderMode mode = GetParam();
    const bool tessellation = mode != RenderMode::Chunks;  // block levels chosen
    auto scene = test::openDemoScene(160, 90);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const MapHeader& header = (*scene)->map->header();
    TerrainNodeSource source(*(*scene)->map, {nullptr, 0.0, tessellation ? kTessellationBlockQuads : 0});
    auto streamer = TerrainStreamer::create(source, extentOf(header), {});
    ASSERT_TRUE(streamer.ok());
    PoolOptions pools;
    pools.tessellation = tessellation;
    pools.blockIndices = mode == RenderMode::BlocksInSmallArrays;
    // Pools of 3-layer arrays draw a group per pair of arrays, in an order that is not the list's: the counts must
    // follow the drawing order.
    pools.layersPerArray = mode == RenderMode::BlocksInSmallArrays ? 3 : 0;
    pools.pixelCounts = true;
    auto renderer = TerrainRenderer::create(TERRAIN_SHADER_DIR, header, 16, pools);
    ASSERT_TRUE(renderer.ok()) << renderer.error().message;
    Camera camera;
    camera.viewportWidth = 160;
    camera.viewportHeight = 90;
    camera.position = {20000.0, -20000.0, 9000.0};
    camera.yaw = 0.0;
    camera.pitch = -20.0 * std::numbers::pi / 180;
    (*streamer)->update(camera, 2.0);
    (*streamer)->drain();
    (*streamer)->update(camera, 2.0);
    const TerrainStreamer& s = **streamer;
    auto draw = [&] { (*renderer)->draw(makeDrawList(s.selection(), s, camera, tessellation ? 1.0 : 0.0), {}); };
    PixelCounts counts;
    draw();  // frame 1
    EXPECT_FALSE((*renderer)->takePixelCounts(counts));
    draw();  // frame 2
    EXPECT_FALSE((*renderer)->takePixelCounts(counts));
    draw();  // frame 3: frame 1's counts are due
    ASSERT_TRUE((*renderer)->takePixelCounts(counts));
    EXPECT_EQ(counts.frame, 1u);
    EXPECT_EQ(counts.nodes.size(), s.selection().nodes.size());
    std::uint64_t sum = 0;
    for (std::uint32_t p : counts.pixels) {
        sum += p;
    }
    EXPECT_GT(sum, 0u);
    EXPECT_FALSE((*renderer)->takePixelCounts(counts)) << "frame 2 is one frame late only";
    ASSERT_TRUE((*renderer)->takePixelCounts(counts, 0));
    EXPECT_EQ(counts.frame, 2u) << "the oldest first";
    EXPECT_EQ((*renderer)->droppedPixelCounts(), 0u);
    draw();  // frame 4 takes frame 1's buffer, which was taken
    draw();  // frame 5 takes frame 2's, taken
    draw();  // frame 6 takes frame 3's, never taken: dropped
    EXPECT_EQ((*renderer)->droppedPixelCounts(), 1u);
    ASSERT_TRUE((*renderer)->takePixelCounts(counts));
    EXPECT_EQ(counts.frame, 4u);
}

INSTANTIATE_TEST_SUITE_P(RenderModes, VisibilityGLTest,
                         ::testing::Values(RenderMode::Chunks, RenderMode::Tessellation,
                                           RenderMode::BlocksInSmallArrays),
                         [](const ::testing::TestParamInfo<RenderMode>& mode) {
                             return mode.param == RenderMode::Chunks         ? "Chunks"
                                    : mode.param == RenderMode::Tessellation ? "Tessellation"
                                                                             : "BlocksInSmallArrays";
                         });

}  // namespace
}  // namespace terrain
