// Terrain shadows and sky visibility as drawn (shadows, lod/NodeHorizons.h) against the truth: every pixel of the
// bundled terrain in view is put back in the world from the depth buffer. Under a low sun, a ray marched from that
// point of the height data towards the sun in quarter-sample steps says whether it is in shadow; the frame drawn
// with shadows over the same frame drawn without (no ambient light: the ratio is the sun's visibility) says what
// the renderer shadowed: intersection over union of the two sets. Under the sky alone (no sun), the ratio of the
// two frames is the sky's visibility drawn; rays marched over 32 azimuths give the share of the cosine-weighted
// sky above the terrain's horizons there. In every render mode: chunks, tessellation, the clipmap's rings.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Camera.h"
#include "heightfield/HeightFieldIo.h"
#include "lod/ClipmapLayout.h"
#include "lod/ClipmapTerrain.h"
#include "lod/NodeHorizons.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "lod/TessellationLevels.h"
#include "quadtree/MapFile.h"
#include "render/ClipmapRenderer.h"
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

enum class Mode { kChunks, kTessellation, kClipmap };

/// A frame and its depth buffer.
struct DrawnFrame {
    Image image;
    std::vector<float> depth;
};

/// The share of a horizontal surface's cosine-weighted sky above the horizons of `data` at (x, y, z), from rays
/// marched in quarter-sample steps over 32 azimuths out to 20 km (Horizon.h's skyVisibility, brute force).
double marchedSkyVisibility(const HeightGrid& data, double x, double y, double z)
{
    constexpr int kAzimuths = 32;
    const double step = 0.25 * data.spacing;
    double sum = 0.0;
    for (int k = 0; k < kAzimuths; ++k) {
        const double a = 2.0 * std::numbers::pi * k / kAzimuths;
        const double dx = std::cos(a), dy = std::sin(a);
        double tangent = 0.0;
        for (double r = step; r <= 20000.0; r += step) {
            tangent = std::max(tangent, (data.at(x + r * dx, y + r * dy) - z) / r);
        }
        sum += 1.0 / (1.0 + tangent * tangent);
    }
    return sum / kAzimuths;
}

/// What the test draws: the camera's frame of the streamer's nodes in `mode` (the draw list for chunks and
/// tessellation; clipmap rings of 255 samples, the default, from the map's leaves to the root, every node
/// resident), with the sun the rings' shadows are made for.
struct ShadowScene {
    Mode mode;
    const MapHeader& header;
    const Camera& camera;
    TerrainStreamer& streamer;
    const DrawList& frame;
    int normalMapTexels;
    std::size_t slots;
    ClipmapSun sun;
};

/// The scene drawn with or without shadows in `style`: the frame and its depth buffer.
DrawnFrame drawScene(const ShadowScene& s, bool shadows, const SceneStyle& style)
{
    DrawnFrame drawn;
    if (s.mode == Mode::kClipmap) {
        const int chunk = static_cast<int>(s.header.chunkSize);
        ClipmapLayout layout(extentOf(s.header), chunk, 255, static_cast<int>(s.header.levels) - 1, 0);
        ClipmapTerrain rings(layout, chunk, static_cast<int>(s.header.textureSize), false, 0, 0.0,
                             shadows ? std::optional(s.sun) : std::nullopt);
        const ResidentNodeLookup lookup = [&](const NodeId& id) { return s.streamer.node(id); };
        rings.update(layout, layout.moveTo(s.camera.position.x, s.camera.position.y), lookup);
        const std::vector<std::vector<LatticeRect>> none(static_cast<std::size_t>(layout.ringCount()));
        for (int round = 0; round < 32 && rings.upsampledNodes() > 0; ++round) {
            s.streamer.updateFor(rings.wanted(layout));
            s.streamer.drain();
            rings.update(layout, none, lookup);
        }
        EXPECT_EQ(rings.upsampledNodes(), 0u);
        auto renderer = ClipmapRenderer::create(TERRAIN_SHADER_DIR, s.header, layout);
        EXPECT_TRUE(renderer.ok()) << renderer.error().message;
        if (!renderer.ok()) {
            return drawn;
        }
        (*renderer)->draw(layout, rings, 0, s.camera, style);
    } else {
        PoolOptions pools;
        pools.slots = s.slots;
        pools.tessellation = s.mode == Mode::kTessellation;
        pools.normalMapTexels = s.normalMapTexels;
        pools.shadows = shadows;
        auto renderer = TerrainRenderer::create(TERRAIN_SHADER_DIR, s.header, 16, pools);
        EXPECT_TRUE(renderer.ok()) << renderer.error().message;
        if (!renderer.ok()) {
            return drawn;
        }
        (*renderer)->draw(s.frame, style);
    }
    glFinish();
    drawn.depth = TerrainRenderer::readDepth(s.camera.viewportWidth, s.camera.viewportHeight);
    drawn.image = captureFrame(s.camera.viewportWidth, s.camera.viewportHeight);
    return drawn;
}

class ShadowsGLTest : public ::testing::TestWithParam<Mode> {};

