// The viewer's session without GL: opened from the viewer's options, advanced frame by frame; a settled frame is
// the fixed point an independent loop of select-and-load reaches, the same whatever the threads, and the viewer
// and the error tool hold the same cache.
#include "MapTestSupport.h"

#include "apps/ViewerSession.h"
#include "lod/CameraPath.h"
#include "lod/HeightQuery.h"
#include "lod/NodeMemory.h"
#include "lod/TessellationLevels.h"

#include <array>
#include <set>

#include <gtest/gtest.h>

#include <vector>

namespace terrain {
namespace {

class ViewerSessionTest : public ::testing::Test {
protected:
    static void SetUpTestSuite()
    {
        sDir = new test::ScratchDir();
        BuildOptions options;
        options.chunkSize = 17;
        options.spacing = 10.0;
        auto report = buildMap(test::hillyField(257, 257), options, *sDir / "hills.map");
        ASSERT_TRUE(report.ok()) << report.error().message;
        // The same hills with the leaves' detail errors: the viewer refines them into dynamic nodes.
        ASSERT_TRUE(test::detailErrorMap(test::hillyField(257, 257), 10.0, *test::grassAndRockSynthesizer(17),
                                         *sDir / "detail.map"));
    }
    static void TearDownTestSuite()
    {
        delete sDir;
        sDir = nullptr;
    }

    /// The viewer's defaults on the test map: static detail, a small cache, one worker.
    static TengineOptions options()
    {
        TengineOptions o;
        o.mapFile = *sDir / "hills.map";
        o.detailCreateNewNodes = false;
        o.quadCacheSize = 400;
        o.dynamicTextureSize = 0;
        o.lodError = 1.0;
        return o;
    }

    std::unique_ptr<ViewerSession> open(const TengineOptions& o, SessionUse use = SessionUse::View)
    {
        auto session =
            ViewerSession::open(o, TERRAIN_MATERIALS_DIR, use, [this](const std::string& m) { said.push_back(m); });
        EXPECT_TRUE(session.ok()) << session.error().message;
        if (!session.ok()) {
            return nullptr;
        }
        auto started = (*session)->startStreaming(GlCapabilities{});
        EXPECT_TRUE(started.ok()) << started.error().message;
        return std::move(session).value();
    }

    static Camera lowCamera(double x, double y, double height, double yawDegrees)
    {
        Camera camera;
        camera.position = {x, y, height};
        camera.yaw = yawDegrees * kRadiansPerDegree;
        camera.pitch = -0.3;
        camera.farPlane = 100000;
        return camera;
    }

    static std::vector<std::uint64_t> keys(const LodSelection& selection)
    {
        std::vector<std::uint64_t> k;
        for (const SelectedNode& node : selection.nodes) {
            k.push_back(node.id.key());
        }
        return k;
    }

