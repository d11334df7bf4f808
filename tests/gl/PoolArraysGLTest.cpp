// Node pools spread over several texture arrays (PoolOptions::layersPerArray, kMaxPoolArrays): the frame drawn
// from pools of many small arrays, where a node's parent often lies in another array than the node, is the frame
// drawn from one array, in both render modes, with normal maps and geomorphing colours (both read the parent's
// layer).
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Camera.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "lod/TessellationLevels.h"
#include "quadtree/ChunkGeometry.h"
#include "quadtree/MapFile.h"
#include "render/FrameCapture.h"
#include "render/GlWindow.h"
#include "render/TerrainRenderer.h"
#include "synthesis/NormalMap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <utility>

namespace terrain {
namespace {

enum class Mode { Chunks, Tessellation, Blocks };

class PoolArraysGLTest : public ::testing::TestWithParam<Mode> {};

TEST_P(PoolArraysGLTest, ManySmallArraysDrawTheFrameOneArrayDraws)
{
    const bool blockIndices = GetParam() == Mode::Blocks;
    const bool tessellation = GetParam() == Mode::Tessellation;  // by tessellation shaders
    auto scene = test::openDemoScene(640, 360);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    if (tessellation) {
        ASSERT_TRUE(TerrainRenderer::tessellationSupported()) << (*scene)->window->description();
    }
    MapFile& map = *(*scene)->map;
    const MapHeader& header = map.header();
    DetailPolicy policy;
    policy.tessellationBlockQuads = tessellation || blockIndices ? kTessellationBlockQuads : 0;
    policy.normalMapSize = 64;
    TerrainNodeSource source(map, policy);
    constexpr std::size_t kSlots = 400;
    StreamerOptions streamerOptions;
    streamerOptions.cacheSize = kSlots;
    streamerOptions.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(header), streamerOptions);
    ASSERT_TRUE(streamer.ok());

    Camera camera;
    camera.viewportWidth = 640;
    camera.viewportHeight = 360;
    camera.nearPlane = 1.0;
    camera.farPlane = 150000.0;
    camera.position = {15000.0, 12000.0, 2496.0};
    camera.yaw = 47.7 * std::numbers::pi / 180;
    camera.pitch = -8.0 * std::numbers::pi / 180;
    const double pixels = 1.0;
    (*streamer)->settle(Settle::Complete, camera, pixels);
    const TerrainStreamer& s = **streamer;
    const LodSelection& selection = s.selection();
    ASSERT_GT(selection.nodes.size(), 40u);
    std::size_t morphing = 0;
    for (const SelectedNode& selected : selection.nodes) {
        morphing += !selected.id.isRoot() && selected.morph < 0.9f ? 1 : 0;
    }
    ASSERT_GT(morphing, 10u) << "the view must show nodes whose colours and normals come half from their parents";

    SceneStyle style;
    style.hazeDistance = 1e9f;
    // 3 layers an array: a parent and its four children never fit in one, so many nodes are drawn with their
    // parent's colour and normal map from another array.
    constexpr std::size_t kLayers = 3;
    // The nodes in the order the split pools draw them (grouped by the arrays of the node and its parent), so
    // that both frames draw the same triangles. In chunks mode they come in the same order, so fragments that tie
    // in depth resolve alike; in tessellation mode the runs of draws differ between one group and many, and the
    // frames agree only because skirts lose every tie (terrain.tese). Either way they must be the same, pixel for
    // pixel.
    DrawList frame = makeDrawList(selection, s, camera, tessellation || blockIndices ? pixels : 0.0);
    std::stable_sort(frame.nodes.begin(), frame.nodes.end(), [](const DrawnNode& a, const DrawnNode& b) {
        return std::pair(a.slot / kLayers, a.parentSlot / kLayers) <
               std::pair(b.slot / kLayers, b.parentSlot / kLayers);
    });
    auto drawWith = [&](std::size_t layersPerArray, RenderStats& stats) {
        PoolOptions pools;
        pools.slots = kSlots;
        pools.tessellation = tessellation || blockIndices;
        pools.blockIndices = blockIndices;
        pools.normalMapTexels = normalMapTexels(policy.normalMapSize);
        pools.layersPerArray = layersPerArray;
        auto renderer = TerrainRenderer::create(TERRAIN_SHADER_DIR, header, 16, pools);
        EXPECT_TRUE(renderer.ok()) << renderer.error().message;
        if (!renderer.ok()) {
            return Image{};
        }
        stats = (*renderer)->draw(frame, style);
        glFinish();
        return captureFrame(camera.viewportWidth, camera.viewportHeight);
    };
    RenderStats one, many;
    const Image reference = drawWith(0, one);
    const Image split = drawWith(kLayers, many);
    ASSERT_EQ(reference.width, split.width);
    ASSERT_EQ(reference.height, split.height);
    // One array: one group, drawn at once (chunks, blocks) or in runs of nodes and ranges of patches (tessellation).
    const auto blocks = static_cast<std::size_t>((header.chunkSize - 1) / kTessellationBlockQuads);
    const std::size_t patches = blocks * (blocks + 4);
    const std::size_t runs = (one.nodes + TerrainRenderer::kNodesPerRun - 1) / TerrainRenderer::kNodesPerRun;
    const std::size_t ranges = (patches + TerrainRenderer::kPatchesPerDraw - 1) / TerrainRenderer::kPatchesPerDraw;
    EXPECT_EQ(one.drawCalls, tessellation ? runs * ranges : 1u);
    const std::size_t arraysUsed = (many.gpuNodes + kLayers - 1) / kLayers;
    // Many arrays: a group holds at most kLayers nodes, one run of `ranges` draws in tessellation mode.
    const std::size_t groups = tessellation ? many.drawCalls / ranges : many.drawCalls;
    EXPECT_EQ(groups * (tessellation ? ranges : 1u), many.drawCalls);
    EXPECT_GT(groups, arraysUsed) << "some nodes must be drawn with their parent in another array";
    EXPECT_EQ(many.triangles, one.triangles);
    EXPECT_EQ(many.nodes, one.nodes);
    std::size_t differing = 0;
    for (int y = 0; y < reference.height; ++y) {
        for (int x = 0; x < reference.width; ++x) {
            differing += std::memcmp(reference.pixel(x, y), split.pixel(x, y), 3) != 0 ? 1 : 0;
        }
    }
    EXPECT_EQ(differing, 0u) << "pixels differ between the frame of one array and that of many";
}

INSTANTIATE_TEST_SUITE_P(RenderModes, PoolArraysGLTest,
                         ::testing::Values(Mode::Chunks, Mode::Tessellation, Mode::Blocks),
                         [](const ::testing::TestParamInfo<Mode>& mode) {
                             return mode.param == Mode::Chunks         ? std::string("Chunks")
                                    : mode.param == Mode::Tessellation ? std::string("Tessellation")
                                                                       : std::string("Blocks");
                         });

}  // namespace
}  // namespace terrain
