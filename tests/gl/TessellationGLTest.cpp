// The tessellation render mode (issue 13) on the GL itself: transform feedback reads back every triangle the
// tessellator made for a frame of the bundled terrain, and each is checked against the pure model the error
// meter measures (lod/TessellationLevels.h): the same vertices at the same heights (as the pools quantize them), cells
// split along one or the other diagonal only, snapped sides, blocks that meet sharing their vertices bit for bit (no
// crack inside a node; and the frame shows no clear colour where the terrain must be), skirts hanging from the drawn
// border. The triangle count the renderer reports is what the GL made.
#include "GlTestSupport.h"
#include "TestSupport.h"

#include "core/Camera.h"
#include "gpudata/BlockTriangles.h"
#include "gpudata/TemplateMesh.h"
#include "lod/NodeTextures.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"
#include "lod/TessellationLevels.h"
#include "quadtree/ChunkGeometry.h"
#include "quadtree/MapFile.h"
#include "render/FrameCapture.h"
#include "render/GlWindow.h"
#include "render/TerrainRenderer.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <numbers>
#include <set>

namespace terrain {
namespace {

using Triangle = std::array<std::pair<int, int>, 3>;

Triangle sorted(glm::ivec2 a, glm::ivec2 b, glm::ivec2 c)
{
    Triangle t{std::pair{a.x, a.y}, std::pair{b.x, b.y}, std::pair{c.x, c.y}};
    std::sort(t.begin(), t.end());
    return t;
}

long doubleArea(const Triangle& t)
{
    return std::labs(static_cast<long>(t[1].first - t[0].first) * (t[2].second - t[0].second) -
                     static_cast<long>(t[1].second - t[0].second) * (t[2].first - t[0].first));
}

/// A frame of the bundled terrain low over a valley, looking along it (near blocks fine, far ones coarse, sides
/// snapped between them), drawn by a tessellation mode renderer (`blockIndices`: render_mode = blocks) with its
/// triangles read back.
struct ValleyFrame {
    std::unique_ptr<test::DemoScene> scene;
    std::unique_ptr<TerrainNodeSource> source;
    std::unique_ptr<TerrainStreamer> streamer;
    Camera camera;
    static constexpr double kBlockPixels = 1.0;
    RenderStats stats;
    std::vector<glm::vec3> feedback;
    int holes = 0, mustHit = 0;  ///< pixels of the clear colour where the terrain must be, of those checked

    const MapHeader& header() const { return scene->map->header(); }
    /// The heights of `node` as the pools hold them (16-bit codes over the node's range), blended at `morph` as the
    /// shaders blend: at sample (i, j).
    static std::function<double(int, int)> drawnHeights(const NodeData& node, int n, float morph)
    {
        std::vector<float> surface(node.heights.base.size());
        node.heights.surface(surface);
        auto quantized = std::make_shared<QuantizedHeights>(quantizeHeightsR16(surface, n));
        return [quantized, n, morph](int i, int j) {
            auto h = [&](int a, int c) -> double {
                return quantized->lo +
                       quantized->range *
                           (quantized->codes[static_cast<std::size_t>(c + 1) * (n + 2) + a + 1] / 65535.0);
            };
            const int dx = i & 1, dy = j & 1;
            return morph * h(i, j) + (1.0 - morph) * 0.5 * (h(i - dx, j - dy) + h(i + dx, j + dy));
        };
    }
};

void drawValleyFrame(ValleyFrame& f, bool blockIndices)
{
    auto scene = test::openDemoScene(640, 360);
    ASSERT_TRUE(scene.ok()) << scene.error().message;
    f.scene = std::move(scene).value();
    ASSERT_TRUE(TerrainRenderer::tessellationSupported()) << f.scene->window->description();
    ASSERT_TRUE(!blockIndices || TerrainRenderer::multiDrawIndirectSupported()) << f.scene->window->description();
    MapFile& map = *f.scene->map;
    const MapHeader& header = map.header();
    f.source = std::make_unique<TerrainNodeSource>(map, DetailPolicy{nullptr, 0.0, kTessellationBlockQuads});
    StreamerOptions streamerOptions;
    streamerOptions.cacheSize = 2048;
    streamerOptions.workers = 2;
    auto streamer = TerrainStreamer::create(*f.source, extentOf(header), streamerOptions);
    ASSERT_TRUE(streamer.ok());
    f.streamer = std::move(streamer).value();
    PoolOptions pools{2048, false, true};
    pools.blockIndices = blockIndices;
    auto renderer = TerrainRenderer::create(TERRAIN_SHADER_DIR, header, 16, pools);
    ASSERT_TRUE(renderer.ok()) << renderer.error().message;

    Camera& camera = f.camera;
    camera.viewportWidth = 640;
    camera.viewportHeight = 360;
    camera.nearPlane = 1.0;
    camera.farPlane = 150000.0;
    camera.position = {15000.0, 12000.0, 2496.0};
    camera.yaw = 47.7 * std::numbers::pi / 180;
    camera.pitch = -8.0 * std::numbers::pi / 180;
    const double nodePixels = 1.0;
    f.streamer->settle(Settle::Complete, camera, nodePixels);
    ASSERT_GT(f.streamer->selection().nodes.size(), 20u);
    // The hole check's style: no sky, the clear colour where nothing is drawn.
    SceneStyle style;
    style.drawSky = false;
    style.clearColour = {1.0f, 0.0f, 1.0f};
    style.hazeDistance = 1e9f;
    f.stats = (*renderer)->draw(makeDrawList(f.streamer->selection(), *f.streamer, camera, ValleyFrame::kBlockPixels),
                                style, &f.feedback);
    // No crack inside a node where blocks of different levels meet, nor between nodes: no pixel whose view ray
    // must hit the terrain shows the clear colour.
    glFinish();
    const Image image = captureFrame(camera.viewportWidth, camera.viewportHeight);
    const double zMin = header.heightOf(map.directory().front().minCode);
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x) {
            if (test::mustHitTerrain(camera, header, zMin, x, y)) {
                ++f.mustHit;
                f.holes += test::isHole(image.pixel(x, y)) ? 1 : 0;
            }
        }
    }
}

