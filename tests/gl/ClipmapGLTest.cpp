// lod_mode = clipmap's morph on the GL itself (issue 17, render/ClipmapRenderer.h, shaders/clipmap.vert): when
// nodes arrive where the rings were drawn upsampled from the coarser ring, the first frame after shows what the
// frame before showed (no pop), and once clipmap_morph_seconds have passed the frame is the one drawn from the
// same nodes without any morph, pixel for pixel: the shader runs the morph ClipmapTerrain::drawnSample models.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Camera.h"
#include "lod/ClipmapLayout.h"
#include "lod/ClipmapTerrain.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "render/ClipmapRenderer.h"
#include "render/FrameCapture.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <numbers>

namespace terrain {
namespace {

/// Pixels of `a` and `b` whose channels differ by more than `levels`.
int pixelsDiffering(const Image& a, const Image& b, int levels)
{
    int count = 0;
    for (int y = 0; y < a.height; ++y) {
        for (int x = 0; x < a.width; ++x) {
            const std::uint8_t* p = a.pixel(x, y);
            const std::uint8_t* q = b.pixel(x, y);
            bool differs = false;
            for (int c = 0; c < 3; ++c) {
                differs = differs || std::abs(int{p[c]} - int{q[c]}) > levels;
            }
            count += differs ? 1 : 0;
        }
    }
    return count;
}

TEST(ClipmapGLTest, ArrivingNodesMorphInFromWhatWasDrawnAndEndOnTheirOwnSurface)
{
    auto scene = test::openDemoScene(480, 270);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    const MapHeader& header = (*scene)->map->header();
    const int chunk = static_cast<int>(header.chunkSize);
    TerrainNodeSource source(*(*scene)->map, {});
    StreamerOptions streamerOptions;
    streamerOptions.workers = 0;
    auto streamer = TerrainStreamer::create(source, extentOf(header), streamerOptions);
    ASSERT_TRUE(streamer.ok());
    const ResidentNodeLookup lookup = [&streamer](const NodeId& id) { return (*streamer)->node(id); };

    // Rings of 63 samples from the map's leaves (level 4, 90 m) to the root.
    const int finest = static_cast<int>(header.levels) - 1;
    ClipmapLayout layout(extentOf(header), chunk, 63, finest, 0);
    ClipmapLayout settledLayout(extentOf(header), chunk, 63, finest, 0);
    constexpr double kMorph = 0.4;
    ClipmapTerrain terrain(layout, chunk, static_cast<int>(header.textureSize), false, 0, kMorph);
    ClipmapTerrain settled(settledLayout, chunk, static_cast<int>(header.textureSize), false, 0, kMorph);
    auto renderer = ClipmapRenderer::create(TERRAIN_SHADER_DIR, header, layout);
    ASSERT_TRUE(renderer.ok()) << renderer.error().message;
    auto settledRenderer = ClipmapRenderer::create(TERRAIN_SHADER_DIR, header, settledLayout);
    ASSERT_TRUE(settledRenderer.ok()) << settledRenderer.error().message;

    // Over the range, looking down a slope: rings 0 to 2 fill most of the frame.
    Camera camera;
    camera.viewportWidth = 480;
    camera.viewportHeight = 270;
    camera.nearPlane = 1.0;
    camera.farPlane = 150000.0;
    camera.position = {51000.0, 51000.0, 4600.0};
    camera.yaw = 215.0 * std::numbers::pi / 180;
    camera.pitch = -35.0 * std::numbers::pi / 180;
    SceneStyle style;
    style.drawSky = false;
    style.clearColour = {1.0f, 0.0f, 1.0f};
    auto draw = [&](ClipmapRenderer& r, ClipmapTerrain& t, const ClipmapLayout& l) {
        r.draw(l, t, 0, camera, style);
        glFinish();
        return captureFrame(camera.viewportWidth, camera.viewportHeight);
    };
    const std::vector<std::vector<LatticeRect>> none(static_cast<std::size_t>(layout.ringCount()));
    auto load = [&](ClipmapTerrain& t, const ClipmapLayout& l, double now) {
        for (int round = 0; round < 32 && t.upsampledNodes() > 0; ++round) {
            (*streamer)->updateFor(t.wanted(l));
            (*streamer)->drain();
            t.update(l, none, lookup, now);
        }
        return t.upsampledNodes();
    };

    // Time 0: only the root is resident, every finer ring is drawn upsampled from it.
    terrain.update(layout, layout.moveTo(camera.position.x, camera.position.y), lookup, 0.0);
    ASSERT_GT(terrain.upsampledNodes(), 0u);
    const Image upsampled = draw(**renderer, terrain, layout);
    // Time 1: every node has arrived.
    ASSERT_EQ(load(terrain, layout, 1.0), 0u);
    const Image arrived = draw(**renderer, terrain, layout);
    terrain.update(layout, none, lookup, 1.0 + 0.5 * kMorph);
    const Image halfway = draw(**renderer, terrain, layout);
    terrain.update(layout, none, lookup, 1.0 + 1.5 * kMorph);
    const Image over = draw(**renderer, terrain, layout);
    // The same nodes, resident before the rings are first filled: no morph at all.
    settled.update(settledLayout, settledLayout.moveTo(camera.position.x, camera.position.y), lookup, 5.0);
    ASSERT_EQ(load(settled, settledLayout, 5.0), 0u);
    const Image reference = draw(**settledRenderer, settled, settledLayout);

    const int pixels = upsampled.width * upsampled.height;
    const int popped = pixelsDiffering(upsampled, reference, 8);
    std::printf("pixels changed by more than 8 levels by the nodes: %d of %d; at their arrival: %d; halfway: %d\n",
                popped, pixels, pixelsDiffering(upsampled, arrived, 8), pixelsDiffering(upsampled, halfway, 8));
    EXPECT_GT(popped, pixels / 20) << "the nodes change the frame: without the morph it would pop";
    // The frame at their arrival is the frame before, up to the rounding of colours blended on the GPU instead
    // of upsampled on the CPU.
    EXPECT_LT(pixelsDiffering(upsampled, arrived, 8), pixels / 1000);
    EXPECT_LT(pixelsDiffering(upsampled, halfway, 8), popped) << "halfway is on its way";
    EXPECT_GT(pixelsDiffering(upsampled, halfway, 8), 0) << "halfway is on its way";
    // Once the morph is over, exactly the frame drawn without one.
    EXPECT_EQ(pixelsDiffering(over, reference, 0), 0);
}

}  // namespace
}  // namespace terrain
