// The viewer end to end under Xvfb + Mesa llvmpipe: frames are checked, not just exit codes.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Camera.h"
#include "heightfield/HeightFieldIo.h"
#include "heightfield/Image.h"
#include "light/Atmosphere.h"
#include "lod/CameraPath.h"
#include "lod/HeightQuery.h"
#include "lod/LodSelector.h"
#include "lod/TerrainNodeSource.h"
#include "quadtree/ChunkGeometry.h"
#include "quadtree/MapFile.h"
#include "quadtree/QuadtreeBuilder.h"
#include "render/TerrainRenderer.h"
#include "synthesis/LeafErrorEstimator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <numbers>
#include <sstream>

namespace terrain {
namespace {

using test::isHole;
using test::mustHitTerrain;
using test::readCsv;

/// The bundled terrain as a map, built once for all tests.
class TengineGLTest : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        sDir = new test::ScratchDir();
        auto built = test::buildDemoMap(*sDir / "trinidad.map");
        ASSERT_TRUE(built.ok()) << built.error().message;
        // The same terrain with the detail errors of the shipped materials below its leaves (3.4.1), as
        // prep --material makes it.
        auto detailed = test::buildDemoMap(*sDir / "trinidad-detail.map", detailMaterials());
        ASSERT_TRUE(detailed.ok()) << detailed.error().message;
        // A slow low flight (10 m/s, 30 m above a hillside) where dynamic nodes reach a few centimetres.
        std::ofstream low(*sDir / "low.path");
        low << "0 51000 51000 3700 215 -15\n"
               "3 50979 50979 3700 215 -15\n";
        // A short low flight up a valley and over a ridge, then a steep look down (demos/trinidad.path's
        // opening and middle, sped up).
        std::ofstream path(*sDir / "flight.path");
        path << "0 15000 12000 2496 47.7 -8\n"
                "2 36000 33000 2700 41.6 -10\n"
                "4 46500 45500 4400 39.8 -15\n"
                "6 58000 60000 3900 29.1 -30\n"
                "8 60000 70000 7000 -50 -60\n";
    }
    static void TearDownTestSuite()
    {
        delete sDir;
        sDir = nullptr;
    }

    static std::filesystem::path map() { return *sDir / "trinidad.map"; }
    static std::filesystem::path detailMap() { return *sDir / "trinidad-detail.map"; }
    static std::vector<std::filesystem::path> detailMaterials()
    {
        const std::filesystem::path dir = TERRAIN_MATERIALS_DIR;
        return {dir / "grass.mat", dir / "rock.mat"};
    }
    /// The shipped materials without their detail textures, written to `dir`: drawn with them, a frame shows the
    /// same relief, colours and tints as with the shipped ones, without the detail layers.
    static std::vector<std::filesystem::path> plainMaterials(const std::filesystem::path& dir)
    {
        std::vector<std::filesystem::path> plain;
        for (const auto& file : detailMaterials()) {
            std::ifstream in(file);
            std::ofstream out(dir / file.filename());
            for (std::string line; std::getline(in, line);) {
                if (line.rfind("detail_texture", 0) != 0) {
                    out << line << "\n";
                }
            }
            plain.push_back(dir / file.filename());
        }
        return plain;
    }
    /// The detail layers' share of the luminance of `detailed` in its `width` x `height` window at (x0, y0): over
    /// the same frame drawn with plainMaterials(), `flat`, so that the relief's shading and the colours cancel.
    static std::vector<double> detailShare(const Image& detailed, const Image& flat, int x0, int y0, int width,
                                           int height)
    {
        std::vector<double> share;
        for (int y = y0; y < y0 + height; ++y) {
            for (int x = x0; x < x0 + width; ++x) {
                auto luminance = [&](const Image& image) {
                    const std::uint8_t* p = image.pixel(x, y);
                    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
                };
                share.push_back(luminance(detailed) / std::max(luminance(flat), 1.0));
            }
        }
        return share;
    }
    /// detailShare of the centred `width` x `height` window of the 1280 x 720 frame that camera path `path` shows
    /// first over `mapFile` in video mode, drawn with the shipped materials and with plainMaterials() (frames and
    /// material copies go under `dir`), with further settings `more`. Empty where a frame is missing or of
    /// another size (reported).
    static std::vector<double> centredDetailShare(const std::filesystem::path& mapFile,
                                                  const std::filesystem::path& path, const std::filesystem::path& dir,
                                                  int width, int height, const std::vector<std::string>& more = {})
    {
        const std::vector<std::filesystem::path> plain = plainMaterials(dir);
        const auto files = detailMaterials();
        auto draw = [&](const std::string& name, const std::vector<std::filesystem::path>& materials) {
            std::vector<std::string> args = {
                mapFile.string(),
                "--set",
                "camera_path=" + path.string(),
                "--set",
                "video_mode=true",
                "--set",
                "video_ffmpeg=false",
                "--set",
                "video_frames=1",
                "--set",
                "draw_user_interface=false",
                "--set",
                "image_path=" + (dir / name).string(),
                "--set",
                "detail_materials=" + materials[0].string() + ", " + materials[1].string()};
            for (const std::string& setting : more) {
                args.push_back("--set");
                args.push_back(setting);
            }
            const test::RunResult run = test::runProgram(TERRAIN_TENGINE_EXE, args);
            EXPECT_EQ(run.exitCode, 0) << run.output;
            return frame(dir / name, 0);
        };
        const Image detailed = draw("detailed", files);
        const Image flat = draw("flat", plain);
        EXPECT_EQ(detailed.width, 1280);
        EXPECT_EQ(flat.width, 1280);
        if (detailed.width != 1280 || flat.width != 1280) {
            return {};
        }
        return detailShare(detailed, flat, (detailed.width - width) / 2, (detailed.height - height) / 2, width, height);
    }
    /// Settings that fly the low path with the shipped materials (over detailMap()), plus `more`.
    static std::vector<std::string> lowDetailFlight(std::vector<std::string> more)
    {
        const auto files = detailMaterials();
        more.push_back("camera_path=" + (*sDir / "low.path").string());
        more.push_back("detail_materials=" + files[0].string() + ", " + files[1].string());
        return more;
    }
    static std::filesystem::path flight() { return *sDir / "flight.path"; }

    /// Runs tengine in video mode with `settings` and returns its result; frames go to `frames`.
    static test::RunResult video(const std::filesystem::path& frames, std::vector<std::string> settings,
                                 const std::filesystem::path& mapFile = {})
    {
        std::vector<std::string> args = {mapFile.empty() ? map().string() : mapFile.string(),
                                         "--set",
                                         "camera_path=" + flight().string(),
                                         "--set",
                                         "video_mode=true",
                                         "--set",
                                         "video_ffmpeg=false",
                                         "--set",
                                         "image_path=" + frames.string(),
                                         "--set",
                                         "window_width=320",
                                         "--set",
                                         "window_height=180"};
        for (auto& s : settings) {
            args.push_back("--set");
            args.push_back(s);
        }
        return test::runProgram(TERRAIN_TENGINE_EXE, args);
    }

    static Image frame(const std::filesystem::path& frames, int index)
    {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05d.png", index);
        auto image = readPngImage(frames / name, 3);
        EXPECT_TRUE(image.ok()) << (image.ok() ? "" : image.error().message);
        return image.ok() ? image.value() : Image{};
    }

    static void expectNoHolesAlongTheFlight(const std::vector<std::string>& more);

    /// The camera a video frame of `image`'s size was drawn with at `t` seconds of `path` (60 degrees, far 150 km).
    static Camera frameCamera(const CameraPath& path, double t, const Image& image)
    {
        Camera camera;
        camera.viewportWidth = image.width;
        camera.viewportHeight = image.height;
        camera.verticalFov = 60.0 * std::numbers::pi / 180;
        camera.farPlane = 150000;
        path.evaluate(t).applyTo(camera);
        return camera;
    }
    /// The hole check of one frame: pixels whose view ray must hit the terrain (above zMin) and, of them, those
    /// showing the clear colour, with the first one's position.
    struct Holes {
        int holes = 0, checked = 0, firstX = -1, firstY = -1;
    };
    static Holes holesIn(const Image& image, const Camera& camera, const MapHeader& header, double zMin)
    {
        Holes h;
        for (int y = 0; y < image.height; ++y) {
            for (int x = 0; x < image.width; ++x) {
                if (mustHitTerrain(camera, header, zMin, x, y)) {
                    ++h.checked;
                    if (isHole(image.pixel(x, y)) && h.holes++ == 0) {
                        h.firstX = x;
                        h.firstY = y;
                    }
                }
            }
        }
        return h;
    }

    static test::ScratchDir* sDir;
};

test::ScratchDir* TengineGLTest::sDir = nullptr;

TEST_F(TengineGLTest, TerrainIsThereAndTheSkyAboveIt)
{
    test::ScratchDir frames;
    auto run = video(frames.path(), {"video_frames=1"});
    ASSERT_EQ(run.exitCode, 0) << run.output;
    Image image = frame(frames.path(), 0);
    ASSERT_EQ(image.width, 320);
    // The camera looks slightly down over the valley: the bottom half is ground (green-brown, darker than
    // the sky and less blue), the top rows are sky (blue dominates).
    int ground = 0, sky = 0;
    for (int x = 0; x < image.width; ++x) {
        const std::uint8_t* bottom = image.pixel(x, image.height - 1);
        ground += (bottom[1] >= bottom[2]) ? 1 : 0;
        const std::uint8_t* top = image.pixel(x, 0);
        sky += (top[2] > top[0] && top[2] > top[1]) ? 1 : 0;
    }
    EXPECT_GT(ground, image.width * 9 / 10);
    EXPECT_GT(sky, image.width * 9 / 10);
}