/// Camera-relative corner `v` of a triangle of node `selected` (N samples a side) -> its node sample, checked to be
/// one.
glm::ivec2 sampleOf(const glm::vec3& v, const SelectedNode& selected, int n)
{
    const double spacing = selected.size / (n - 1);
    const double x = (v.x - selected.cameraRelativeOrigin.x) / spacing;
    const double y = (v.y - selected.cameraRelativeOrigin.y) / spacing;
    const glm::ivec2 p{static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y))};
    EXPECT_NEAR(x, p.x, 1e-3) << selected.id.toString();
    EXPECT_NEAR(y, p.y, 1e-3) << selected.id.toString();
    return p;
}

TEST(TessellationGLTest, GeneratedTrianglesAreTheModelsAndBlocksShareTheirVerticesBitForBit)
{
    ValleyFrame frame;
    drawValleyFrame(frame, false);
    if (HasFatalFailure()) {
        return;
    }
    const Camera& camera = frame.camera;
    const MapHeader& header = frame.header();
    const int n = static_cast<int>(header.chunkSize);
    const double blockPixels = ValleyFrame::kBlockPixels;
    const TerrainStreamer& s = *frame.streamer;
    const LodSelection& selection = s.selection();
    const RenderStats& stats = frame.stats;
    const std::vector<glm::vec3>& feedback = frame.feedback;
    EXPECT_EQ(frame.holes, 0) << "pixels of the clear colour where the terrain must be";
    EXPECT_GT(frame.mustHit, 640 * 360 / 4);
    EXPECT_EQ(stats.generatedTriangles, stats.triangles) << "the renderer's count is what the GL made";
    ASSERT_EQ(feedback.size(), 3 * stats.triangles);

    const QuadtreeExtent extent = extentOf(header);
    const int q = kTessellationBlockQuads, b = (n - 1) / q;
    const double heightBase = header.heightOffset - camera.position.z;
    std::size_t at = 0, shared = 0, snappedSides = 0, skirtTops = 0, checkedVertices = 0;
    std::set<int> levelsSeen;
    for (const SelectedNode& selected : selection.nodes) {
        const NodePtr node = s.node(selected.id);
        ASSERT_TRUE(node && node->tessellation);
        const BlockLevels levels = chooseBlockLevels(
            *node->tessellation, extent.box(selected.id, node->zMin, node->zMax), camera, blockPixels);
        const auto height = ValleyFrame::drawnHeights(*node, n, selected.id.isRoot() ? 1.0f : selected.morph);
        auto sample = [&](const glm::vec3& v) { return sampleOf(v, selected, n); };
        std::map<std::pair<int, int>, glm::vec3> surfaceVertex;  // first seen, per sample
        std::map<std::pair<int, int>, int> blockOf;
        for (int patch = 0; patch < b * b + 4 * b; ++patch) {
            const bool skirt = patch >= b * b;
            const int side = skirt ? (patch - b * b) / b : -1, k = skirt ? (patch - b * b) % b : 0;
            const int bx = !skirt ? patch % b : side == kEast ? b - 1 : side == kWest ? 0 : k;
            const int by = !skirt ? patch / b : side == kNorth ? b - 1 : side == kSouth ? 0 : k;
            const auto block = static_cast<std::size_t>(by * b + bx);
            if (levels.culled[block]) {
                continue;
            }
            const int t = levels.level[block], f = q >> t;
            const std::uint64_t count = skirt ? skirtPatchTriangles(f) : 2ull * f * f;
            ASSERT_LE(at + 3 * count, feedback.size());
            if (!skirt) {
                levelsSeen.insert(t);
                const int snap[4] = {levels.snap[4 * block], levels.snap[4 * block + 1], levels.snap[4 * block + 2],
                                     levels.snap[4 * block + 3]};
                for (int e : snap) {
                    snappedSides += e > t ? 1 : 0;
                }
                // The model's triangles: every cell under either diagonal.
                std::set<Triangle> candidates;
                for (int c = 0; c < f; ++c) {
                    for (int a = 0; a < f; ++a) {
                        const glm::ivec2 v00 = tessellatedVertex(q, bx, by, t, a, c, snap);
                        const glm::ivec2 v10 = tessellatedVertex(q, bx, by, t, a + 1, c, snap);
                        const glm::ivec2 v11 = tessellatedVertex(q, bx, by, t, a + 1, c + 1, snap);
                        const glm::ivec2 v01 = tessellatedVertex(q, bx, by, t, a, c + 1, snap);
                        for (const Triangle& tri : {sorted(v00, v10, v11), sorted(v00, v11, v01), sorted(v00, v10, v01),
                                                    sorted(v10, v11, v01)}) {
                            candidates.insert(tri);
                        }
                    }
                }
                long area = 0;
                for (std::uint64_t m = 0; m < count; ++m) {
                    glm::ivec2 p[3];
                    for (int c = 0; c < 3; ++c) {
                        const glm::vec3& v = feedback[at + 3 * m + static_cast<std::size_t>(c)];
                        p[c] = sample(v);
                        EXPECT_NEAR(v.z, heightBase + height(p[c].x, p[c].y),
                                    2e-3 * std::max(1.0, std::abs(double{v.z})));
                        ++checkedVertices;
                        const std::pair key{p[c].x, p[c].y};
                        auto [it, inserted] = surfaceVertex.try_emplace(key, v);
                        if (!inserted) {
                            EXPECT_TRUE(it->second == v) << selected.id.toString() << " sample " << p[c].x << ","
                                                         << p[c].y << ": a vertex made twice differs";
                            shared += blockOf[key] != patch ? 1 : 0;
                        } else {
                            blockOf[key] = patch;
                        }
                    }
                    const Triangle tri = sorted(p[0], p[1], p[2]);
                    if (doubleArea(tri) == 0) {
                        continue;  // a cell collapsed by snapping: dropped by the rasterizer
                    }
                    EXPECT_TRUE(candidates.count(tri)) << selected.id.toString() << " block " << bx << "," << by
                                                       << ": a triangle the model does not make";
                    area += doubleArea(tri);
                }
                EXPECT_EQ(area, 2l * q * q) << "the block's triangles cover it once";
            } else {
                for (std::uint64_t m = 0; m < 3 * count; ++m) {
                    const glm::vec3& v = feedback[at + m];
                    const glm::ivec2 p = sample(v);
                    const bool onBorder = side == kSouth   ? p.y == 0
                                          : side == kNorth ? p.y == n - 1
                                          : side == kEast  ? p.x == n - 1
                                                           : p.x == 0;
                    EXPECT_TRUE(onBorder) << selected.id.toString() << " skirt " << side;
                    // The top of the skirt is the drawn border vertex itself.
                    auto it = surfaceVertex.find({p.x, p.y});
                    if (it != surfaceVertex.end() && it->second == v) {
                        ++skirtTops;
                    } else {
                        EXPECT_LT(v.z, heightBase + height(p.x, p.y) + 1e-3) << "skirts hang below the border";
                    }
                }
            }
            at += 3 * count;
        }
    }
    EXPECT_EQ(at, feedback.size());
    std::printf(
        "%zu triangles, %zu vertices checked, %zu made twice by neighbouring blocks, %zu snapped sides, "
        "%zu skirt tops, levels seen %zu\n",
        feedback.size() / 3, checkedVertices, shared, snappedSides, skirtTops, levelsSeen.size());
    EXPECT_GT(shared, 1000u);
    EXPECT_GT(snappedSides, 50u) << "the frame must have blocks of different levels side by side";
    EXPECT_GE(levelsSeen.size(), 3u);
    EXPECT_GT(skirtTops, 1000u);
}

