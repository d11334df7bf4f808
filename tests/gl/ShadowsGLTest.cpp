// Terrain shadows as drawn (shadows, lod/NodeHorizons.h) against the truth: under a low sun, every pixel of the
// bundled terrain in view is put back in the world from the depth buffer, and a ray marched from that point of the
// height data towards the sun in quarter-sample steps says whether it is in shadow. The frame drawn with shadows,
// over the same frame drawn without (no ambient light: the ratio is the sun's visibility), says what the renderer
// shadowed. Intersection over union of the two sets, in both render modes.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Camera.h"
#include "heightfield/HeightFieldIo.h"
#include "lod/NodeHorizons.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "lod/TessellationLevels.h"
#include "quadtree/MapFile.h"
#include "render/FrameCapture.h"
#include "render/GlWindow.h"
#include "render/TerrainRenderer.h"
#include "synthesis/NormalMap.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_inverse.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

namespace terrain {
namespace {

class ShadowsGLTest : public ::testing::TestWithParam<bool> {};

TEST_P(ShadowsGLTest, DrawnShadowsAreTheShadowsOfRaysMarchedOverTheHeightData)
{
    const bool tessellation = GetParam();
    constexpr int kWidth = 480, kHeight = 270;
    auto scene = test::openDemoScene(kWidth, kHeight);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    MapFile& map = *(*scene)->map;
    const MapHeader& header = map.header();
    auto grid = staticHeightGrid(map, 2049);
    ASSERT_TRUE(grid.ok()) << grid.error().message;
    // The truth's surface: the input's samples themselves (bilinear), not the map's grid.
    auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    ASSERT_EQ(field->width, grid->width) << "the map's finest level is the input";
    const HeightGrid data{field->width,   field->height,        header.originX,
                          header.originY, header.sampleSpacing, field->samples};

    DetailPolicy policy;
    policy.tessellationBlockQuads = tessellation ? kTessellationBlockQuads : 0;
    policy.normalMapSize = 64;
    policy.horizonGrid = std::make_shared<const HeightGrid>(std::move(grid).value());
    TerrainNodeSource source(map, policy);
    constexpr std::size_t kSlots = 600;
    StreamerOptions streamerOptions;
    streamerOptions.cacheSize = kSlots;
    streamerOptions.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(header), streamerOptions);
    ASSERT_TRUE(streamer.ok());

    // Over the range's crest, looking north-east and down; the sun low in the south-east.
    Camera camera;
    camera.viewportWidth = kWidth;
    camera.viewportHeight = kHeight;
    camera.nearPlane = 5.0;
    camera.farPlane = 150000.0;
    camera.position = {52000.0, 52000.0, 11000.0};
    camera.yaw = 45.0 * std::numbers::pi / 180;
    camera.pitch = -60.0 * std::numbers::pi / 180;
    const double pixels = 1.0;
    (*streamer)->settle(Settle::Complete, camera, pixels);
    const DrawList frame = makeDrawList((*streamer)->selection(), **streamer, camera, tessellation ? pixels : 0.0);

    const double sunAzimuth = 135.0 * std::numbers::pi / 180, sunElevation = 10.0 * std::numbers::pi / 180;
    SceneStyle style;
    style.sunDirection = glm::vec3(static_cast<float>(std::sin(sunAzimuth) * std::cos(sunElevation)),
                                   static_cast<float>(std::cos(sunAzimuth) * std::cos(sunElevation)),
                                   static_cast<float>(std::sin(sunElevation)));
    style.sunColour = glm::vec3(3.0f);  // bright: a low sun on flat ground gives 0.17 of it
    style.ambient = glm::vec3(0.0f);
    style.hazeDistance = 1e9f;
    style.drawSky = false;
    std::vector<float> depth;
    auto drawWith = [&](bool shadows) {
        PoolOptions pools;
        pools.slots = kSlots;
        pools.tessellation = tessellation;
        pools.normalMapTexels = normalMapTexels(policy.normalMapSize);
        pools.shadows = shadows;
        auto renderer = TerrainRenderer::create(TERRAIN_SHADER_DIR, header, 16, pools);
        EXPECT_TRUE(renderer.ok()) << renderer.error().message;
        if (!renderer.ok()) {
            return Image{};
        }
        (*renderer)->draw(frame, style);
        glFinish();
        depth = TerrainRenderer::readDepth(kWidth, kHeight);
        return captureFrame(kWidth, kHeight);
    };
    const Image open = drawWith(false);
    const Image shadowed = drawWith(true);
    if (const char* keep = std::getenv("TERRAIN_KEEP_FRAMES")) {
        (void)writePngImage(std::filesystem::path(keep) / (tessellation ? "shadows-tess.png" : "shadows.png"),
                            shadowed);
        (void)writePngImage(std::filesystem::path(keep) / (tessellation ? "open-tess.png" : "open.png"), open);
    }
    ASSERT_EQ(open.width, kWidth);
    ASSERT_EQ(shadowed.width, kWidth);

