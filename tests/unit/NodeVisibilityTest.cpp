// NodeVisibility (issue 16): pixel counts of drawn nodes, read back late, become "hidden" for the selection
// only after k dark measured frames, summed over the nodes drawn below a node, conservatively for nodes
// not measured lately, and more slowly again after a reveal.
#include "lod/NodeVisibility.h"

#include <gtest/gtest.h>

#include <vector>

namespace terrain {
namespace {

const NodeId kA{2, 1, 1};

TEST(NodeVisibilityTest, HiddenAfterKDarkFramesAndVisibleAgainAtOnce)
{
    NodeVisibility v(3);
    EXPECT_FALSE(v.hidden(kA)) << "never drawn: not hidden";
    const std::vector<NodeId> drawn{kA};
    for (std::uint64_t f = 1; f <= 2; ++f) {
        v.record(f, drawn, std::vector<std::uint32_t>{0});
        EXPECT_FALSE(v.hidden(kA)) << "frame " << f;
    }
    v.record(3, drawn, std::vector<std::uint32_t>{0});
    EXPECT_TRUE(v.hidden(kA));
    EXPECT_TRUE(v.hidden(kA.parent())) << "its ancestors drew nothing else";
    v.record(4, drawn, std::vector<std::uint32_t>{12});
    EXPECT_FALSE(v.hidden(kA)) << "one visible pixel reveals it";
}

TEST(NodeVisibilityTest, ANodeSumsTheNodesDrawnBelowIt)
{
    NodeVisibility v(2);
    const std::vector<NodeId> children{kA.child(0), kA.child(1), kA.child(2), kA.child(3)};
    for (std::uint64_t f = 1; f <= 4; ++f) {
        v.record(f, children, std::vector<std::uint32_t>{0, 0, 5, 0});
    }
    EXPECT_FALSE(v.hidden(kA)) << "one child shows pixels";
    EXPECT_TRUE(v.hidden(kA.child(0)));
    EXPECT_FALSE(v.hidden(kA.child(2)));
    for (std::uint64_t f = 5; f <= 6; ++f) {
        v.record(f, children, std::vector<std::uint32_t>{0, 0, 0, 0});
    }
    EXPECT_TRUE(v.hidden(kA)) << "all four dark for k frames";
}

TEST(NodeVisibilityTest, NodesNotDrawnInTheLatestMeasuredFrameAreNotHidden)
{
    NodeVisibility v(1);
    const NodeId b{2, 3, 0};
    v.record(1, std::vector<NodeId>{kA, b}, std::vector<std::uint32_t>{0, 0});
    EXPECT_TRUE(v.hidden(kA));
    v.record(2, std::vector<NodeId>{b}, std::vector<std::uint32_t>{0});
    EXPECT_FALSE(v.hidden(kA)) << "out of view since: its old count says nothing now";
    EXPECT_TRUE(v.hidden(b));
    EXPECT_EQ(v.latestFrame(), 2u);
}

TEST(NodeVisibilityTest, ARevealedNodeMustStayDarkTwiceAsLongUpToEightK)
{
    NodeVisibility v(2);
    const std::vector<NodeId> drawn{kA};
    std::uint64_t f = 0;
    auto darkFramesToHide = [&] {
        int n = 0;
        do {
            v.record(++f, drawn, std::vector<std::uint32_t>{0});
            ++n;
        } while (!v.hidden(kA));
        v.record(++f, drawn, std::vector<std::uint32_t>{1});  // revealed
        return n;
    };
    EXPECT_EQ(darkFramesToHide(), 2);
    EXPECT_EQ(darkFramesToHide(), 4);
    EXPECT_EQ(darkFramesToHide(), 8);
    EXPECT_EQ(darkFramesToHide(), 16);
    EXPECT_EQ(darkFramesToHide(), 16) << "capped at 8 k";
}

TEST(NodeVisibilityTest, RecordsOfNodesNotDrawnForLongAreDropped)
{
    NodeVisibility v(1);
    v.record(1, std::vector<NodeId>{kA}, std::vector<std::uint32_t>{0});
    const std::size_t withA = v.records();
    EXPECT_EQ(withA, 3u) << "the node and its two ancestors";
    const NodeId b{1, 1, 0};
    for (std::uint64_t f = 2; f <= 320; ++f) {
        v.record(f, std::vector<NodeId>{b}, std::vector<std::uint32_t>{1});
    }
    EXPECT_EQ(v.records(), 2u) << "only b and the root remain";
}

}  // namespace
}  // namespace terrain