/// render_mode = blocks: the GL draws each node's BlockTriangles lists (tested on their own against the error
/// meter's surface) with that node's constants: every triangle read back is the list's, at the drawn heights, in
/// the list's order node by node; the frame has no hole.
TEST(TessellationGLTest, BlockIndicesDrawEachNodesListsWithItsConstants)
{
    ValleyFrame frame;
    drawValleyFrame(frame, true);
    if (HasFatalFailure()) {
        return;
    }
    const MapHeader& header = frame.header();
    const int n = static_cast<int>(header.chunkSize);
    const TerrainStreamer& s = *frame.streamer;
    EXPECT_EQ(frame.holes, 0) << "pixels of the clear colour where the terrain must be";
    EXPECT_GT(frame.mustHit, 640 * 360 / 4);
    EXPECT_EQ(frame.stats.generatedTriangles, frame.stats.triangles) << "the renderer's count is what the GL made";
    ASSERT_EQ(frame.feedback.size(), 3 * frame.stats.triangles);
    EXPECT_EQ(frame.stats.drawCalls, 1u) << "one multi-draw for the frame's one group";

    const TemplateMesh mesh = buildTemplateMesh(n);
    const BlockTriangles lists(n, kTessellationBlockQuads);
    const QuadtreeExtent extent = extentOf(header);
    const double heightBase = header.heightOffset - frame.camera.position.z;
    std::size_t at = 0, skirtVertices = 0;
    std::uint64_t fewer = 0;  // than the tessellator makes for the same blocks
    for (const SelectedNode& selected : s.selection().nodes) {
        const NodePtr node = s.node(selected.id);
        ASSERT_TRUE(node && node->tessellation);
        const BlockLevels levels =
            chooseBlockLevels(*node->tessellation, extent.box(selected.id, node->zMin, node->zMax), frame.camera,
                              ValleyFrame::kBlockPixels);
        std::vector<std::uint32_t> indices;
        lists.append(levels, indices);
        fewer += levels.triangles() - indices.size() / 3;
        const auto height = ValleyFrame::drawnHeights(*node, n, selected.id.isRoot() ? 1.0f : selected.morph);
        ASSERT_LE(at + indices.size(), frame.feedback.size()) << selected.id.toString();
        for (const std::uint32_t index : indices) {
            const glm::vec3& v = frame.feedback[at++];
            const TemplateVertex& expected = mesh.vertices[index];
            const glm::ivec2 p = sampleOf(v, selected, n);
            ASSERT_EQ(p, glm::ivec2(expected.i, expected.j)) << selected.id.toString() << ": another vertex";
            if (expected.skirt) {
                ++skirtVertices;
                EXPECT_LT(v.z, heightBase + height(p.x, p.y)) << "skirts hang below the border";
            } else {
                EXPECT_NEAR(v.z, heightBase + height(p.x, p.y), 2e-3 * std::max(1.0, std::abs(double{v.z})));
            }
        }
    }
    EXPECT_EQ(at, frame.feedback.size());
    EXPECT_GT(skirtVertices, 1000u);
    std::printf("%zu triangles, %llu fewer than the tessellator makes for the same blocks\n", at / 3,
                static_cast<unsigned long long>(fewer));
    EXPECT_GT(fewer, 0u) << "collapsed cells and the skirts' extra rows are left out";
}

}  // namespace
}  // namespace terrain
