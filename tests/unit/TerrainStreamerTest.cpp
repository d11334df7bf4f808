// The runtime core end to end on a real map: selector + cache + server + static node source.
#include "MapTestSupport.h"

#include "lod/CameraPath.h"
#include "lod/TerrainNodeSource.h"
#include "lod/TerrainStreamer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

namespace terrain {
namespace {

class TerrainStreamerTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        BuildOptions options;
        options.chunkSize = 17;
        options.spacing = 10.0;
        auto report = buildMap(test::hillyField(513, 513), options, mDir / "hills.map");
        ASSERT_TRUE(report.ok()) << report.error().message;
        auto map = MapFile::open(mDir / "hills.map", ReaderKind::Stream);
        ASSERT_TRUE(map.ok()) << map.error().message;
        mMap = std::move(map.value());
    }

    /// A low flight across the map and back, looking ahead and a little down.
    CameraPath flight() const
    {
        auto path = CameraPath::parse(
            "0 200 300 1450 45 -10\n"
            "20 2500 2400 1500 80 -12\n"
            "40 4800 3000 1500 -30 -10\n"
            "60 1000 4700 1600 -150 -20\n",
            "flight.path");
        EXPECT_TRUE(path.ok()) << path.error().message;
        return path.value();
    }

    test::ScratchDir mDir;
    std::unique_ptr<MapFile> mMap;
};

TEST_F(TerrainStreamerTest, CacheNeverExceedsItsCapacityAndEverythingDrawnIsResident)
{
    TerrainNodeSource source(*mMap, {});
    StreamerOptions options;
    options.cacheSize = 45;
    options.workers = 0;  // inline: deterministic
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok()) << streamer.error().message;
    const CameraPath path = flight();
    Camera camera;
    std::size_t peak = 0, evictionsSeen = 0;
    for (int frame = 0; frame <= 600; ++frame) {
        path.evaluate(frame * 0.1).applyTo(camera);
        (*streamer)->update(camera, 2.0);
        (*streamer)->drain();
        peak = std::max(peak, (*streamer)->cache().size());
        ASSERT_LE((*streamer)->cache().size(), options.cacheSize) << "frame " << frame;
        for (const auto& selected : (*streamer)->selection().nodes) {
            NodePtr node = (*streamer)->node(selected.id);
            ASSERT_TRUE(node) << "frame " << frame << ": selected node " << selected.id.toString() << " not resident";
            ASSERT_EQ(node->id, selected.id);
        }
        evictionsSeen = (*streamer)->cache().evictions();
    }
    EXPECT_GT(evictionsSeen, 0u) << "the flight should need more nodes than the cache holds";
    EXPECT_GT(peak, options.cacheSize - 8);
}

TEST_F(TerrainStreamerTest, ACacheTooSmallRefinesWhereTheErrorIsLargestAndCountsWhatIsLeftOut)
{
    // A cache far smaller than the flight's wanted set: each frame the groups asked for are those whose parents
    // have the largest screen-space error (delta_c over distance) of all the selection wanted, and the rest
    // are counted as deferred (frames.csv's cache_short).
    TerrainNodeSource source(*mMap, {});
    StreamerOptions options;
    options.cacheSize = 21;
    options.queueLimit = 64;  // the server takes whatever the cache has room for
    options.workers = 0;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok()) << streamer.error().message;
    const CameraPath path = flight();
    Camera camera;
    int shortFrames = 0;
    for (int frame = 0; frame <= 60; ++frame) {
        path.evaluate(frame * 1.0).applyTo(camera);
        const FrameStats stats = (*streamer)->update(camera, 2.0);
        const std::vector<ChildRequest> wanted = (*streamer)->selection().requests;
        ASSERT_EQ(stats.requested, wanted.size());
        (*streamer)->drain();
        if (stats.deferred == 0) {
            continue;
        }
        ++shortFrames;
        double leastTaken = INFINITY, mostLeft = 0.0;
        std::size_t taken = 0;
        for (const ChildRequest& request : wanted) {
            const double error = (*streamer)->node(request.parent)->deltaC / std::max(request.distance, 1e-3);
            if ((*streamer)->childrenResident(request.parent)) {
                ++taken;
                leastTaken = std::min(leastTaken, error);
            } else {
                mostLeft = std::max(mostLeft, error);
            }
        }
        EXPECT_EQ(taken + stats.deferred, wanted.size()) << "frame " << frame;
        EXPECT_GE(leastTaken, mostLeft) << "frame " << frame << ": a group of smaller error was refined first";
    }
    EXPECT_GT(shortFrames, 10) << "the cache must be short on this flight for the test to mean anything";
}

