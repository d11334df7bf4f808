#include "lod/NodeServer.h"

#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <mutex>
#include <set>

namespace terrain {
namespace {

/// Synthetic children; fails for chosen parents; records the order of loads.
class FakeSource final : public NodeSource {
public:
    std::set<std::uint64_t> failing;
    std::vector<NodeId> order;

    Expected<NodePtr> loadRoot() override { return node(NodeId::root()); }
    Expected<ChildNodes> loadChildren(const NodeData& parent) override
    {
        {
            std::lock_guard lock(mMutex);
            order.push_back(parent.id);
        }
        if (failing.count(parent.id.key())) {
            return makeError("test.map: node ", parent.id.toString(), ": checksum mismatch");
        }
        ChildNodes children;
        for (int q = 0; q < 4; ++q) {
            children[static_cast<std::size_t>(q)] = node(parent.id.child(q));
        }
        return children;
    }
    static NodePtr node(const NodeId& id)
    {
        auto n = std::make_shared<NodeData>();
        n->id = id;
        n->hasChildren = true;
        n->codes.assign(69 * 69, static_cast<std::uint16_t>(id.key()));
        return n;
    }

private:
    std::mutex mMutex;
};

std::vector<LoadRequest> requests(std::initializer_list<std::pair<NodeId, double>> list)
{
    std::vector<LoadRequest> out;
    for (const auto& [id, distance] : list) {
        out.push_back({FakeSource::node(id), distance});
    }
    return out;
}

const NodeId kA = NodeId::root().child(0), kB = NodeId::root().child(1), kC = NodeId::root().child(2),
             kD = NodeId::root().child(3);

TEST(NodeServerTest, InlineLoadsNearestFirst)
{
    FakeSource source;
    NodeServer server(source, {0, 8});
    server.submit(requests({{kA, 30}, {kB, 10}, {kC, 20}}));
    EXPECT_TRUE(server.takeCompleted().empty()) << "inline mode loads only in drain()";
    server.drain();
    EXPECT_EQ(source.order, (std::vector<NodeId>{kB, kC, kA}));
    auto done = server.takeCompleted();
    ASSERT_EQ(done.size(), 3u);
    for (const auto& group : done) {
        ASSERT_TRUE(group.children.ok());
        for (int q = 0; q < 4; ++q) {
            EXPECT_EQ((*group.children)[static_cast<std::size_t>(q)]->id, group.parent.child(q));
        }
    }
}

TEST(NodeServerTest, QueueIsBoundedAndKeepsTheNearest)
{
    FakeSource source;
    NodeServer server(source, {0, 2});
    server.submit(requests({{kA, 40}, {kB, 10}, {kC, 30}, {kD, 20}}));
    auto stats = server.stats();
    EXPECT_EQ(stats.queued, 2u);
    EXPECT_EQ(stats.rejected, 2u);
    EXPECT_EQ(stats.peakPending, 2u);
    server.drain();
    EXPECT_EQ(source.order, (std::vector<NodeId>{kB, kD}));
    // The remaining two fit now; the peak stays the most pending at once, not the total.
    server.submit(requests({{kA, 40}, {kC, 30}}));
    server.drain();
    EXPECT_EQ(server.stats().requested, 4u);
    EXPECT_EQ(server.stats().peakPending, 2u);
}

TEST(NodeServerTest, StaleRequestsAreCancelled)
{
    FakeSource source;
    NodeServer server(source, {0, 8});
    server.submit(requests({{kA, 10}, {kB, 20}}));
    server.submit(requests({{kB, 20}, {kC, 5}}));  // the camera moved: A is no longer wanted
    server.drain();
    EXPECT_EQ(source.order, (std::vector<NodeId>{kC, kB}));
    EXPECT_EQ(server.stats().cancelled, 1u);
}

TEST(NodeServerTest, RepeatedRequestsAreNotDuplicated)
{
    FakeSource source;
    NodeServer server(source, {0, 8});
    server.submit(requests({{kA, 10}}));
    server.drain();
    server.submit(requests({{kA, 10}}));  // done but not yet taken
    server.drain();
    EXPECT_EQ(source.order.size(), 1u);
    EXPECT_EQ(server.takeCompleted().size(), 1u);
}

TEST(NodeServerTest, FailedGroupIsReportedOnceAndNeverRetried)
{
    FakeSource source;
    source.failing.insert(kA.key());
    NodeServer server(source, {0, 8});
    server.submit(requests({{kA, 10}, {kB, 20}}));
    server.drain();
    auto done = server.takeCompleted();
    ASSERT_EQ(done.size(), 2u);
    EXPECT_FALSE(done[0].children.ok());
    EXPECT_NE(done[0].children.error().message.find("1/0/0"), std::string::npos);
    EXPECT_TRUE(done[1].children.ok());
    for (int frame = 0; frame < 3; ++frame) {
        server.submit(requests({{kA, 10}}));
        server.drain();
        EXPECT_TRUE(server.takeCompleted().empty());
    }
    EXPECT_EQ(source.order.size(), 2u);
    EXPECT_EQ(server.stats().failed, 1u);
}

TEST(NodeServerTest, WorkersLoadEverythingAndMatchInline)
{
    auto run = [](int workers) {
        FakeSource source;
        NodeServer server(source, {workers, 64});
        std::vector<LoadRequest> wanted;
        std::map<std::uint64_t, std::uint16_t> loaded;
        NodeId parent = NodeId::root();
        for (int level = 0; level < 3; ++level) {
            for (std::uint32_t i = 0; i < (1u << (2 * level)); ++i) {
                NodeId id{level, i % (1u << level), i / (1u << level)};
                wanted.push_back({FakeSource::node(id), double(i)});
            }
        }
        server.submit(wanted);
        server.drain();
        EXPECT_EQ(server.stats().peakPending, wanted.size()) << "all admitted at once, none loaded yet";
        for (auto& group : server.takeCompleted()) {
            EXPECT_TRUE(group.children.ok());
            for (const auto& child : *group.children) {
                loaded[child->id.key()] = child->codes.front();
            }
        }
        (void)parent;
        return loaded;
    };
    auto inline0 = run(0);
    EXPECT_EQ(inline0.size(), 4u * 21u);
    EXPECT_EQ(run(1), inline0);
    EXPECT_EQ(run(2), inline0);
}

TEST(NodeServerTest, ShutdownWithRequestsInFlightReturns)
{
    FakeSource source;
    {
        NodeServer server(source, {2, 64});
        std::vector<LoadRequest> wanted;
        for (std::uint32_t i = 0; i < 64; ++i) {
            wanted.push_back({FakeSource::node({3, i % 8, i / 8}), double(i)});
        }
        server.submit(wanted);
        // Destroyed at once: queued requests are cancelled, loads in flight finish, workers join.
    }
    SUCCEED();
}

}  // namespace
}  // namespace terrain