/// The hole check over the flight, 4 frames a second, with `more` settings: no pixel whose view ray must hit
/// the terrain shows the clear colour.
void TengineGLTest::expectNoHolesAlongTheFlight(const std::vector<std::string>& more)
{
    test::ScratchDir frames;
    std::vector<std::string> settings = {"frames_per_second=4", "draw_sky=false",  "draw_user_interface=false",
                                         "clear_color=1,0,1",   "haze_distance=0", "camera_z_far=150000"};
    settings.insert(settings.end(), more.begin(), more.end());
    auto run = video(frames.path(), settings);
    ASSERT_EQ(run.exitCode, 0) << run.output;
    auto mapFile = MapFile::open(map(), ReaderKind::Stream);
    ASSERT_TRUE(mapFile.ok());
    const MapHeader& header = (*mapFile)->header();
    const double zMin = header.heightOf((*mapFile)->directory().front().minCode);
    auto path = CameraPath::load(flight());
    ASSERT_TRUE(path.ok());
    int framesChecked = 0, pixelsChecked = 0;
    for (int f = 0;; ++f) {
        if (!std::filesystem::exists(frames.path() / ("frame_" + std::string(5 - std::to_string(f).size(), '0') +
                                                      std::to_string(f) + ".png"))) {
            break;
        }
        const Image image = frame(frames.path(), f);
        const Holes h = holesIn(image, frameCamera(*path, f / 4.0, image), header, zMin);
        pixelsChecked += h.checked;
        EXPECT_EQ(h.holes, 0) << "frame " << f << ": " << h.holes
                              << " pixels show the clear colour below the horizon, first at (" << h.firstX << ", "
                              << h.firstY << ")";
        ++framesChecked;
    }
    EXPECT_EQ(framesChecked, 33);
    EXPECT_GT(pixelsChecked, framesChecked * 320 * 180 / 4) << "the flight should look at the ground";
}

TEST_F(TengineGLTest, NoHolesAlongTheFlight)
{
    expectNoHolesAlongTheFlight({"render_mode=chunks"});
}

/// render_mode = tessellation (issue 13): no holes, neither between nodes (skirts) nor inside them where
/// blocks of different levels meet (snapped sides); per program a frame (with a cache that fits one texture array a
/// pool), its nodes in runs and each run's patches in ranges (TerrainRenderer::drawPatchRanges); identical frames
/// run to run; and fewer triangles than chunks on the same flight.
TEST_F(TengineGLTest, TessellationHasNoHolesRunsOfDrawsAndFewerTriangles)
{
    expectNoHolesAlongTheFlight({"render_mode=tessellation"});
    test::ScratchDir a, b, chunks;
    const std::vector<std::string> settings = {"frames_per_second=2", "render_mode=tessellation",
                                               "quad_cache_size=2048"};
    auto run = video(a.path(), settings);
    ASSERT_EQ(run.exitCode, 0) << run.output;
    ASSERT_EQ(video(b.path(), settings).exitCode, 0);
    ASSERT_EQ(video(chunks.path(), {"frames_per_second=2", "render_mode=chunks", "quad_cache_size=2048"}).exitCode, 0);
    for (int f = 0; f <= 16; ++f) {
        Image first = frame(a.path(), f), second = frame(b.path(), f);
        ASSERT_EQ(first.pixels.size(), second.pixels.size());
        EXPECT_TRUE(first.pixels == second.pixels) << "frame " << f << " differs";
    }
    const auto tessellated = readCsv(a.path() / "frames.csv"), chunked = readCsv(chunks.path() / "frames.csv");
    ASSERT_EQ(tessellated.size(), chunked.size());
    double sumTessellated = 0.0, sumChunked = 0.0;
    for (std::size_t f = 0; f < tessellated.size(); ++f) {
        // The map's 65-sample nodes have 8 x 8 blocks: 64 + 4 x 8 patches, drawn in ranges, for each run of nodes
        // of a program (one or two: nodes beyond the detail layers' fade go in a second program).
        const double ranges = std::ceil(96.0 / TerrainRenderer::kPatchesPerDraw);
        const double runs = std::ceil((tessellated[f].at("nodes_static") + tessellated[f].at("nodes_dynamic")) /
                                      static_cast<double>(TerrainRenderer::kNodesPerRun));
        EXPECT_EQ(std::fmod(tessellated[f].at("draw_calls"), ranges), 0.0) << "frame " << f;
        EXPECT_GE(tessellated[f].at("draw_calls"), ranges * runs) << "frame " << f;
        EXPECT_LE(tessellated[f].at("draw_calls"), ranges * (runs + 1.0)) << "frame " << f;
        sumTessellated += tessellated[f].at("triangles");
        sumChunked += chunked[f].at("triangles");
    }
    std::printf("triangles per frame: tessellation %.0f, chunks %.0f (%.2fx fewer)\n",
                sumTessellated / static_cast<double>(tessellated.size()),
                sumChunked / static_cast<double>(chunked.size()), sumChunked / sumTessellated);
    EXPECT_LT(2.0 * sumTessellated, sumChunked);
}

/// render_mode = blocks (the default): the tessellation mode's blocks from index lists, no holes along the flight,
/// identical frames run to run, one draw a program (the pools fit one array), and fewer triangles than the
/// tessellator makes for the same blocks (no collapsed cells, two triangles a skirt cell).
TEST_F(TengineGLTest, BlocksHaveNoHolesOneDrawAProgramAndFewerTrianglesThanTessellation)
{
    expectNoHolesAlongTheFlight({"render_mode=blocks"});
    test::ScratchDir a, b, tessellation;
    const std::vector<std::string> settings = {"frames_per_second=2", "quad_cache_size=2048"};  // the default mode
    auto run = video(a.path(), settings);
    ASSERT_EQ(run.exitCode, 0) << run.output;
    ASSERT_EQ(video(b.path(), settings).exitCode, 0);
    ASSERT_EQ(video(tessellation.path(), {"frames_per_second=2", "render_mode=tessellation", "quad_cache_size=2048"})
                  .exitCode,
              0);
    for (int f = 0; f <= 16; ++f) {
        Image first = frame(a.path(), f), second = frame(b.path(), f);
        ASSERT_EQ(first.pixels.size(), second.pixels.size());
        EXPECT_TRUE(first.pixels == second.pixels) << "frame " << f << " differs";
    }
    const auto blocks = readCsv(a.path() / "frames.csv"), tessellated = readCsv(tessellation.path() / "frames.csv");
    ASSERT_EQ(blocks.size(), tessellated.size());
    double sumBlocks = 0.0, sumTessellated = 0.0;
    for (std::size_t f = 0; f < blocks.size(); ++f) {
        EXPECT_GE(blocks[f].at("draw_calls"), 1.0) << "frame " << f;
        EXPECT_LE(blocks[f].at("draw_calls"), 2.0) << "frame " << f << ": one or two programs, one array";
        EXPECT_EQ(blocks[f].at("nodes_static") + blocks[f].at("nodes_dynamic"),
                  tessellated[f].at("nodes_static") + tessellated[f].at("nodes_dynamic"))
            << "frame " << f << ": the same selection";
        sumBlocks += blocks[f].at("triangles");
        sumTessellated += tessellated[f].at("triangles");
    }
    std::printf("triangles per frame: blocks %.0f, tessellation %.0f (%.2fx fewer)\n",
                sumBlocks / static_cast<double>(blocks.size()),
                sumTessellated / static_cast<double>(tessellated.size()), sumTessellated / sumBlocks);
    EXPECT_LT(sumBlocks, sumTessellated);
    EXPECT_GT(sumBlocks, 0.5 * sumTessellated) << "the same blocks";
}

/// Hardware without tessellation shaders (here: Mesa told to offer OpenGL 3.3 only) draws chunks instead of
/// failing, and says so in one line.
/// lod_mode = clipmap (seed 002, issue 17): no holes along the flight, identical frames run to run, the cache
/// within the size its memory budget pays for and the ring data a fixed size (memory bounded by the clipmap, not
/// the path).
TEST_F(TengineGLTest, ClipmapModeHasNoHolesAndIdenticalFrames)
{
    expectNoHolesAlongTheFlight({"lod_mode=clipmap"});
    test::ScratchDir a, b;
    const std::vector<std::string> settings = {"frames_per_second=2", "lod_mode=clipmap", "worker_threads=2"};
    auto run = video(a.path(), settings);
    ASSERT_EQ(run.exitCode, 0) << run.output;
    ASSERT_EQ(video(b.path(), settings).exitCode, 0);
    for (int f = 0; f <= 16; ++f) {
        Image first = frame(a.path(), f), second = frame(b.path(), f);
        ASSERT_EQ(first.pixels.size(), second.pixels.size());
        EXPECT_TRUE(first.pixels == second.pixels) << "frame " << f << " differs";
    }
    // 255 x 255 samples, 22 bytes each (heights, morphs, colours and the colours morphs start from, sky visibility
    // now and before) on the CPU and on the GPU, for levels 0 to the finest.
    EXPECT_NE(run.output.find("clipmap: "), std::string::npos) << run.output;
    // The cache within the capacity memory_budget pays for (the log says how many nodes).
    const std::size_t holds = run.output.find(" holds ");
    ASSERT_NE(holds, std::string::npos) << run.output;
    const double capacity = std::stod(run.output.substr(holds + 7));
    EXPECT_GE(capacity, 5.0);
    const auto rows = readCsv(a.path() / "frames.csv");
    ASSERT_EQ(rows.size(), 17u);
    for (const auto& row : rows) {
        EXPECT_LE(row.at("cache_nodes"), capacity);
        EXPECT_GT(row.at("triangles"), 0.0);
    }
}