TEST_F(TerrainStreamerTest, ConvergesToTheSelectionWithEverythingResident)
{
    TerrainNodeSource source(*mMap, {});
    StreamerOptions options;
    options.cacheSize = mMap->directory().size();
    options.workers = 2;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok());
    Camera camera;
    flight().evaluate(25.0).applyTo(camera);
    for (int round = 0; round < 32; ++round) {
        if ((*streamer)->update(camera, 2.0).requested == 0) {
            break;
        }
        (*streamer)->drain();
    }
    LodSelection reference;
    selectNodes((*streamer)->tree(), camera, 2.0, {}, reference);  // every node resident
    ASSERT_EQ((*streamer)->selection().nodes.size(), reference.nodes.size());
    for (std::size_t i = 0; i < reference.nodes.size(); ++i) {
        EXPECT_EQ((*streamer)->selection().nodes[i].id, reference.nodes[i].id);
    }
    // Loaded data equals what the map decodes along the path from the root.
    for (const auto& selected : reference.nodes) {
        auto direct = mMap->loadPath(selected.id);
        ASSERT_TRUE(direct.ok());
        EXPECT_EQ((*streamer)->node(selected.id)->codes, direct->heights) << selected.id.toString();
    }
}

TEST_F(TerrainStreamerTest, ACorruptNodeIsReportedOnceAndItsParentKeepsBeingDrawn)
{
    // Corrupt one level-2 node's payload: its whole sibling group fails to load.
    const DirectoryEntry* victim = mMap->find({2, 1, 1});
    ASSERT_NE(victim, nullptr);
    const auto offset = victim->offset + victim->heightBytes / 2;
    mMap.reset();
    ASSERT_TRUE(test::flipBits(mDir / "hills.map", offset, 0x5a));
    auto map = MapFile::open(mDir / "hills.map", ReaderKind::MemoryMapped);
    ASSERT_TRUE(map.ok());
    TerrainNodeSource source(**map, {});
    StreamerOptions options;
    options.cacheSize = (*map)->directory().size();
    options.workers = 1;
    auto streamer = TerrainStreamer::create(source, extentOf((*map)->header()), options);
    ASSERT_TRUE(streamer.ok());
    std::vector<std::string> reports;
    (*streamer)->onLoadError([&](const std::string& message) { reports.push_back(message); });
    // Look straight down at the corrupt node's parent from close by.
    Camera camera;
    const double size = (*map)->header().nodeSizeAt(2);
    camera.position = {1.5 * size, 1.5 * size, 1600};  // above the centre of node 2/1/1
    camera.pitch = -std::numbers::pi / 2 + 0.01;
    for (int frame = 0; frame < 10; ++frame) {
        (*streamer)->update(camera, 1.0);
        (*streamer)->drain();
    }
    ASSERT_EQ(reports.size(), 1u);
    EXPECT_NE(reports.front().find("node 2/1/1"), std::string::npos) << reports.front();
    bool parentDrawn = false;
    for (const auto& selected : (*streamer)->selection().nodes) {
        parentDrawn = parentDrawn || selected.id == NodeId{1, 0, 0};
        EXPECT_NE(selected.id.level >= 2 ? selected.id.parent() : NodeId{}, (NodeId{1, 0, 0}))
            << "a child of the failed group was drawn";
    }
    EXPECT_TRUE(parentDrawn);
}