    static test::ScratchDir* sDir;
    std::vector<std::string> said;
};

test::ScratchDir* ViewerSessionTest::sDir = nullptr;

TEST_F(ViewerSessionTest, ASettledFrameIsWhatSelectingAndLoadingUntilNothingChangesReaches)
{
    TengineOptions o = options();
    auto session = open(o);
    ASSERT_TRUE(session);
    // The reference: a streamer of its own loading inline, selecting again until the selection stops changing.
    TerrainNodeSource source(session->map(), {});
    StreamerOptions streamerOptions;
    streamerOptions.cacheSize = session->cache().nodes;
    streamerOptions.workers = 0;
    auto reference = TerrainStreamer::create(source, extentOf(session->header()), streamerOptions);
    ASSERT_TRUE(reference.ok());
    for (const Camera& camera :
         {lowCamera(300, 400, 900, 45), lowCamera(2000, 1200, 700, 200), lowCamera(1200, 2400, 3000, 150)}) {
        const FrameStats stats = session->advance(camera, 0.0, 0.0, Settle::Complete);
        EXPECT_EQ(stats.requested, stats.deferred) << "a settled frame wants nothing it could load";
        std::vector<std::uint64_t> previous;
        for (int round = 0; round < 100; ++round) {
            (*reference)->update(camera, session->nodePixels());
            (*reference)->drain();
            if (keys((*reference)->selection()) == previous) {
                break;
            }
            previous = keys((*reference)->selection());
        }
        EXPECT_EQ(keys(session->drawnSelection()), previous);
        EXPECT_GT(previous.size(), 4u) << camera.position.x << ", " << camera.position.y;
    }
}

TEST_F(ViewerSessionTest, SettledFramesAreTheSameWhateverTheWorkersAndArrivedFramesComeLater)
{
    auto path = CameraPath::parse("0 300 300 1200 45 -10\n10 2300 2200 800 80 -20\n", "flight.path");
    ASSERT_TRUE(path.ok());
    TengineOptions inline0 = options(), threaded = options();
    inline0.workerThreads = 0;
    threaded.workerThreads = 2;
    auto a = open(inline0), b = open(threaded), realTime = open(threaded);
    ASSERT_TRUE(a && b && realTime);
    std::size_t framesBehind = 0;
    for (int frame = 0; frame <= 40; ++frame) {
        Camera camera;
        camera.farPlane = 100000;
        const double t = frame * 0.25;
        path->evaluate(t).applyTo(camera);
        a->advance(camera, t, 0.0, Settle::Complete);
        b->advance(camera, t, 0.0, Settle::Complete);
        realTime->advance(camera, t, 0.0, Settle::Arrived);
        ASSERT_EQ(keys(a->drawnSelection()), keys(b->drawnSelection())) << "frame " << frame;
        framesBehind += keys(realTime->drawnSelection()) != keys(a->drawnSelection()) ? 1 : 0;
    }
    EXPECT_GT(framesBehind, 0u) << "real time draws what has arrived, not all that is wanted";
}

TEST_F(ViewerSessionTest, TheDrawListIsTheDrawnSelectionWithItsNodesCacheSlotsAndBlockLevels)
{
    for (const bool geomorph : {true, false}) {
        TengineOptions o = options();
        o.tessellation = true;
        o.geomorph = geomorph;
        auto session = open(o);
        ASSERT_TRUE(session);
        const QuadtreeExtent extent = extentOf(session->header());
        for (const Camera& camera : {lowCamera(300, 400, 900, 45), lowCamera(2000, 1200, 700, 200)}) {
            session->advance(camera, 0.0, 0.0, Settle::Complete);
            const DrawList& list = session->drawList();
            const LodSelection& selection = session->drawnSelection();
            ASSERT_EQ(list.nodes.size(), selection.nodes.size());
            EXPECT_EQ(list.blockPixels, session->blockPixels());
            std::set<int> slots;
            std::uint64_t triangles = 0;
            for (std::size_t i = 0; i < list.nodes.size(); ++i) {
                const DrawnNode& drawn = list.nodes[i];
                const SelectedNode& selected = selection.nodes[i];
                ASSERT_EQ(drawn.selected.id, selected.id) << "the selection's order";
                EXPECT_EQ(drawn.selected.morph, geomorph ? selected.morph : 1.0f);
                EXPECT_EQ(drawn.node, session->node(selected.id));
                EXPECT_EQ(drawn.slot, session->streamer().cache().slotOf(selected.id));
                EXPECT_TRUE(slots.insert(drawn.slot).second) << "two drawn nodes share slot " << drawn.slot;
                EXPECT_LT(static_cast<std::size_t>(drawn.slot), session->cache().nodes);
                if (!selected.id.isRoot()) {
                    EXPECT_EQ(drawn.parent, session->node(selected.id.parent()));
                    EXPECT_EQ(drawn.parentSlot, session->streamer().cache().slotOf(selected.id.parent()));
                }
                // Nothing is hidden without visibility_lod: the blocks' own levels for the blocks' budget.
                const NodeData& node = *drawn.node;
                const BlockLevels reference = chooseBlockLevels(
                    *node.tessellation, extent.box(selected.id, node.zMin, node.zMax), camera, session->blockPixels());
                EXPECT_EQ(drawn.levels.level, reference.level) << selected.id.toString();
                EXPECT_EQ(drawn.levels.snap, reference.snap) << selected.id.toString();
                EXPECT_EQ(drawn.levels.culled, reference.culled) << selected.id.toString();
                triangles += reference.triangles();
            }
            EXPECT_EQ(list.blockTriangles, triangles);
            EXPECT_GT(list.nodes.size(), 4u);
        }
    }
}

/// Pixel counts as a renderer gives them, some frames late: every node of each list drawn is counted, those whose
/// south-west corner lies east of `darkEastOf` dark, the others 100 pixels.
class FakeCounts : public PixelCountSource {
public:
    explicit FakeCounts(double darkEastOf) : mDarkEastOf(darkEastOf) {}
    /// The frame `list` draws.
    void drew(const DrawList& list)
    {
        PixelCounts counts;
        counts.frame = ++mFrame;
        counts.camera = list.camera;
        for (const DrawnNode& drawn : list.nodes) {
            counts.nodes.push_back(drawn.selected.id);
            const double east = list.camera.position.x + drawn.selected.cameraRelativeOrigin.x;
            counts.pixels.push_back(east >= mDarkEastOf ? 0u : 100u);
        }
        mPending.push_back(std::move(counts));
    }
    bool takePixelCounts(PixelCounts& out) override
    {
        if (mPending.empty()) {
            return false;
        }
        out = std::move(mPending.front());
        mPending.erase(mPending.begin());
        return true;
    }

private:
    double mDarkEastOf;
    std::uint64_t mFrame = 0;
    std::vector<PixelCounts> mPending;
};

TEST_F(ViewerSessionTest, PixelCountsFromWhatDrewTheFramesHideNodesAndDrawTheirBlocksCoarsest)
{
    TengineOptions o = options();
    o.tessellation = true;
    o.visibilityLod = true;
    o.visibilityHiddenFrames = 2;
    auto session = ViewerSession::open(o, TERRAIN_MATERIALS_DIR, SessionUse::View, [](const std::string&) {});
    ASSERT_TRUE(session.ok()) << session.error().message;
    GlCapabilities gl;
    gl.pixelCounts = true;
    ASSERT_TRUE((*session)->startStreaming(gl).ok());
    ASSERT_TRUE((*session)->countsPixels());
    const Camera camera = lowCamera(300, 1200, 900, 90);  // looking east over the hills
    constexpr double kDarkEastOf = 1600.0;
    FakeCounts counts(kDarkEastOf);
    std::size_t before = 0;
    for (int frame = 0; frame < 8; ++frame) {
        (*session)->advance(camera, frame * 0.1, 0.0, Settle::Complete, &counts);
        if (frame == 0) {
            before = (*session)->drawList().nodes.size();
        }
        counts.drew((*session)->drawList());
    }
    const DrawList& list = (*session)->drawList();
    std::size_t hidden = 0;
    for (const DrawnNode& drawn : list.nodes) {
        if (!drawn.selected.hidden) {
            continue;
        }
        ++hidden;
        const double east = camera.position.x + drawn.selected.cameraRelativeOrigin.x;
        EXPECT_GE(east, kDarkEastOf) << drawn.selected.id.toString() << " showed pixels yet is hidden";
        for (std::uint8_t level : drawn.levels.level) {
            EXPECT_EQ(1 << level, kTessellationBlockQuads) << "a hidden node's blocks are drawn at their coarsest";
        }
    }
    EXPECT_GT(hidden, 0u) << "nodes dark for " << o.visibilityHiddenFrames << " counted frames are hidden";
    EXPECT_LT(list.nodes.size(), before) << "hidden nodes are not refined";
    std::size_t occluded = 0;
    for (const DrawnNode& drawn : list.nodes) {
        occluded += static_cast<std::size_t>(drawn.levels.occludedBlocks);
    }
    EXPECT_EQ(list.occludedBlocks, occluded);
}

TEST_F(ViewerSessionTest, TheViewerAndTheErrorToolHoldTheSameCacheAndSplitTauAlike)
{
    TengineOptions o = options();
    o.quadCacheSize = 0;
    o.memoryBudget = 64;
    o.tessellation = true;
    o.tessellationShare = 0.25;
    auto view = open(o, SessionUse::View), measure = open(o, SessionUse::Measure);
    ASSERT_TRUE(view && measure);
    EXPECT_EQ(view->cache().nodes, measure->cache().nodes);
    EXPECT_EQ(view->cache().description, measure->cache().description);
    EXPECT_TRUE(view->tessellation());
    EXPECT_DOUBLE_EQ(view->nodePixels(), measure->nodePixels());
    EXPECT_DOUBLE_EQ(view->nodePixels() + view->blockPixels(), o.lodError);
    EXPECT_DOUBLE_EQ(view->blockPixels(), 0.25 * o.lodError);
    EXPECT_EQ(view->meter(), nullptr) << "the viewer measures only with video_measure_error_every";
    ASSERT_NE(measure->meter(), nullptr);
    const Camera camera = lowCamera(1300, 1300, 900, 10);
    view->advance(camera, 0.0, 0.0, Settle::Complete);
    measure->advance(camera, 0.0, 0.0, Settle::Complete);
    EXPECT_EQ(keys(view->drawnSelection()), keys(measure->drawnSelection()));
    auto error = measure->measureDrawn(camera);
    ASSERT_TRUE(error.ok()) << error.error().message;
    EXPECT_GT(error->points, 0u);
    EXPECT_LE(error->maxPixels, o.lodError * 1.5);
}

TEST_F(ViewerSessionTest, AMemoryBudgetHoldsTheViewersNodesWhateverTheirLevels)
{
    // Dynamic nodes with textures, normal maps and horizons under a small memory_budget: every resident node the
    // frames draw is charged at least the CPU bytes it holds (the charge of its level stands for them, for the
    // error tool too), the cache's charges stay within what the budget leaves after the GPU's slots, and the
    // bytes, not the slots, bound the cache.
    TengineOptions o = options();
    o.mapFile = *sDir / "detail.map";
    o.detailCreateNewNodes = true;
    o.dynamicTextureSize = 64;  // the most the test map's 17-sample nodes take
    o.shadows = true;
    o.quadCacheSize = 0;
    o.memoryBudget = 24;
    auto session = open(o);
    ASSERT_TRUE(session);
    const NodeCache& cache = session->streamer().cache();
    ASSERT_LT(session->cache().cpuBytes, SIZE_MAX);
    std::size_t checked = 0, dynamic = 0;
    bool bytesBound = false;
    for (const auto& [x, y, yaw] : {std::array{300.0, 400.0, 45.0}, std::array{2000.0, 1200.0, 200.0},
                                    std::array{1200.0, 2400.0, 150.0}, std::array{2400.0, 600.0, 300.0}}) {
        const auto ground = staticHeightAt(session->map(), x, y);
        ASSERT_TRUE(ground.ok()) << ground.error().message;
        session->advance(lowCamera(x, y, ground->height + 15.0, yaw), 0.0, 0.0, Settle::Complete);
        for (const SelectedNode& selected : session->drawnSelection().nodes) {
            const NodePtr node = session->streamer().node(selected.id);
            ASSERT_TRUE(node);
            EXPECT_LE(residentBytes(*node), cache.chargeOf(*node)) << selected.id.toString();
            dynamic += node->isStatic ? 0 : 1;
            ++checked;
        }
        EXPECT_LE(cache.bytes(), session->cache().cpuBytes);
        bytesBound =
            bytesBound || (static_cast<double>(cache.bytes()) > 0.9 * static_cast<double>(session->cache().cpuBytes) &&
                           cache.size() + 4 <= cache.capacity());
    }
    EXPECT_GT(dynamic, 0u) << "the cameras are low enough for synthesized nodes";
    EXPECT_GT(checked, 40u);
    EXPECT_TRUE(bytesBound) << "the bytes run out with slots free: the slots are sized for the deepest level's "
                               "nodes, and the static levels' horizons hold more";
}

TEST_F(ViewerSessionTest, WithoutTessellationInTheGlTheSelectionGetsAllOfTauAndTheViewerIsTold)
{
    TengineOptions o = options();
    o.tessellation = true;
    o.blockIndices = false;
    auto session = ViewerSession::open(o, TERRAIN_MATERIALS_DIR, SessionUse::View,
                                       [this](const std::string& m) { said.push_back(m); });
    ASSERT_TRUE(session.ok());
    GlCapabilities gl;
    gl.tessellation = false;
    ASSERT_TRUE((*session)->startStreaming(gl).ok());
    EXPECT_FALSE((*session)->tessellation());
    EXPECT_DOUBLE_EQ((*session)->nodePixels(), o.lodError);
    EXPECT_DOUBLE_EQ((*session)->blockPixels(), 0.0);
    ASSERT_EQ(said.size(), 1u);
    EXPECT_NE(said[0].find("render_mode = tessellation needs OpenGL 4.0"), std::string::npos) << said[0];
}

/// render_mode = blocks needs indirect draws (OpenGL 4.3), not tessellation shaders: without them the blocks are
/// tessellated, and without those too the selection gets all of tau; one line says which.
TEST_F(ViewerSessionTest, WithoutIndirectDrawsBlocksAreTessellatedOrChunksDrawn)
{
    for (const bool tessellation : {true, false}) {
        for (const bool indirect : {true, false}) {
            said.clear();
            TengineOptions o = options();
            o.tessellation = true;
            o.blockIndices = true;
            auto session = ViewerSession::open(o, TERRAIN_MATERIALS_DIR, SessionUse::View,
                                               [this](const std::string& m) { said.push_back(m); });
            ASSERT_TRUE(session.ok());
            GlCapabilities gl;
            gl.tessellation = tessellation;
            gl.multiDrawIndirect = indirect;
            ASSERT_TRUE((*session)->startStreaming(gl).ok());
            EXPECT_EQ((*session)->blockIndices(), indirect);
            EXPECT_EQ((*session)->tessellation(), indirect || tessellation);
            EXPECT_DOUBLE_EQ((*session)->nodePixels(), indirect || tessellation ? 0.5 * o.lodError : o.lodError);
            if (indirect) {
                EXPECT_TRUE(said.empty());
                continue;
            }
            ASSERT_EQ(said.size(), 1u);
            EXPECT_NE(said[0].find("render_mode = blocks needs OpenGL 4.3"), std::string::npos) << said[0];
            EXPECT_NE(said[0].find(tessellation ? "drawing the blocks by tessellation shaders" : "drawing chunks"),
                      std::string::npos)
                << said[0];
        }
    }
}

TEST_F(ViewerSessionTest, TheDrawnSurfaceIsTheMapsWhereTheFinestStaticLevelIsDrawn)
{
    TengineOptions o = options();
    o.lodError = 0.25;
    o.geomorph = false;  // nodes at their own detail: the drawn surface is exactly the finest level's
    auto session = open(o);
    ASSERT_TRUE(session);
    const Camera camera = lowCamera(1280, 1000, 0, 0);
    Camera above = camera;
    above.position.z = staticHeightAt(session->map(), 1280, 1000)->height + 30.0;
    session->advance(above, 0.0, 0.0, Settle::Complete);
    for (double dy : {20.0, 35.5, 51.25}) {
        const auto drawn = session->drawnHeightAt(1280 + dy * 0.3, 1000 + dy);
        const auto stored = staticHeightAt(session->map(), 1280 + dy * 0.3, 1000 + dy);
        ASSERT_TRUE(drawn && stored.ok());
        EXPECT_NEAR(*drawn, stored->height, 1e-3) << "at " << dy << " m ahead";
    }
    EXPECT_FALSE(session->drawnHeightAt(-5000, -5000).has_value());
}

TEST_F(ViewerSessionTest, ClipmapFramesSettleTheirRingsAndTheFirstRingFollowsTheGround)
{
    TengineOptions o = options();
    o.clipmap = true;
    o.clipmapSamples = 31;
    auto session = open(o);
    ASSERT_TRUE(session);
    ASSERT_NE(session->clipmap(), nullptr);
    const double ground = staticHeightAt(session->map(), 1300, 1300)->height;
    int firstRingHigh = 0;
    for (double height : {5000.0, 10.0}) {
        const Camera camera = lowCamera(1300, 1300, ground + height, 0);
        const FrameStats stats = session->advance(camera, 0.0, 0.0, Settle::Complete);
        EXPECT_EQ(stats.requested, stats.deferred) << "at " << height << " m";
        const int firstRing = session->clipmapFirstRing();
        const FrameStats again = session->advance(camera, 0.0, 0.0, Settle::Arrived);
        EXPECT_EQ(again.requested, 0u) << "at " << height << " m: the rings drawn have their data";
        EXPECT_EQ(session->clipmapFirstRing(), firstRing) << "at " << height << " m";
        if (height > 1000.0) {
            firstRingHigh = session->clipmapFirstRing();
        } else {
            EXPECT_LT(session->clipmapFirstRing(), firstRingHigh) << "near the ground the finer rings are drawn";
        }
    }
}

TEST_F(ViewerSessionTest, BadMapsAndSettingsAreErrorsThatNameThem)
{
    TengineOptions o = options();
    o.mapFile = *sDir / "missing.map";
    auto missing = ViewerSession::open(o, TERRAIN_MATERIALS_DIR, SessionUse::View, [](const std::string&) {});
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.error().message.find("missing.map"), std::string::npos) << missing.error().message;
    o = options();
    o.dynamicTextureSize = 129;  // 16 cells a node: at most 64 normal-map cells
    auto tooFine = ViewerSession::open(o, TERRAIN_MATERIALS_DIR, SessionUse::View, [](const std::string&) {});
    ASSERT_FALSE(tooFine.ok());
    EXPECT_NE(tooFine.error().message.find("dynamic_texture_size 129"), std::string::npos) << tooFine.error().message;
}

}  // namespace
}  // namespace terrain