/// A close low look with small clipmaps (n = 15: rings of 14 cells, so the transitions of seven rings are in
/// view, from 5.6 m spacing out) shows no seam where rings meet: no pixel of the terrain shows the clear colour.
TEST_F(TengineGLTest, ClipmapRingsMeetWithoutSeamsUpClose)
{
    test::ScratchDir frames;
    const std::filesystem::path close = frames.path() / "close.path";
    {
        std::ofstream out(close);
        out << "0 51000 51000 3760 215 -55\n"
               "1 51013 51020 3752 200 -40\n";
    }
    const std::vector<std::string> settings = {"camera_path=" + close.string(),
                                               "frames_per_second=4",
                                               "lod_mode=clipmap",
                                               "clipmap_samples=15",
                                               "draw_sky=false",
                                               "draw_user_interface=false",
                                               "clear_color=1,0,1",
                                               "haze_distance=0"};
    auto run = video(frames.path(), settings, detailMap());
    ASSERT_EQ(run.exitCode, 0) << run.output;
    auto mapFile = MapFile::open(detailMap(), ReaderKind::Stream);
    ASSERT_TRUE(mapFile.ok());
    const MapHeader& header = (*mapFile)->header();
    const double zMin = header.heightOf((*mapFile)->directory().front().minCode);
    auto path = CameraPath::load(close);
    ASSERT_TRUE(path.ok());
    for (int f = 0; f <= 4; ++f) {
        const Image image = frame(frames.path(), f);
        const Holes h = holesIn(image, frameCamera(*path, f / 4.0, image), header, zMin);
        EXPECT_GT(h.checked, image.width * image.height / 2) << "frame " << f << " should look at the ground";
        EXPECT_EQ(h.holes, 0) << "frame " << f << ": " << h.holes << " pixels show the clear colour, first at ("
                              << h.firstX << ", " << h.firstY << ")";
    }
    const auto rows = readCsv(frames.path() / "frames.csv");
    ASSERT_FALSE(rows.empty());
    EXPECT_GT(rows.front().at("deepest_level"), 4.0) << "rings below the map's data (dynamic levels) drawn";
}

/// lod_mode = clipmap draws the materials' detail textures and the nodes' normal maps as the quadtree does
/// (render/DetailLayers.h, dynamic_texture_size): the same low view with the shipped materials and with copies
/// that lack their detail_texture lines (the same synthesis, the same ring heights) differs on the near
/// ground by fine-grained contrast, the textures' grain; without the textures, the normal maps add shading
/// finer than the rings' triangles (against dynamic_texture_size = 0, lit by vertex normals).
TEST_F(TengineGLTest, ClipmapModeDrawsTheMaterialsDetailTexturesAndNormalMaps)
{
    test::ScratchDir plainMaterials;
    std::vector<std::filesystem::path> plain;
    for (const auto& file : detailMaterials()) {
        std::ifstream in(file);
        std::ofstream out(plainMaterials.path() / file.filename());
        for (std::string line; std::getline(in, line);) {
            if (line.rfind("detail_texture", 0) != 0) {
                out << line << "\n";
            }
        }
        plain.push_back(plainMaterials.path() / file.filename());
    }
    // The last detail_materials setting counts: lowDetailFlight's are the shipped ones.
    auto render = [&](const std::filesystem::path& frames, const std::vector<std::filesystem::path>& materials,
                      std::string more = "video_frames=1") {
        std::vector<std::string> settings = {"video_frames=1", "draw_user_interface=false", "lod_mode=clipmap", more};
        settings = lowDetailFlight(settings);
        if (!materials.empty()) {
            settings.push_back("detail_materials=" + materials[0].string() + ", " + materials[1].string());
        }
        auto run = video(frames, settings, detailMap());
        EXPECT_EQ(run.exitCode, 0) << run.output;
        return frame(frames, 0);
    };
    test::ScratchDir with, without, unmapped;
    const Image textured = render(with.path(), {});
    const Image smooth = render(without.path(), plain);
    const Image flat = render(unmapped.path(), plain, "dynamic_texture_size=0");
    ASSERT_EQ(textured.pixels.size(), smooth.pixels.size());
    // Grain: the mean absolute difference between horizontal neighbours over the lowest quarter (the ground
    // nearest the camera, where every layer shows).
    auto grain = [](const Image& image) {
        double sum = 0.0;
        std::size_t count = 0;
        for (int y = image.height * 3 / 4; y < image.height; ++y) {
            for (int x = 1; x < image.width; ++x) {
                for (int c = 0; c < 3; ++c) {
                    sum += std::abs(int(image.pixel(x, y)[c]) - int(image.pixel(x - 1, y)[c]));
                    ++count;
                }
            }
        }
        return sum / static_cast<double>(count);
    };
    const double withGrain = grain(textured), withoutGrain = grain(smooth);
    std::printf("clipmap near-ground grain: %.3f with detail textures, %.3f without\n", withGrain, withoutGrain);
    EXPECT_GT(withGrain, 1.4 * withoutGrain) << "the detail textures must show on the near ground";
    const double flatGrain = grain(flat);
    std::printf("clipmap near-ground grain without detail textures: %.3f with normal maps, %.3f without\n",
                withoutGrain, flatGrain);
    EXPECT_GT(withoutGrain, 1.2 * flatGrain) << "the normal maps must shade the near ground finer";
}

/// Without OpenGL 4.3 (here: Mesa told to offer 4.1) render_mode = blocks tessellates the same blocks, and says so;
/// without 4.0 it draws chunks.
TEST_F(TengineGLTest, WithoutIndirectDrawsBlocksAreTessellated)
{
    for (const auto& [version, fallback] :
         {std::pair{"4.1", "drawing the blocks by tessellation shaders"}, std::pair{"3.3", "drawing chunks"}}) {
        test::ScratchDir frames;
        ::setenv("MESA_GL_VERSION_OVERRIDE", version, 1);  // inherited by the viewer this test starts
        auto run = video(frames.path(), {"frames_per_second=1", "render_mode=blocks"});
        ::unsetenv("MESA_GL_VERSION_OVERRIDE");
        ASSERT_EQ(run.exitCode, 0) << run.output;
        EXPECT_NE(run.output.find(std::string("render_mode = blocks needs OpenGL 4.3 (indirect draws with base "
                                              "instances), which this GL lacks: ") +
                                  fallback),
                  std::string::npos)
            << run.output;
        EXPECT_EQ(run.output.find("render_mode = tessellation needs"), std::string::npos) << "one line";
        const auto rows = readCsv(frames.path() / "frames.csv");
        ASSERT_FALSE(rows.empty());
        for (const auto& row : rows) {
            if (std::string(version) == "3.3") {
                EXPECT_EQ(std::fmod(row.at("triangles"), static_cast<double>(trianglesPerChunk(65))), 0.0)
                    << "whole chunks";
                EXPECT_LE(row.at("draw_calls"), 2.0) << "one instanced draw a program";
            } else {
                EXPECT_GE(row.at("draw_calls"), std::ceil(96.0 / TerrainRenderer::kPatchesPerDraw))
                    << "runs of nodes times ranges of patches (TerrainRenderer::drawPatchRanges)";
            }
        }
    }
}