TEST_F(TerrainStreamerTest, MinimumSpacingStopsRefinement)
{
    // lod_minimum_spacing as the viewer applies it (DetailPolicy::minimumSpacing of the node source): 10 m
    // samples at the finest level, so a 20 m minimum keeps every node at 20 m or coarser, one level short of
    // the leaves the same view reaches without it.
    Camera camera;
    camera.position = {2560, 2560, 1100};
    camera.pitch = -1.2;
    auto deepestSettled = [&](double minimumSpacing) {
        TerrainNodeSource source(*mMap, {nullptr, minimumSpacing});
        StreamerOptions options;
        options.cacheSize = mMap->directory().size();
        options.workers = 0;  // inline: deterministic
        auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
        EXPECT_TRUE(streamer.ok()) << streamer.error().message;
        (*streamer)->settle(Settle::Complete, camera, 0.5);
        EXPECT_EQ((*streamer)->update(camera, 0.5).requested, 0u) << "the selection should have settled";
        int deepest = 0;
        for (const auto& node : (*streamer)->selection().nodes) {
            deepest = std::max(deepest, node.id.level);
            EXPECT_GE(mMap->header().spacingAt(node.id.level), minimumSpacing) << node.id.toString();
        }
        return deepest;
    };
    const int deepestFull = deepestSettled(0.0);
    EXPECT_EQ(deepestFull, static_cast<int>(mMap->header().levels) - 1)
        << "without the limit the view reaches the leaves";
    EXPECT_EQ(deepestSettled(20.0), deepestFull - 1);
    // A minimum between two levels' spacings keeps the coarser one: 15 m allows 20 m nodes, not 10 m ones.
    EXPECT_EQ(deepestSettled(15.0), deepestFull - 1);
    // A minimum of exactly a level's spacing still allows that level.
    EXPECT_EQ(deepestSettled(10.0), deepestFull);
}

/// Whether `id` lies strictly below `ancestor`.
bool isBelow(NodeId id, const NodeId& ancestor)
{
    while (id.level > ancestor.level) {
        id = id.parent();
        if (id == ancestor) {
            return true;
        }
    }
    return false;
}