    const glm::dmat4 toWorld = glm::inverse(camera.viewProjection());
    const glm::dvec3 toSun(std::sin(sunAzimuth) * std::cos(sunElevation), std::cos(sunAzimuth) * std::cos(sunElevation),
                           std::sin(sunElevation));
    const double step = 0.25 * header.sampleSpacing;
    int both = 0, either = 0, compared = 0, dark = 0, terrain = 0;
    std::vector<double> misfit;
    Image agreement = open;  // with TERRAIN_KEEP_FRAMES: white both, red rays only, blue drawn only
    for (int y = 0; y < kHeight; y += 2) {
        for (int x = 0; x < kWidth; x += 2) {
            const float d = depth[static_cast<std::size_t>(kHeight - 1 - y) * kWidth + static_cast<std::size_t>(x)];
            if (d >= 1.0f) {
                continue;  // no terrain
            }
            const glm::dvec4 ndc((x + 0.5) / kWidth * 2.0 - 1.0, 1.0 - (y + 0.5) / kHeight * 2.0, d * 2.0 - 1.0, 1.0);
            const glm::dvec4 h = toWorld * ndc;
            const glm::dvec3 p = glm::dvec3(h) / h.w;
            ++terrain;
            misfit.push_back(std::abs(p.z - data.at(p.x, p.y)));  // the input holds absolute heights
            // Compared where the sun lights the open frame: slopes turned from the sun are dark in both.
            const double lit = open.pixel(x, y)[1];
            if (lit < 20.0) {
                continue;
            }
            ++compared;
            const bool drawnDark = shadowed.pixel(x, y)[1] < 0.5 * lit;
            // The truth from the data's surface at the point, out to the horizons' 20 km.
            const double z = data.at(p.x, p.y);
            bool hidden = false;
            for (double r = step; r <= 20000.0 && !hidden; r += step) {
                hidden = data.at(p.x + r * toSun.x, p.y + r * toSun.y) > z + r * toSun.z;
            }
            std::uint8_t* a = agreement.pixel(x, y);
            if (hidden || drawnDark) {
                a[0] = hidden ? 255 : 0;
                a[1] = hidden && drawnDark ? 255 : 0;
                a[2] = drawnDark ? 255 : 0;
            }
            both += hidden && drawnDark;
            either += hidden || drawnDark;
            dark += drawnDark;
        }
    }
    if (const char* keep = std::getenv("TERRAIN_KEEP_FRAMES")) {
        (void)writePngImage(std::filesystem::path(keep) / (tessellation ? "agreement-tess.png" : "agreement.png"),
                            agreement);
    }
    ASSERT_GT(terrain, 1000);
    std::nth_element(misfit.begin(), misfit.begin() + static_cast<std::ptrdiff_t>(misfit.size() / 2), misfit.end());
    ASSERT_LT(misfit[misfit.size() / 2], 30.0) << "the depth buffer's points lie on the terrain";
    const double iou = either > 0 ? static_cast<double>(both) / either : 0.0;
    std::printf(
        "%s: %d terrain pixels, %d lit in the open frame, %d of them shadowed by rays or drawn dark, %d drawn "
        "dark, IoU %.3f\n",
        tessellation ? "tessellation" : "chunks", terrain, compared, either, dark, iou);
    ASSERT_GT(compared, 1000);
    EXPECT_GT(either, compared / 20) << "the view must show shadows";
    EXPECT_GE(iou, 0.8);
}

INSTANTIATE_TEST_SUITE_P(RenderModes, ShadowsGLTest, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& mode) {
                             return mode.param ? std::string("Tessellation") : std::string("Chunks");
                         });

}  // namespace
}  // namespace terrain