TEST_F(TengineGLTest, WithoutTessellationShadersTheTessellationModeFallsBackToChunks)
{
    test::ScratchDir frames;
    ::setenv("MESA_GL_VERSION_OVERRIDE", "3.3", 1);  // inherited by the viewer this test starts
    auto run = video(frames.path(), {"frames_per_second=1", "render_mode=tessellation"});
    ::unsetenv("MESA_GL_VERSION_OVERRIDE");
    ASSERT_EQ(run.exitCode, 0) << run.output;
    EXPECT_NE(run.output.find("OpenGL 3.3"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("render_mode = tessellation needs OpenGL 4.0 tessellation shaders, which this GL "
                              "lacks: drawing chunks"),
              std::string::npos)
        << run.output;
    const auto rows = readCsv(frames.path() / "frames.csv");
    ASSERT_FALSE(rows.empty());
    for (const auto& row : rows) {
        // Whole chunks: every node with all its triangles and skirts.
        EXPECT_EQ(std::fmod(row.at("triangles"), static_cast<double>(trianglesPerChunk(65))), 0.0);
    }
}

TEST_F(TengineGLTest, SameRunGivesIdenticalFrames)
{
    test::ScratchDir a, b;
    // Chunks here; TessellationHasNoHolesOneDrawAndFewerTriangles checks the default mode's frames.
    std::vector<std::string> settings = {"frames_per_second=2", "worker_threads=2", "render_mode=chunks"};
    ASSERT_EQ(video(a.path(), settings).exitCode, 0);
    ASSERT_EQ(video(b.path(), settings).exitCode, 0);
    for (int f = 0; f <= 16; ++f) {
        Image first = frame(a.path(), f), second = frame(b.path(), f);
        ASSERT_EQ(first.pixels.size(), second.pixels.size());
        EXPECT_TRUE(first.pixels == second.pixels) << "frame " << f << " differs";
    }
    // The statistics CSV has a header and one row per frame.
    std::ifstream csv(a.path() / "frames.csv");
    std::string line;
    int rows = 0;
    std::getline(csv, line);
    EXPECT_EQ(line.rfind("frame,time_s,milliseconds,triangles,", 0), 0u) << line;
    while (std::getline(csv, line)) {
        ++rows;
    }
    EXPECT_EQ(rows, 17);
}

/// The node pools: with a cache that fits one texture array a pool, every frame's terrain in chunks mode is one
/// instanced draw per program (detail layers need two: the nodes beyond the layers' fade get a program without
/// them; PoolArraysGLTest draws with several arrays, TessellationHasNoHolesRunsOfDrawsAndFewerTriangles counts the
/// tessellation mode's runs), the log gives each slot's bytes, and DXT1 colour layers
/// (node_texture_compression) look like the uncompressed ones. The same node count in both, or the budget
/// would hold more of the smaller DXT1 nodes. Without shadows: with them the colour layers carry the sun's
/// visibility in alpha and are never DXT1.
TEST_F(TengineGLTest, NodePoolsDrawOneCallPerProgramAndCompressedTexturesLookTheSame)
{
    test::ScratchDir plain, compressed, detail;
    const std::vector<std::string> settings = {"frames_per_second=2", "quad_cache_size=1024", "render_mode=chunks",
                                               "shadows=false"};
    auto run = video(plain.path(), settings);
    ASSERT_EQ(run.exitCode, 0) << run.output;
    EXPECT_NE(run.output.find("node pools: "), std::string::npos) << run.output;
    std::vector<std::string> on = settings;
    on.push_back("node_texture_compression=on");
    auto runCompressed = video(compressed.path(), on);
    ASSERT_EQ(runCompressed.exitCode, 0) << runCompressed.output;

    // draw_calls per frame from the CSV (its header names the column).
    auto drawCalls = [](const std::filesystem::path& dir) {
        std::ifstream csv(dir / "frames.csv");
        std::string line;
        std::getline(csv, line);
        std::vector<std::string> header;
        for (std::size_t at = 0, next; at <= line.size(); at = next + 1) {
            next = std::min(line.find(',', at), line.size());
            header.push_back(line.substr(at, next - at));
        }
        const auto column = std::find(header.begin(), header.end(), "draw_calls") - header.begin();
        EXPECT_LT(static_cast<std::size_t>(column), header.size()) << line;
        std::vector<int> calls;
        while (std::getline(csv, line)) {
            std::size_t at = 0;
            for (std::ptrdiff_t k = 0; k < column; ++k) {
                at = line.find(',', at) + 1;
            }
            calls.push_back(std::stoi(line.substr(at)));
        }
        return calls;
    };
    // The built-in materials have detail layers: one call, or two where near and far nodes are in view.
    const std::vector<int> calls = drawCalls(plain.path());
    ASSERT_EQ(calls.size(), 17u);
    for (int c : calls) {
        EXPECT_GE(c, 1);
        EXPECT_LE(c, 2);
    }

    double worstMean = 0.0;
    int worst = 0;
    for (int f = 0; f <= 16; ++f) {
        const Image a = frame(plain.path(), f), b = frame(compressed.path(), f);
        ASSERT_EQ(a.pixels.size(), b.pixels.size());
        double sum = 0.0;
        for (std::size_t k = 0; k < a.pixels.size(); ++k) {
            const int d = std::abs(int{a.pixels[k]} - int{b.pixels[k]});
            sum += d;
            worst = std::max(worst, d);
        }
        worstMean = std::max(worstMean, sum / static_cast<double>(a.pixels.size()));
    }
    std::printf("DXT1 against RGB8 colour layers: mean difference at most %.3f, largest %d of 255\n", worstMean, worst);
    EXPECT_GT(worst, 0) << "compression must change something, or the option does nothing";
    EXPECT_LT(worstMean, 2.0);
    EXPECT_LT(worst, 64);

    // Low over the detail map, near and far nodes are both in view: two calls, one per program.
    auto runDetail =
        video(detail.path(),
              lowDetailFlight({"frames_per_second=2", "video_frames=8", "quad_cache_size=1024", "render_mode=chunks"}),
              detailMap());
    ASSERT_EQ(runDetail.exitCode, 0) << runDetail.output;
    const std::vector<int> detailCalls = drawCalls(detail.path());
    ASSERT_FALSE(detailCalls.empty());
    for (int c : detailCalls) {
        EXPECT_EQ(c, 2);
    }
}

TEST_F(TengineGLTest, ACacheLargerThanTheGpuPoolsCanHoldIsAClearError)
{
    test::ScratchDir frames;
    auto run = video(frames.path(), {"video_frames=1", "quad_cache_size=1000000"});
    EXPECT_NE(run.exitCode, 0);
    EXPECT_NE(run.output.find("quad_cache_size 1000000"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("GL_MAX_ARRAY_TEXTURE_LAYERS"), std::string::npos) << run.output;
}

/// No output of tengine may be one of its inputs, the log included: nothing is written, not even the refusal.
TEST_F(TengineGLTest, OutputsNamingAnInputAreRefusedBeforeAnythingIsWritten)
{
    test::ScratchDir dir;
    const std::filesystem::path mapCopy = dir / "terrain.map", config = dir / "view.cfg", path = dir / "flight.path";
    std::filesystem::copy_file(map(), mapCopy);
    std::filesystem::copy_file(flight(), path);
    std::ofstream(config) << "lod_error = 2\n";
    std::filesystem::create_directories(dir / "rec");
    std::ofstream(dir / "rec" / "frames.csv") << "frame,time_s\n0,0\n";
    const std::filesystem::path csv = dir / "rec" / "frames.csv";
    auto bytes = [](const std::filesystem::path& file) {
        std::ifstream in(file, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::string mapBytes = bytes(mapCopy), configBytes = bytes(config), pathBytes = bytes(path),
                      csvBytes = bytes(csv);
    struct Case {
        std::vector<std::string> args;
        std::string says;
    };
    const std::string m = mapCopy.string();
    const Case cases[] = {
        {{m, "--set", "log_file=" + m}, "refusing"},
        {{config.string(), m, "--set", "log_file=" + config.string()}, "refusing"},
        {{m, "--set", "camera_path=" + path.string(), "--set", "log_file=" + path.string()}, "refusing"},
        // A recording's CSV given as an argument is neither a map nor a config: an error, never overwritten.
        {{csv.string(), m, "--set", "camera_path=" + path.string(), "--set", "video_mode=true", "--set",
          "image_path=" + (dir / "rec").string(), "--set", "video_frames=1"},
         "is neither a map"},
    };
    for (const Case& c : cases) {
        auto run = test::runProgram(TERRAIN_TENGINE_EXE, c.args);
        EXPECT_NE(run.exitCode, 0) << c.args.back() << ":\n" << run.output;
        EXPECT_NE(run.output.find(c.says), std::string::npos) << run.output;
        EXPECT_EQ(bytes(mapCopy), mapBytes) << c.args.back();
        EXPECT_EQ(bytes(config), configBytes) << c.args.back();
        EXPECT_EQ(bytes(path), pathBytes) << c.args.back();
        EXPECT_EQ(bytes(csv), csvBytes) << c.args.back();
    }
}

TEST_F(TengineGLTest, MissingMapIsAClearError)
{
    auto run = test::runProgram(TERRAIN_TENGINE_EXE, {"/nonexistent/terrain.map"});
    EXPECT_NE(run.exitCode, 0);
    EXPECT_NE(run.output.find("/nonexistent/terrain.map"), std::string::npos) << run.output;
}

TEST_F(TengineGLTest, NormalMapsFinerThanTheSurfaceBelowAreAClearError)
{
    // 65-sample nodes: normal maps sample at most 2 levels below, 256 cells; 512 is refused by name.
    auto run = video(std::filesystem::path(*sDir / "unused"), {"dynamic_texture_size=512"});
    EXPECT_NE(run.exitCode, 0);
    EXPECT_NE(run.output.find("dynamic_texture_size 512 is more than 4x the 64 cells of"), std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("(at most 256)"), std::string::npos) << run.output;
}

TEST_F(TengineGLTest, BrokenShaderIsAClearError)
{
    // Each render mode's own stage broken in turn.
    for (const auto& [file, mode] : {std::pair{"terrain.vert", "chunks"}, std::pair{"terrain.tese", "tessellation"}}) {
        test::ScratchDir shaders;
        for (const auto& entry : std::filesystem::directory_iterator(TERRAIN_SHADER_DIR)) {
            std::filesystem::copy(entry.path(), shaders / entry.path().filename().string());
        }
        std::ofstream(shaders / file, std::ios::app) << "\nthis is not GLSL;\n";
        test::ScratchDir frames;
        auto run = video(frames.path(), {"video_frames=1", "shader_path=" + shaders.path().string(),
                                         std::string("render_mode=") + mode});
        EXPECT_NE(run.exitCode, 0) << mode;
        EXPECT_NE(run.output.find(file), std::string::npos) << run.output;
        EXPECT_NE(run.output.find("does not compile"), std::string::npos) << run.output;
        EXPECT_TRUE(frames.list().empty()) << "no frames from a run that failed";
    }
}

TEST_F(TengineGLTest, BadConfigIsAnErrorNamingFileAndLine)
{
    test::ScratchDir dir;
    std::ofstream(dir / "bad.cfg") << "# a viewer config\nlod_error = 2\ncamera_fov = 500\n";
    auto run = test::runProgram(TERRAIN_TENGINE_EXE, {(dir / "bad.cfg").string(), map().string()});
    EXPECT_EQ(run.exitCode, 2);
    EXPECT_NE(run.output.find("bad.cfg:3"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("camera_fov"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace terrain

namespace terrain {
namespace {

/// Mean absolute difference of two images, per channel value.
double meanDifference(const Image& a, const Image& b)
{
    double sum = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        sum += std::abs(int(a.pixels[i]) - int(b.pixels[i]));
    }
    return sum / static_cast<double>(a.pixels.size());
}

TEST_F(TengineGLTest, GeomorphingHidesTheSwitchBetweenDetailLevels)
{
    // Find two camera positions 2 m apart between which the selection changes (a node splits), on a
    // descent towards the ridge, with every node resident (as video mode draws them).
    constexpr double kTau = 2.0;
    auto mapFile = MapFile::open(map(), ReaderKind::Stream);
    ASSERT_TRUE(mapFile.ok());
    MapLodTree tree(**mapFile);
    Camera camera;
    camera.viewportWidth = 320;
    camera.viewportHeight = 180;
    camera.yaw = 40 * std::numbers::pi / 180;
    camera.pitch = -25 * std::numbers::pi / 180;
    LodSelection previous, current;
    glm::dvec3 before{}, after{};
    bool found = false;
    for (int step = 0; step < 20000 && !found; ++step) {
        camera.position = {38000 + step * 1.4, 35500 + step * 1.4, 9000 - step * 2.0};
        selectNodes(tree, camera, kTau, {}, current);
        if (step > 0 && current.nodes.size() > previous.nodes.size() + 2) {
            before = {38000 + (step - 1) * 1.4, 35500 + (step - 1) * 1.4, 9000 - (step - 1) * 2.0};
            after = camera.position;
            found = true;
        }
        std::swap(previous, current);
    }
    ASSERT_TRUE(found);
    // Close in on the split: a few centimetres of camera motion either side of it, so that with geomorphing
    // the frames differ by almost nothing while without it the split shows in full.
    const std::size_t coarse = [&] {
        camera.position = before;
        selectNodes(tree, camera, kTau, {}, current);
        return current.nodes.size();
    }();
    for (int halving = 0; halving < 12; ++halving) {
        camera.position = 0.5 * (before + after);
        selectNodes(tree, camera, kTau, {}, current);
        (current.nodes.size() == coarse ? before : after) = camera.position;
    }
    test::ScratchDir dir;
    {
        std::ofstream path(dir / "split.path");
        path.precision(17);
        path << "0 " << before.x << ' ' << before.y << ' ' << before.z << " 40 -25\n"
             << "1 " << after.x << ' ' << after.y << ' ' << after.z << " 40 -25\n";
    }
    auto render = [&](const std::filesystem::path& frames, bool geomorph) {
        auto run = test::runProgram(
            TERRAIN_TENGINE_EXE,
            {map().string(), "--set", "camera_path=" + (dir / "split.path").string(), "--set", "video_mode=true",
             "--set", "video_ffmpeg=false", "--set", "image_path=" + frames.string(), "--set", "window_width=320",
             "--set", "window_height=180", "--set", "frames_per_second=1", "--set", "draw_user_interface=false",
             "--set", std::string("geomorph=") + (geomorph ? "true" : "false"), "--set", "lod_error=2",
             // The split was found in the static tree: no dynamic nodes, whose errors differ. Chunks: the
             // split is the selection's at all of tau (tessellation selects for part of it).
             "--set", "detail_create_new_nodes=false", "--set", "render_mode=chunks"});
        EXPECT_EQ(run.exitCode, 0) << run.output;
        return meanDifference(frame(frames, 0), frame(frames, 1));
    };
    test::ScratchDir morphed, popped;
    const double smooth = render(morphed.path(), true);
    const double pop = render(popped.path(), false);
    // Without morphing the split shows as a visible jump; with it the two frames differ only by the few
    // centimetres the camera moved.
    EXPECT_GT(pop, 4 * smooth) << "morphed " << smooth << ", popping " << pop;
    EXPECT_LT(smooth, 0.5);
    RecordProperty("mean_difference_morphed", std::to_string(smooth));
    RecordProperty("mean_difference_popping", std::to_string(pop));
}

TEST_F(TengineGLTest, DetailFlightHasDynamicNodesAndNoHoles)
{
    // The viewer's hole check over a low flight with detail synthesis: dynamic nodes next to static ones
    // and to each other at many levels, skirts and all, leave no pixel of the clear colour.
    test::ScratchDir frames;
    auto run =
        video(frames.path(),
              lowDetailFlight({"frames_per_second=4", "draw_sky=false", "draw_user_interface=false",
                               "clear_color=1,0,1", "haze_distance=0", "camera_z_far=150000", "worker_threads=2"}),
              detailMap());
    ASSERT_EQ(run.exitCode, 0) << run.output;
    auto mapFile = MapFile::open(detailMap(), ReaderKind::Stream);
    ASSERT_TRUE(mapFile.ok());
    const MapHeader& header = (*mapFile)->header();
    const double zMin = header.heightOf((*mapFile)->directory().front().minCode) - 10.0;  // displacement below
    auto path = CameraPath::load(*sDir / "low.path");
    ASSERT_TRUE(path.ok());
    const auto rows = readCsv(frames.path() / "frames.csv");
    ASSERT_EQ(rows.size(), 13u);
    for (std::size_t f = 0; f < rows.size(); ++f) {
        EXPECT_GT(rows[f].at("nodes_dynamic"), 20) << "frame " << f;
        const Image image = frame(frames.path(), static_cast<int>(f));
        const Holes h = holesIn(image, frameCamera(*path, static_cast<double>(f) / 4.0, image), header, zMin);
        EXPECT_GT(h.checked, image.width * image.height / 2) << "frame " << f;
        EXPECT_EQ(h.holes, 0) << "frame " << f;
    }
}

/// visibility_lod (issue 16) over the pass at the head of demos/trinidad-valley.path (36-48 s of it: the far
/// side hidden behind the pass, then seen from its crest), in both render modes, with detail: no holes in any
/// frame while hidden terrain comes into view, nodes hidden and revealed, and the frames those of the same
/// flight without it, bar a few pixels (no jump the reveal would add to ordinary refinement).
TEST_F(TengineGLTest, CrestingThePassWithVisibilityLodShowsNoHolesAndTheSameFrames)
{
    std::ofstream(*sDir / "crest.path") << "0 64850 53100 2899 -1.0 -2.0\n"
                                           "3 64775 53650 2953 -0.5 -2.0\n"
                                           "6 64700 54200 2961 0.0 -2.0\n"
                                           "9 64633 54667 2960 0.0 -2.0\n"
                                           "12 64567 55133 2924 0.0 -2.0\n";
    const auto materials = detailMaterials();
    auto mapFile = MapFile::open(detailMap(), ReaderKind::Stream);
    ASSERT_TRUE(mapFile.ok());
    const MapHeader& header = (*mapFile)->header();
    const double zMin = header.heightOf((*mapFile)->directory().front().minCode) - 10.0;  // displacement below
    auto path = CameraPath::load(*sDir / "crest.path");
    ASSERT_TRUE(path.ok());
    for (const std::string mode : {"chunks", "tessellation"}) {
        SCOPED_TRACE(mode);
        test::ScratchDir on, off;
        for (const bool visibility : {true, false}) {
            auto run =
                video(visibility ? on.path() : off.path(),
                      {"camera_path=" + (*sDir / "crest.path").string(),
                       "detail_materials=" + materials[0].string() + ", " + materials[1].string(),
                       "frames_per_second=4", "draw_sky=false", "draw_user_interface=false", "clear_color=1,0,1",
                       "haze_distance=0", "camera_z_far=150000", "render_mode=" + mode,
                       std::string("visibility_lod=") + (visibility ? "true" : "false"), "video_measure_error_every=12",
                       "window_width=640", "window_height=360"},  // at 320 x 180 too little is refined to hide
                      detailMap());
            ASSERT_EQ(run.exitCode, 0) << run.output;
        }
        const auto rows = readCsv(on.path() / "frames.csv");
        ASSERT_EQ(rows.size(), 49u);
        double hidden = 0, revealing = 0;
        int measured = 0, holesWithout = 0;
        for (std::size_t f = 0; f < rows.size(); ++f) {
            // The error of what shows, measured by the viewer on frames 0, 12, 24, 36, 48: within tau.
            ASSERT_EQ(rows[f].count("error_max_px"), f % 12 == 0 ? 1u : 0u) << "frame " << f;
            if (f % 12 == 0) {
                ++measured;
                EXPECT_LE(rows[f].at("error_max_px"), 2.0) << "frame " << f;
                EXPECT_GT(rows[f].at("error_max_px"), 0.0) << "frame " << f << ": something is measured";
            }
            hidden += rows[f].at("nodes_hidden");
            revealing += rows[f].at("nodes_revealing");
            const Image image = frame(on.path(), static_cast<int>(f));
            const Image imageWithout = frame(off.path(), static_cast<int>(f));
            const Camera camera = frameCamera(*path, static_cast<double>(f) / 4.0, image);
            const Holes withIt = holesIn(image, camera, header, zMin);
            const Holes without = holesIn(imageWithout, camera, header, zMin);
            EXPECT_GT(withIt.checked, image.width * image.height / 3) << "frame " << f;
            // Tessellation mode leaves a pixel open in frame 0 at 640 x 360 with or without visibility (before
            // any count or depth exists): a crack of its own, not of the reveal. Visibility must add none.
            EXPECT_LE(withIt.holes, without.holes)
                << "frame " << f << ", first at (" << withIt.firstX << ", " << withIt.firstY << ")";
            if (mode == "chunks") {
                EXPECT_EQ(withIt.holes, 0)
                    << "frame " << f << ", first at (" << withIt.firstX << ", " << withIt.firstY << ")";
            }
            holesWithout += without.holes;
            if (f >= 4) {  // after the first second: the counts arrive two frames late, k = 4 dark frames
                auto d = compareImages(image, imageWithout, 8);
                ASSERT_TRUE(d.ok()) << d.error().message;
                EXPECT_GE(static_cast<double>(d->identical), 0.995 * static_cast<double>(d->pixels)) << "frame " << f;
                EXPECT_LE(d->largestRegion, 16u)
                    << "frame " << f << " at " << d->largestRegionX << "," << d->largestRegionY;
            }
        }
        EXPECT_GT(hidden, 0.0) << "terrain behind the pass is hidden";
        EXPECT_GT(revealing, 0.0) << "and comes into view";
        EXPECT_EQ(measured, 5);
        std::printf("%s: %.0f nodes hidden, %.0f revealing over the crest; holes without visibility_lod %d\n",
                    mode.c_str(), hidden, revealing, holesWithout);
    }
}

TEST_F(TengineGLTest, DetailShowsUpCloseAndRunsRepeatIdentically)
{
    // The paper's figure 5.2: the same low view with detail synthesis off, subdivision only and with the
    // materials. Detail changes the near ground; two runs with two workers give the same frames.
    auto render = [&](const std::filesystem::path& frames, std::vector<std::string> settings) {
        settings.push_back("video_frames=1");
        settings.push_back("draw_user_interface=false");
        auto run = video(frames, lowDetailFlight(settings), detailMap());
        EXPECT_EQ(run.exitCode, 0) << run.output;
        return frame(frames, 0);
    };
    test::ScratchDir off, subdivided, full, again;
    const Image plain = render(off.path(), {"detail_create_new_nodes=false"});
    const Image smooth = render(subdivided.path(), {"detail_add_material=false"});
    const Image detailed = render(full.path(), {"worker_threads=2"});
    const Image repeat = render(again.path(), {"worker_threads=2"});
    EXPECT_TRUE(detailed.pixels == repeat.pixels) << "detail frames must not depend on thread timing";
    // Compare the lower half (the near ground).
    auto lowerHalfDifference = [](const Image& a, const Image& b) {
        double sum = 0;
        std::size_t count = 0;
        for (int y = a.height / 2; y < a.height; ++y) {
            for (int x = 0; x < a.width; ++x) {
                for (int c = 0; c < 3; ++c) {
                    sum += std::abs(int(a.pixel(x, y)[c]) - int(b.pixel(x, y)[c]));
                    ++count;
                }
            }
        }
        return sum / static_cast<double>(count);
    };
    const double materialEffect = lowerHalfDifference(detailed, smooth);
    const double subdivisionEffect = lowerHalfDifference(smooth, plain);
    RecordProperty("difference_materials", std::to_string(materialEffect));
    RecordProperty("difference_subdivision", std::to_string(subdivisionEffect));
    EXPECT_GT(materialEffect, 2.0) << "detail textures and displacement must show near the camera";
    EXPECT_GT(subdivisionEffect, 0.2) << "subdivision reshapes the near ground";
}

TEST_F(TengineGLTest, NormalMapsShowShadingDetailFinerThanTheTriangles)
{
    // dynamic_texture_size (issue 14): the same low view lit by normal maps of 32 texels a node (coarser than
    // its 65 samples) and of 256 (the surface two levels below it). The larger maps add shading detail to the
    // near ground: more luminance variation between neighbouring pixels. No holes either way, and the same
    // frames run to run.
    auto render = [&](const std::filesystem::path& frames, int size) {
        auto run =
            video(frames,
                  lowDetailFlight({"video_frames=1", "draw_user_interface=false", "draw_sky=false", "clear_color=1,0,1",
                                   "haze_distance=0", "camera_z_far=150000", "worker_threads=2", "window_width=480",
                                   "window_height=270", "dynamic_texture_size=" + std::to_string(size)}),
                  detailMap());
        EXPECT_EQ(run.exitCode, 0) << run.output;
        return frame(frames, 0);
    };
    test::ScratchDir coarse, fine, again;
    const Image small = render(coarse.path(), 32);
    const Image large = render(fine.path(), 256);
    const Image repeat = render(again.path(), 256);
    ASSERT_EQ(small.width, 480);
    ASSERT_EQ(large.width, 480);
    EXPECT_TRUE(large.pixels == repeat.pixels) << "normal maps must not depend on thread timing";
    // Shading detail: the mean absolute difference of luminance between horizontal and vertical neighbours
    // over the terrain (the clear colour left out).
    auto detail = [](const Image& image) {
        auto luminance = [&](int x, int y) {
            const std::uint8_t* p = image.pixel(x, y);
            return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
        };
        double sum = 0.0;
        std::size_t count = 0;
        for (int y = 0; y + 1 < image.height; ++y) {
            for (int x = 0; x + 1 < image.width; ++x) {
                if (isHole(image.pixel(x, y)) || isHole(image.pixel(x + 1, y)) || isHole(image.pixel(x, y + 1))) {
                    continue;
                }
                sum +=
                    std::abs(luminance(x + 1, y) - luminance(x, y)) + std::abs(luminance(x, y + 1) - luminance(x, y));
                count += 2;
            }
        }
        return sum / static_cast<double>(count);
    };
    const double coarseDetail = detail(small), fineDetail = detail(large);
    RecordProperty("shading_detail_32", std::to_string(coarseDetail));
    RecordProperty("shading_detail_256", std::to_string(fineDetail));
    std::printf("shading detail (mean |luminance step| of the terrain): 32 texels %.3f, 256 texels %.3f\n",
                coarseDetail, fineDetail);
    EXPECT_GT(fineDetail, 1.25 * coarseDetail);  // measured 2.12x
    auto mapFile = MapFile::open(detailMap(), ReaderKind::Stream);
    ASSERT_TRUE(mapFile.ok());
    const MapHeader& header = (*mapFile)->header();
    const double zMin = header.heightOf((*mapFile)->directory().front().minCode) - 10.0;
    auto path = CameraPath::load(*sDir / "low.path");
    ASSERT_TRUE(path.ok());
    for (const Image* image : {&small, &large}) {
        const Holes h = holesIn(*image, frameCamera(*path, 0.0, *image), header, zMin);
        EXPECT_GT(h.checked, image->width * image->height / 2);
        EXPECT_EQ(h.holes, 0);
    }
}

TEST_F(TengineGLTest, CompressedNormalMapsShadeLikeTheUncompressedOnes)
{
    // normal_map_compression: the same low view lit by RGTC2 normal maps (1 byte a texel) and by RG8 ones
    // (2 bytes), 129 texels a node. The frames differ little pixel by pixel and keep their shading detail
    // (the mean luminance step between neighbouring pixels); the log gives the smaller slots.
    auto render = [&](const std::filesystem::path& frames, bool compressed, std::string& log) {
        auto run = video(frames,
                         lowDetailFlight({"video_frames=1", "draw_user_interface=false", "worker_threads=2",
                                          "window_width=480", "window_height=270", "dynamic_texture_size=128",
                                          std::string("normal_map_compression=") + (compressed ? "on" : "off")}),
                         detailMap());
        EXPECT_EQ(run.exitCode, 0) << run.output;
        log = run.output;
        return frame(frames, 0);
    };
    test::ScratchDir plain, compressed;
    std::string plainLog, compressedLog;
    const Image a = render(plain.path(), false, plainLog);
    const Image b = render(compressed.path(), true, compressedLog);
    ASSERT_EQ(a.width, 480);
    ASSERT_EQ(a.pixels.size(), b.pixels.size());
    EXPECT_NE(plainLog.find("normal map 33282"), std::string::npos) << plainLog;            // 129^2 x 2
    EXPECT_NE(compressedLog.find("normal map 17424"), std::string::npos) << compressedLog;  // 132^2 x 1
    double sum = 0.0;
    int worst = 0;
    for (std::size_t k = 0; k < a.pixels.size(); ++k) {
        const int d = std::abs(int{a.pixels[k]} - int{b.pixels[k]});
        sum += d;
        worst = std::max(worst, d);
    }
    const double mean = sum / static_cast<double>(a.pixels.size());
    auto detail = [](const Image& image) {
        auto luminance = [&](int x, int y) {
            const std::uint8_t* p = image.pixel(x, y);
            return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
        };
        double steps = 0.0;
        for (int y = 0; y + 1 < image.height; ++y) {
            for (int x = 0; x + 1 < image.width; ++x) {
                steps +=
                    std::abs(luminance(x + 1, y) - luminance(x, y)) + std::abs(luminance(x, y + 1) - luminance(x, y));
            }
        }
        return steps / (2.0 * (image.width - 1) * (image.height - 1));
    };
    const double detailA = detail(a), detailB = detail(b);
    std::printf("RGTC2 against RG8 normal maps: mean difference %.3f, largest %d of 255; shading detail %.3f / %.3f\n",
                mean, worst, detailB, detailA);
    EXPECT_GT(worst, 0) << "compression must change something, or the option does nothing";
    EXPECT_LT(mean, 0.5);  // measured 0.21, largest 6, detail 1.007x
    EXPECT_LT(worst, 24);
    EXPECT_NEAR(detailB / detailA, 1.0, 0.03);
}

TEST_F(TengineGLTest, ACoarseCopyShowsTheReliefOfTheOriginalUpClose)
{
    // Issue 14: 30 m above a ridge of the bundled terrain decimated 16x (1440 m between samples, one node),
    // the synthesized detail (the terrain's own roughness continued, the materials, the normal maps) shows as
    // much relief as the same view over the 90 m original: the luminance standard deviation of the terrain
    // pixels within 30 % (measured 0.95x). With the materials' absolute amplitudes and no roughness continued
    // (before issue 14) the coarse copy is the smooth subdivided data (0.33x).
    auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    constexpr int kFactor = 16;
    HeightField coarse;
    coarse.width = (field->width - 1) / kFactor + 1;
    coarse.height = (field->height - 1) / kFactor + 1;
    coarse.integerSamples = field->integerSamples;
    for (int j = 0; j < coarse.height; ++j) {
        for (int i = 0; i < coarse.width; ++i) {
            coarse.samples.push_back(field->at(i * kFactor, j * kFactor));
        }
    }
    // The highest sample away from the border, and the way down from it (the lowest of its neighbours two
    // samples away): the camera looks down the ridge's flank.
    int pi = 4, pj = 4;
    for (int j = 4; j < coarse.height - 4; ++j) {
        for (int i = 4; i < coarse.width - 4; ++i) {
            if (coarse.at(i, j) > coarse.at(pi, pj)) {
                pi = i;
                pj = j;
            }
        }
    }
    int di = 0, dj = 1;
    for (int j = -2; j <= 2; j += 2) {
        for (int i = -2; i <= 2; i += 2) {
            if ((i != 0 || j != 0) && coarse.at(pi + i, pj + j) < coarse.at(pi + di, pj + dj)) {
                di = i;
                dj = j;
            }
        }
    }
    const std::filesystem::path coarseMap = *sDir / "trinidad-1440.map";
    auto built = test::buildDetailMap(std::move(coarse), 90.0 * kFactor, coarseMap, detailMaterials());
    ASSERT_TRUE(built.ok()) << built.error().message;
    const double cx = pi * 90.0 * kFactor, cy = pj * 90.0 * kFactor;
    const double yaw = std::atan2(static_cast<double>(di), static_cast<double>(dj)) * 180.0 / std::numbers::pi;
    // Looking down at the flank (50 degrees): the near ground fills the frame, the part that synthesis makes
    // for both maps (below 90 m).
    constexpr double kPitch = -50.0;
    auto view = [&](const std::filesystem::path& mapFile, const std::filesystem::path& frames,
                    std::vector<std::string> more) {
        auto opened = MapFile::open(mapFile, ReaderKind::Stream);
        EXPECT_TRUE(opened.ok());
        auto ground = staticHeightAt(**opened, cx, cy);
        EXPECT_TRUE(ground.ok()) << ground.error().message;
        const std::filesystem::path path = frames.string() + ".path";
        {
            std::ofstream out(path);
            out << "0 " << cx << ' ' << cy << ' ' << ground->height + 30.0 << ' ' << yaw << ' ' << kPitch << "\n"
                << "1 " << cx << ' ' << cy << ' ' << ground->height + 30.0 << ' ' << yaw << ' ' << kPitch << "\n";
        }
        const auto files = detailMaterials();
        std::vector<std::string> settings = {"camera_path=" + path.string(),
                                             "video_frames=1",
                                             "draw_user_interface=false",
                                             "draw_sky=false",
                                             "clear_color=1,0,1",
                                             "haze_distance=0",
                                             "camera_z_far=150000",
                                             "worker_threads=2",
                                             "window_width=480",
                                             "window_height=270",
                                             "detail_materials=" + files[0].string() + ", " + files[1].string()};
        settings.insert(settings.end(), more.begin(), more.end());  // later settings win
        auto run = video(frames, settings, mapFile);
        EXPECT_EQ(run.exitCode, 0) << run.output;
        return frame(frames, 0);
    };
    auto deviation = [](const Image& image) {
        double sum = 0.0, squares = 0.0;
        std::size_t count = 0;
        for (int y = 0; y < image.height; ++y) {
            for (int x = 0; x < image.width; ++x) {
                const std::uint8_t* p = image.pixel(x, y);
                if (isHole(p)) {
                    continue;
                }
                const double l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
                sum += l;
                squares += l * l;
                ++count;
            }
        }
        EXPECT_GT(count, static_cast<std::size_t>(image.width * image.height / 2)) << "mostly terrain";
        const double mean = sum / static_cast<double>(count);
        return std::sqrt(std::max(squares / static_cast<double>(count) - mean * mean, 0.0));
    };
    // Before issue 14: the materials' absolute amplitudes (the shipped files without relative_amplitude) and no
    // roughness continued.
    test::ScratchDir a, b;
    std::vector<std::string> absolute;
    for (const auto& file : detailMaterials()) {
        std::ifstream in(file);
        const std::filesystem::path copy = b.path() / file.filename();
        std::ofstream out(copy);
        for (std::string line; std::getline(in, line);) {
            if (line.rfind("relative_amplitude", 0) == 0) {
                continue;
            }
            if (line.rfind("detail_texture =", 0) == 0) {
                line = "detail_texture = " + (file.parent_path() / line.substr(line.find('=') + 2)).string();
            }
            out << line << '\n';
        }
        absolute.push_back(copy.string());
    }
    const double original = deviation(view(detailMap(), a.path() / "original", {}));
    const double copy = deviation(view(coarseMap, b.path() / "coarse", {}));
    const double smooth =
        deviation(view(coarseMap, b.path() / "smooth",
                       {"detail_roughness=false", "detail_materials=" + absolute[0] + ", " + absolute[1]}));
    std::printf(
        "luminance deviation 30 m above the ridge: 90 m original %.2f, 1440 m copy %.2f (%.2fx), "
        "absolute materials, no roughness %.2f (%.2fx)\n",
        original, copy, copy / original, smooth, smooth / original);
    RecordProperty("luminance_deviation_ratio", std::to_string(copy / original));
    EXPECT_NEAR(copy / original, 1.0, 0.3);
    EXPECT_LT(smooth, 0.6 * copy) << "the roughness continued below the data is what shows the relief";
}

// The ground up close, 25 m above grass looking straight down, shows no tile: the detail textures' share of the
// frame (the frame over the same frame drawn with materials that have no detail textures, so that the relief's
// shading, the node colours and the tints cancel) has no autocorrelation peak above 0.10 at lags from 16 to
// 160 pixels. A texture repeating every 2 m (grass's detail_texture_size, 51 pixels here) would show one there.
TEST_F(TengineGLTest, CloseUpGroundShowsNoRepeatingTile)
{
    constexpr double kX = 30000.0, kY = 30000.0;  // meadow on the bundled terrain's western plain
    auto opened = MapFile::open(detailMap(), ReaderKind::Stream);
    ASSERT_TRUE(opened.ok());
    auto ground = staticHeightAt(**opened, kX, kY);
    ASSERT_TRUE(ground.ok()) << ground.error().message;
    test::ScratchDir dir;
    {
        std::ofstream path(dir / "down.path");
        path << "0 " << kX << ' ' << kY << ' ' << ground->height + 25.0 << " 0 -89.9\n"
             << "1 " << kX << ' ' << kY << ' ' << ground->height + 25.0 << " 0 -89.9\n";
    }
    constexpr int kWidth = 1024, kHeight = 512;
    const std::vector<double> share = centredDetailShare(detailMap(), dir / "down.path", dir.path(), kWidth, kHeight);
    ASSERT_EQ(share.size(), static_cast<std::size_t>(kWidth) * kHeight);
    const test::AutocorrelationPeak peak = test::autocorrelationPeak(share, kWidth, kHeight, 16, 160);
    std::printf("close-up detail: autocorrelation peak %.3f at lag (%d, %d) pixels\n", peak.value, peak.dx, peak.dy);
    EXPECT_LE(peak.value, 0.10);
}

// Detail on a cliff is not stretched down its face: a 70 degree face seen level from 20 m in front of its middle
// shows the detail layers' share of the frame (detailShare) with the same correlation length down the face as
// across it, within 40%. Projected from above, as on the plains, the layers would stretch down the face by
// tan(70 degrees), 2.7x: a metre of the texture covers that many metres of height (the test fails so).
TEST_F(TengineGLTest, CliffDetailIsNotStretchedDownTheFace)
{
    constexpr double kFoot = 100.0, kTop = 120.0;
    const double rise = std::tan(70.0 * std::numbers::pi / 180.0);
    HeightField field;
    field.width = field.height = 257;
    field.integerSamples = false;
    for (int j = 0; j < field.height; ++j) {
        for (int i = 0; i < field.width; ++i) {
            field.samples.push_back(static_cast<float>(std::clamp((i - kFoot) * rise, 0.0, kTop)));
        }
    }
    test::ScratchDir dir;
    const std::filesystem::path mapFile = dir / "cliff.map";
    ASSERT_TRUE(test::buildDetailMap(std::move(field), 1.0, mapFile, detailMaterials()).ok());
    {
        const double faceX = kFoot + 0.5 * kTop / rise;
        std::ofstream path(dir / "cliff.path");
        for (int k = 0; k < 2; ++k) {
            path << k << ' ' << faceX - 20.0 << " 128 " << 0.5 * kTop << " 90 0\n";
        }
    }
    constexpr int kSize = 512;
    std::vector<double> share =
        centredDetailShare(mapFile, dir / "cliff.path", dir.path(), kSize, kSize, {"sun_azimuth=250"});
    ASSERT_EQ(share.size(), static_cast<std::size_t>(kSize) * kSize);
    double mean = 0.0;
    for (double v : share) {
        mean += v / static_cast<double>(share.size());
    }
    for (double& v : share) {
        v -= mean;
    }
    // The normalised autocorrelation at a lag of (dx, dy) pixels, and the lag along an axis where it falls to 1/2.
    auto correlation = [&](int dx, int dy) {
        double products = 0.0, squares = 0.0;
        for (int y = 0; y + dy < kSize; ++y) {
            for (int x = 0; x + dx < kSize; ++x) {
                const double a = share[static_cast<std::size_t>(y) * kSize + static_cast<std::size_t>(x)];
                products += a * share[static_cast<std::size_t>(y + dy) * kSize + static_cast<std::size_t>(x + dx)];
                squares += a * a;
            }
        }
        return products / squares;
    };
    auto halfLength = [&](int ax, int ay) {
        double previous = 1.0;
        for (int d = 1; d <= 128; ++d) {
            const double r = correlation(ax * d, ay * d);
            if (r < 0.5) {
                return d - 1 + (previous - 0.5) / (previous - r);
            }
            previous = r;
        }
        return 128.0;
    };
    const double across = halfLength(1, 0), down = halfLength(0, 1);
    std::printf("cliff detail: correlation falls to 1/2 at %.2f pixels across the face, %.2f down it (%.2fx)\n", across,
                down, down / across);
    EXPECT_GT(across, 1.0) << "detail to measure";
    EXPECT_NEAR(down / across, 1.0, 0.4);
}

// Aerial perspective on distant relief: four walls facing the viewer 2.5, 5, 20 and 60 km east of it, painted in
// light and dark stripes (at least 4 of the map's texels and 2 degrees wide), the sun low behind the viewer so that
// the air scatters alike on both sides of the view. Two surfaces at one distance differ by their own difference
// times the air's transmittance (the in-scattered light adds to both), so the contrast between the stripes,
// taken back through the tone map to radiance, falls with distance as the model's transmittance does: within
// 10 % of it at 5, 20 and 60 km, relative to the nearest wall, in green, and in blue (which the air dims most;
// a gray haze would not) at 5 and 20 km.
TEST_F(TengineGLTest, DistantRidgesLoseContrastAsTheAirsTransmittance)
{
    constexpr double kSpacing = 100.0, kViewerX = 200.0, kAltitude = 500.0, kBand = 12000.0;
    const std::array<double, 4> distances = {2500.0, 5000.0, 20000.0, 60000.0};
    const std::array<double, 4> stripes = {400.0, 400.0, 800.0, 2000.0};  // metres, 4 texels or more
    HeightField field;
    field.width = 650;
    field.height = static_cast<int>(distances.size() * kBand / kSpacing);
    field.integerSamples = true;
    Image paint{field.width, field.height, 3,
                std::vector<std::uint8_t>(static_cast<std::size_t>(field.width) * field.height * 3)};
    for (int j = 0; j < field.height; ++j) {
        const double y = j * kSpacing;
        const auto band = static_cast<std::size_t>(y / kBand);
        const double face = kViewerX + distances[band];
        const bool light = static_cast<long>(std::floor(y / stripes[band])) % 2 == 0;
        for (int i = 0; i < field.width; ++i) {
            field.samples.push_back(i * kSpacing >= face ? 1500.0f : 0.0f);
            // Image rows run north to south.
            std::uint8_t* p = paint.pixel(i, field.height - 1 - j);
            p[0] = p[1] = p[2] = light ? 200 : 60;
        }
    }
    // The stripes as the map's colours (not colours by height, which a wall's face would take as a mix of the
    // plain's and the plateau's that changes with the level drawn).
    test::ScratchDir dir;
    ASSERT_TRUE(writePngImage(dir / "paint.png", paint).ok());
    const std::filesystem::path mapFile = *sDir / "walls.map";
    ASSERT_TRUE(test::buildDetailMap(std::move(field), kSpacing, mapFile, {}, dir / "paint.png").ok());
    {
        // One key a second, looking east at each wall's middle from 500 m.
        std::ofstream path(dir / "walls.path");
        for (std::size_t k = 0; k < distances.size(); ++k) {
            path << k << ' ' << kViewerX << ' ' << (static_cast<double>(k) + 0.5) * kBand << ' ' << kAltitude
                 << " 90 0\n";
        }
    }
    constexpr double kExposure = 2.0;
    const test::RunResult run = test::runProgram(TERRAIN_TENGINE_EXE, {mapFile.string(),
                                                                       "--set",
                                                                       "camera_path=" + (dir / "walls.path").string(),
                                                                       "--set",
                                                                       "video_mode=true",
                                                                       "--set",
                                                                       "video_ffmpeg=false",
                                                                       "--set",
                                                                       "video_frames=4",
                                                                       "--set",
                                                                       "frames_per_second=1",
                                                                       "--set",
                                                                       "draw_user_interface=false",
                                                                       "--set",
                                                                       "atmosphere=true",
                                                                       "--set",
                                                                       "exposure=" + std::to_string(kExposure),
                                                                       "--set",
                                                                       "sun_azimuth=270",
                                                                       "--set",
                                                                       "sun_elevation=15",
                                                                       "--set",
                                                                       "image_path=" + (dir / "frames").string()});
    ASSERT_EQ(run.exitCode, 0) << run.output;
    // A channel of a frame back through the display gamma and the tone map (Narkowicz's fit, inverted).
    auto radiance = [](std::uint8_t value) {
        const double m = (value / 255.0) * (value / 255.0);
        const double a = 2.51 - 2.43 * m, b = 0.03 - 0.59 * m, c = -0.14 * m;
        return (-b + std::sqrt(b * b - 4.0 * a * c)) / (2.0 * a) / kExposure;
    };
    const AtmosphereModel air;
    std::vector<Image> images;
    for (std::size_t k = 0; k < distances.size(); ++k) {
        images.push_back(frame(dir / "frames", static_cast<int>(k)));
        ASSERT_EQ(images.back().width, 1280);
    }
    // Green, and blue, which the air dims most: a gray haze would not.
    for (int channel : {1, 2}) {
        std::array<double, 4> contrast{}, expected{};
        for (std::size_t k = 0; k < distances.size(); ++k) {
            const Image& image = images[k];
            // The middle rows where they meet the wall: half the band's angular width each way, at most the frame.
            const double halfWidth = std::atan(0.4 * kBand / distances[k]);
            const double pixelsPerRadian = (image.height / 2.0) / std::tan(30.0 * std::numbers::pi / 180.0);
            const int reach = std::min(600, static_cast<int>(pixelsPerRadian * std::tan(halfWidth)));
            std::vector<double> values;
            for (int y = image.height / 2 - 3; y <= image.height / 2 + 3; ++y) {
                for (int x = image.width / 2 - reach; x <= image.width / 2 + reach; ++x) {
                    values.push_back(radiance(image.pixel(x, y)[channel]));
                }
            }
            std::sort(values.begin(), values.end());
            const std::size_t quarter = values.size() / 4;
            double low = 0.0, high = 0.0;
            for (std::size_t i = 0; i < quarter; ++i) {
                low += values[i] / static_cast<double>(quarter);
                high += values[values.size() - 1 - i] / static_cast<double>(quarter);
            }
            contrast[k] = high - low;
            expected[k] = transmittance(air, kAltitude, 0.0, distances[k])[channel];
        }
        for (std::size_t k = 1; k < distances.size(); ++k) {
            const double measured = contrast[k] / contrast[0], model = expected[k] / expected[0];
            std::printf(
                "%s, wall at %5.0f m: contrast %.4f, %.3f of the nearest wall's; the model's transmittance "
                "%.3f of it\n",
                channel == 1 ? "green" : "blue", distances[k], contrast[k], measured, model);
            // Blue at 60 km keeps 14 % of its contrast, 0.008 in radiance: a few steps of the frame's 8 bits there,
            // so it is printed, not held.
            if (channel == 1 || distances[k] < 50000.0) {
                EXPECT_NEAR(measured, model, 0.1 * model) << distances[k] << " m, channel " << channel;
            }
        }
    }
}

}  // namespace
}  // namespace terrain