TEST_F(TerrainStreamerTest, AHiddenNodeIsNotRefinedAndItsReturnMorphsInALevelAtATime)
{
    TerrainNodeSource source(*mMap, {});
    StreamerOptions options;
    options.cacheSize = mMap->directory().size();
    options.workers = 0;
    options.revealSeconds = 0.1;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok());
    TerrainStreamer& s = **streamer;
    Camera camera;
    flight().evaluate(25.0).applyTo(camera);
    double time = 0.0;
    const double step = 1.0 / 30.0;
    // As video mode does: load what the frame wants, select again.
    auto frame = [&](const NodeHidden& hidden) {
        const FrameStats stats = s.settle(Settle::Complete, camera, 2.0, 0.0, {hidden, time});
        time += step;
        return stats;
    };
    frame({});
    const LodSelection full = s.selection();
    // The ancestor two levels above the deepest node drawn: hidden, its subtree collapses to it.
    const auto deepest = std::max_element(full.nodes.begin(), full.nodes.end(),
                                          [](const auto& a, const auto& b) { return a.id.level < b.id.level; });
    ASSERT_GE(deepest->id.level, 3);
    const NodeId hiddenId = deepest->id.parent().parent();
    std::size_t below = 0;
    for (const auto& n : full.nodes) {
        below += isBelow(n.id, hiddenId) ? 1 : 0;
    }
    ASSERT_GT(below, 4u);
    const NodeHidden hidden = [&](const NodeId& id) { return id == hiddenId; };
    for (int f = 0; f < 5; ++f) {
        const FrameStats stats = frame(hidden);
        EXPECT_EQ(stats.hidden, 1u);
        EXPECT_EQ(stats.requestsSkippedHidden, 0u) << "its children are resident";
        const auto& nodes = s.selection().nodes;
        EXPECT_TRUE(std::any_of(nodes.begin(), nodes.end(), [&](const auto& n) { return n.id == hiddenId; }));
        for (const auto& n : nodes) {
            EXPECT_FALSE(isBelow(n.id, hiddenId)) << n.id.toString() << " drawn below the hidden node";
        }
        EXPECT_EQ(nodes.size(), full.nodes.size() - below + 1);
    }
    // Revealed: the children come in at their parent's surface (morph 0), held there (not refined), morphing
    // to their own detail over revealSeconds; then the next level does the same; then all is as before.
    const double revealed = time;
    std::set<int> levelsMorphedIn;
    int framesToFull = -1;
    for (int f = 0; f < 60; ++f) {
        const double now = time;
        const FrameStats stats = frame({});
        const auto& nodes = s.selection().nodes;
        for (const auto& n : nodes) {
            if (!isBelow(n.id, hiddenId)) {
                continue;
            }
            // A level every revealSeconds: level l below the hidden node first drawn at ramp * (l - 1).
            const int depth = n.id.level - hiddenId.level;
            const double since = now - revealed - options.revealSeconds * (depth - 1);
            ASSERT_GE(since, -1e-9) << n.id.toString() << " drawn before its parent finished morphing in";
            const float bound = static_cast<float>(since / options.revealSeconds);
            const auto reference =
                std::find_if(full.nodes.begin(), full.nodes.end(), [&](const auto& r) { return r.id == n.id; });
            const float target = reference == full.nodes.end() ? 1.0f : reference->morph;
            EXPECT_LE(n.morph, std::max(bound, 0.0f) + 1e-4f) << n.id.toString() << " frame " << f;
            EXPECT_NEAR(n.morph, std::min(std::max(bound, 0.0f), target), 1e-4f) << n.id.toString() << " frame " << f;
            if (since < 1e-9) {
                levelsMorphedIn.insert(n.id.level);
            }
        }
        if (stats.revealing == 0 && nodes.size() == full.nodes.size()) {
            framesToFull = f;
            break;
        }
    }
    EXPECT_GE(levelsMorphedIn.size(), 2u) << "each level came in at morph 0";
    ASSERT_GE(framesToFull, 0) << "full detail again within 2 s";
    const int levels = deepest->id.level - hiddenId.level;
    EXPECT_LE(framesToFull, static_cast<int>(std::ceil(levels * options.revealSeconds / step)) + 1);
    for (std::size_t i = 0; i < full.nodes.size(); ++i) {
        EXPECT_EQ(s.selection().nodes[i].id, full.nodes[i].id);
        EXPECT_FLOAT_EQ(s.selection().nodes[i].morph, full.nodes[i].morph);
    }
}

TEST_F(TerrainStreamerTest, AHiddenNodeRequestsNothingAndBadRevealTimesAreRefused)
{
    TerrainNodeSource source(*mMap, {});
    StreamerOptions options;
    options.workers = 0;
    auto streamer = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_TRUE(streamer.ok());
    Camera camera;
    flight().evaluate(25.0).applyTo(camera);
    const FrameStats stats = (*streamer)->update(camera, 2.0, 0.0, {[](const NodeId& id) { return id.isRoot(); }, 0.0});
    EXPECT_EQ(stats.hidden, 1u);
    EXPECT_EQ(stats.requestsSkippedHidden, 1u);
    EXPECT_EQ(stats.requested, 0u);
    ASSERT_EQ((*streamer)->selection().nodes.size(), 1u);
    EXPECT_TRUE((*streamer)->selection().nodes[0].id.isRoot());
    EXPECT_EQ((*streamer)->update(camera, 2.0, 0.0, {{}, 0.1}).requested, 1u) << "visible again: it asks";

    options.revealSeconds = 0.0;
    auto refused = TerrainStreamer::create(source, extentOf(mMap->header()), options);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.error().message.find("visibility_reveal_seconds"), std::string::npos);
}

}  // namespace
}  // namespace terrain
