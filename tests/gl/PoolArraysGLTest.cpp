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

#include <cmath>
#include <numbers>

namespace terrain {
namespace {

class PoolArraysGLTest : public ::testing::TestWithParam<bool> {};

TEST_P(PoolArraysGLTest, ManySmallArraysDrawTheFrameOneArrayDraws)
{
    const bool tessellation = GetParam();
    auto scene = test::openDemoScene(640, 360);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    if (tessellation) {
        ASSERT_TRUE(TerrainRenderer::tessellationSupported()) << (*scene)->window->description();
    }
    MapFile& map = *(*scene)->map;
    const MapHeader& header = map.header();
    DetailPolicy policy;
    policy.tessellationBlockQuads = tessellation ? kTessellationBlockQuads : 0;
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
    auto drawWith = [&](std::size_t layersPerArray, RenderStats& stats) {
        PoolOptions pools;
        pools.slots = kSlots;
        pools.tessellation = tessellation;
        pools.normalMapTexels = normalMapTexels(policy.normalMapSize);
        pools.layersPerArray = layersPerArray;
        auto renderer = TerrainRenderer::create(TERRAIN_SHADER_DIR, header, 16, pools);
        EXPECT_TRUE(renderer.ok()) << renderer.error().message;
        if (!renderer.ok()) {
            return Image{};
        }
        stats = (*renderer)->draw(
            selection, [&s](const NodeId& id) { return s.node(id); }, camera, style, pixels);
        glFinish();
        return captureFrame(camera.viewportWidth, camera.viewportHeight);
    };
    RenderStats one, many;
    const Image reference = drawWith(0, one);
    // 3 layers an array: a parent and its four children never fit in one, so many nodes are drawn with their
    // parent's colour and normal map from another array.
    constexpr std::size_t kLayers = 3;
    const Image split = drawWith(kLayers, many);
    ASSERT_EQ(reference.width, split.width);
    ASSERT_EQ(reference.height, split.height);
    EXPECT_EQ(one.drawCalls, 1u);
    const std::size_t arraysUsed = (many.gpuNodes + kLayers - 1) / kLayers;
    EXPECT_GT(many.drawCalls, arraysUsed) << "some nodes must be drawn with their parent in another array";
    EXPECT_EQ(many.triangles, one.triangles);
    EXPECT_EQ(many.nodes, one.nodes);
    // The same pixels, but where two nodes' fragments tie in depth (skirts against their neighbours): there the
    // draw order, which the arrays change, decides.
    std::size_t differing = 0, far = 0;
    for (int y = 0; y < reference.height; ++y) {
        for (int x = 0; x < reference.width; ++x) {
            const std::uint8_t* a = reference.pixel(x, y);
            const std::uint8_t* b = split.pixel(x, y);
            int largest = 0;
            for (int c = 0; c < 3; ++c) {
                largest = std::max(largest, std::abs(static_cast<int>(a[c]) - static_cast<int>(b[c])));
            }
            differing += largest > 0 ? 1 : 0;
            far += largest > 8 ? 1 : 0;
        }
    }
    const std::size_t total = static_cast<std::size_t>(reference.width) * static_cast<std::size_t>(reference.height);
    EXPECT_LE(differing, total / 1000) << differing << " of " << total << " pixels differ";
    EXPECT_EQ(far, 0u) << "pixels differing by more than 8 grey levels";
}

INSTANTIATE_TEST_SUITE_P(RenderModes, PoolArraysGLTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& mode) {
                             return mode.param ? std::string("Tessellation") : std::string("Chunks");
                         });

}  // namespace
}  // namespace terrain
