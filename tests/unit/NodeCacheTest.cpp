#include "lod/NodeCache.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace terrain {
namespace {

NodePtr makeNode(const NodeId& id)
{
    auto node = std::make_shared<NodeData>();
    node->id = id;
    node->hasChildren = true;
    return node;
}

ChildNodes makeChildren(const NodeId& parent)
{
    ChildNodes children;
    for (int q = 0; q < 4; ++q) {
        children[static_cast<std::size_t>(q)] = makeNode(parent.child(q));
    }
    return children;
}

/// Every resident node's parent is resident (reachability from the root).
void expectReachable(const NodeCache& cache, const std::vector<NodeId>& everInserted)
{
    for (const NodeId& parent : everInserted) {
        if (cache.children(parent)) {
            EXPECT_TRUE(cache.isResident(parent)) << "children of " << parent.toString() << " are orphaned";
        }
    }
}

TEST(NodeCacheTest, RootIsAlwaysResident)
{
    NodeCache cache(5);
    cache.setRoot(makeNode(NodeId::root()));
    EXPECT_TRUE(cache.isResident(NodeId::root()));
    EXPECT_EQ(cache.size(), 1u);
    EXPECT_FALSE(cache.isResident(NodeId::root().child(0)));
}

TEST(NodeCacheTest, InsertRequiresResidentParent)
{
    NodeCache cache(100);
    cache.setRoot(makeNode(NodeId::root()));
    NodeId grandChild = NodeId::root().child(1).child(2);
    EXPECT_EQ(cache.insertChildren(grandChild, makeChildren(grandChild)), NodeCache::Insert::ParentNotResident);
    EXPECT_EQ(cache.insertChildren(NodeId::root(), makeChildren(NodeId::root())), NodeCache::Insert::Inserted);
    EXPECT_EQ(cache.insertChildren(NodeId::root(), makeChildren(NodeId::root())), NodeCache::Insert::AlreadyResident);
    EXPECT_EQ(cache.size(), 5u);
    EXPECT_TRUE(cache.isResident(NodeId::root().child(3)));
}

TEST(NodeCacheTest, EvictsTheLeastRecentlyUsedGroup)
{
    // Capacity for the root and two groups: the root's children plus one grandchild group at a time.
    NodeCache cache(9);
    cache.setRoot(makeNode(NodeId::root()));
    const NodeId a = NodeId::root().child(0), b = NodeId::root().child(1), c = NodeId::root().child(2);
    ASSERT_EQ(cache.insertChildren(NodeId::root(), makeChildren(NodeId::root())), NodeCache::Insert::Inserted);
    ASSERT_EQ(cache.insertChildren(a, makeChildren(a)), NodeCache::Insert::Inserted);
    cache.beginFrame();
    cache.touchChildren(NodeId::root());
    cache.touchChildren(a);
    cache.beginFrame();
    cache.touchChildren(NodeId::root());
    // a's group was not used this frame: it goes to make room for b's.
    EXPECT_EQ(cache.groupsInsertable(), 1u);
    EXPECT_EQ(cache.insertChildren(b, makeChildren(b)), NodeCache::Insert::Inserted);
    EXPECT_EQ(cache.children(a), nullptr);
    EXPECT_NE(cache.children(b), nullptr);
    EXPECT_EQ(cache.evictions(), 1u);
    // b's group arrived this frame and the root's group was used: no room for c's.
    EXPECT_EQ(cache.groupsInsertable(), 0u);
    EXPECT_EQ(cache.insertChildren(c, makeChildren(c)), NodeCache::Insert::NoRoom);
    EXPECT_LE(cache.size(), cache.capacity());
}

TEST(NodeCacheTest, NeverEvictsAGroupWithResidentChildren)
{
    // root -> r0 -> r00: r0's group is older than r1's but holds the parent of a resident group.
    NodeCache cache(13);
    cache.setRoot(makeNode(NodeId::root()));
    const NodeId r0 = NodeId::root().child(0), r00 = r0.child(0), r1 = NodeId::root().child(1);
    ASSERT_EQ(cache.insertChildren(NodeId::root(), makeChildren(NodeId::root())), NodeCache::Insert::Inserted);
    ASSERT_EQ(cache.insertChildren(r0, makeChildren(r0)), NodeCache::Insert::Inserted);
    ASSERT_EQ(cache.insertChildren(r00, makeChildren(r00)), NodeCache::Insert::Inserted);
    cache.beginFrame();
    cache.touchChildren(r00);  // r00's group used more recently than r0's
    cache.beginFrame();
    EXPECT_EQ(cache.insertChildren(r1, makeChildren(r1)), NodeCache::Insert::Inserted);
    // r00's group (a leaf group) had to go, not r0's, though r0's was older.
    EXPECT_NE(cache.children(r0), nullptr);
    EXPECT_EQ(cache.children(r00), nullptr);
    expectReachable(cache, {NodeId::root(), r0, r00, r1});
}

/// Every resident node has a slot below the capacity that no other resident node has, its group's four in
/// quadrant order; the root's is 0; a node not resident has none.
void expectSlots(const NodeCache& cache, const std::vector<NodeId>& everInserted)
{
    std::vector<NodeId> holder(cache.capacity());
    ASSERT_EQ(cache.slotOf(NodeId::root()), 0);
    holder[0] = NodeId::root();
    std::size_t resident = 1;
    for (const NodeId& parent : everInserted) {
        const bool in = cache.children(parent) != nullptr;
        for (int q = 0; q < 4; ++q) {
            const NodeId child = parent.child(q);
            const int slot = cache.slotOf(child);
            if (!in) {
                EXPECT_EQ(slot, -1) << child.toString() << " is not resident";
                continue;
            }
            ASSERT_GE(slot, 1);
            ASSERT_LT(static_cast<std::size_t>(slot), cache.capacity());
            EXPECT_EQ(slot, cache.slotOf(parent.child(0)) + q) << "a group's slots are consecutive";
            if (holder[static_cast<std::size_t>(slot)] == child) {
                continue;  // the same parent inserted again later
            }
            EXPECT_EQ(holder[static_cast<std::size_t>(slot)].level, 0u)
                << child.toString() << " shares slot " << slot << " with "
                << holder[static_cast<std::size_t>(slot)].toString();
            holder[static_cast<std::size_t>(slot)] = child;
            ++resident;
        }
    }
    EXPECT_EQ(resident, cache.size());
}

TEST(NodeCacheTest, RandomWorkloadKeepsCapacityAndReachability)
{
    std::mt19937 random(7);
    NodeCache cache(41);
    cache.setRoot(makeNode(NodeId::root()));
    std::vector<NodeId> inserted;
    for (int frame = 0; frame < 2000; ++frame) {
        cache.beginFrame();
        // Touch a random resident path, then insert a random group below a resident node.
        NodeId id = NodeId::root();
        while (id.level < 6 && cache.touchChildren(id)) {
            id = id.child(static_cast<int>(random() % 4));
        }
        if (id.level < 6 && cache.isResident(id)) {
            cache.insertChildren(id, makeChildren(id));
            inserted.push_back(id);
        }
        ASSERT_LE(cache.size(), cache.capacity());
        if (frame % 50 == 0) {
            expectSlots(cache, inserted);
        }
    }
    expectReachable(cache, inserted);
    expectSlots(cache, inserted);
    EXPECT_GT(cache.evictions(), 0u);
}

}  // namespace
}  // namespace terrain