TEST_P(ShadowsGLTest, DrawnShadowsAndSkyAreThoseOfRaysMarchedOverTheHeightData)
{
    const Mode mode = GetParam();
    const bool tessellation = mode == Mode::kTessellation;
    const char* name = mode == Mode::kChunks ? "chunks" : (tessellation ? "tessellation" : "clipmap");
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
    const glm::dvec3 toSun(std::sin(sunAzimuth) * std::cos(sunElevation), std::cos(sunAzimuth) * std::cos(sunElevation),
                           std::sin(sunElevation));
    SceneStyle sunOnly;
    sunOnly.sunDirection = glm::vec3(toSun);
    sunOnly.sunColour = glm::vec3(3.0f);  // bright: a low sun on flat ground gives 0.17 of it
    sunOnly.ambient = glm::vec3(0.0f);
    sunOnly.hazeDistance = 1e9f;
    sunOnly.drawSky = false;
    SceneStyle skyOnly = sunOnly;
    skyOnly.sunColour = glm::vec3(0.0f);
    skyOnly.ambient = glm::vec3(1.0f);
    const ShadowScene drawn{mode,   header,
                            camera, **streamer,
                            frame,  normalMapTexels(policy.normalMapSize),
                            kSlots, {std::atan2(toSun.y, toSun.x), sunElevation}};
    auto draw = [&](bool shadows, const SceneStyle& style) { return drawScene(drawn, shadows, style); };
    const DrawnFrame open = draw(false, sunOnly);
    const DrawnFrame shadowed = draw(true, sunOnly);
    const DrawnFrame openSky = draw(false, skyOnly);
    const DrawnFrame shadedSky = draw(true, skyOnly);
    if (const char* keep = std::getenv("TERRAIN_KEEP_FRAMES")) {
        const std::filesystem::path folder(keep);
        (void)writePngImage(folder / ("shadows-" + std::string(name) + ".png"), shadowed.image);
        (void)writePngImage(folder / ("open-" + std::string(name) + ".png"), open.image);
        (void)writePngImage(folder / ("sky-" + std::string(name) + ".png"), shadedSky.image);
    }
    ASSERT_EQ(open.image.width, kWidth);
    ASSERT_EQ(shadowed.image.width, kWidth);
    ASSERT_EQ(openSky.image.width, kWidth);
    ASSERT_EQ(shadedSky.image.width, kWidth);

    const glm::dmat4 toWorld = glm::inverse(camera.viewProjection());
    const double step = 0.25 * header.sampleSpacing;
    int both = 0, either = 0, compared = 0, dark = 0, terrain = 0;
    std::vector<double> misfit;
    // The sky's visibility, drawn against marched, and the error of drawing none (1 everywhere).
    double skyError = 0.0, openSkyError = 0.0;
    int skyCompared = 0;
    Image agreement = open.image;  // with TERRAIN_KEEP_FRAMES: white both, red rays only, blue drawn only
    for (int y = 0; y < kHeight; y += 2) {
        for (int x = 0; x < kWidth; x += 2) {
            const float d =
                open.depth[static_cast<std::size_t>(kHeight - 1 - y) * kWidth + static_cast<std::size_t>(x)];
            if (d >= 1.0f) {
                continue;  // no terrain
            }
            const glm::dvec4 ndc((x + 0.5) / kWidth * 2.0 - 1.0, 1.0 - (y + 0.5) / kHeight * 2.0, d * 2.0 - 1.0, 1.0);
            const glm::dvec4 h = toWorld * ndc;
            const glm::dvec3 p = glm::dvec3(h) / h.w;
            ++terrain;
            misfit.push_back(std::abs(p.z - data.at(p.x, p.y)));  // the input holds absolute heights
            // The data's surface at the point.
            const double z = data.at(p.x, p.y);
            const double skyLit = openSky.image.pixel(x, y)[1];
            if (x % 8 == 0 && y % 8 == 0 && skyLit >= 40.0) {
                const double truth = marchedSkyVisibility(data, p.x, p.y, z);
                skyError += std::abs(shadedSky.image.pixel(x, y)[1] / skyLit - truth);
                openSkyError += 1.0 - truth;
                ++skyCompared;
            }
            // Compared where the sun lights the open frame: slopes turned from the sun are dark in both.
            const double lit = open.image.pixel(x, y)[1];
            if (lit < 20.0) {
                continue;
            }
            ++compared;
            const bool drawnDark = shadowed.image.pixel(x, y)[1] < 0.5 * lit;
            // The truth out to the horizons' 20 km.
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
        (void)writePngImage(std::filesystem::path(keep) / ("agreement-" + std::string(name) + ".png"), agreement);
    }
    ASSERT_GT(terrain, 1000);
    std::nth_element(misfit.begin(), misfit.begin() + static_cast<std::ptrdiff_t>(misfit.size() / 2), misfit.end());
    ASSERT_LT(misfit[misfit.size() / 2], 30.0) << "the depth buffer's points lie on the terrain";
    const double iou = either > 0 ? static_cast<double>(both) / either : 0.0;
    ASSERT_GT(skyCompared, 300);
    skyError /= skyCompared;
    openSkyError /= skyCompared;
    std::printf(
        "%s: %d terrain pixels, %d lit in the open frame, %d of them shadowed by rays or drawn dark, %d drawn "
        "dark, IoU %.3f; sky visibility at %d points: mean error %.3f drawn, %.3f drawing none\n",
        name, terrain, compared, either, dark, iou, skyCompared, skyError, openSkyError);
    ASSERT_GT(compared, 1000);
    EXPECT_GT(either, compared / 20) << "the view must show shadows";
    EXPECT_GE(iou, 0.8);
    EXPECT_GT(openSkyError, 0.015) << "the view must show valleys that see less of the sky";
    EXPECT_LT(skyError, 0.4 * openSkyError);
}

INSTANTIATE_TEST_SUITE_P(RenderModes, ShadowsGLTest,
                         ::testing::Values(Mode::kChunks, Mode::kTessellation, Mode::kClipmap),
                         [](const ::testing::TestParamInfo<Mode>& mode) {
                             return mode.param == Mode::kChunks
                                        ? std::string("Chunks")
                                        : (mode.param == Mode::kTessellation ? std::string("Tessellation")
                                                                             : std::string("Clipmap"));
                         });

}  // namespace
}  // namespace terrain
