#include "lod/NodeCache.h"
#include "lod/NodeMemory.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
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

/// Walks from the root down random resident groups (touching them) to a node whose children are not resident,
/// above `maxLevel`; or to where the walk stopped at `maxLevel` (then the caller inserts nothing).
NodeId walkToMissingGroup(NodeCache& cache, std::mt19937& random, int maxLevel)
{
    NodeId id = NodeId::root();
    while (id.level < maxLevel && cache.touchChildren(id)) {
        id = id.child(static_cast<int>(random() % 4));
    }
    return id;
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
        const NodeId id = walkToMissingGroup(cache, random, 6);
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

TEST(NodeCacheTest, MakingRoomNeverEvictsTheGroupThatHoldsTheNewGroupsParent)
{
    // Root + two groups fill the 9 slots: the root's children, and child 0's. A group below child 0's child 1
    // needs room; the only evictable group is child 0's, which holds its parent: refused, nothing evicted.
    NodeCache cache(9);
    cache.setRoot(makeNode(NodeId::root()));
    const NodeId child = NodeId::root().child(0);
    ASSERT_EQ(cache.insertChildren(NodeId::root(), makeChildren(NodeId::root())), NodeCache::Insert::Inserted);
    ASSERT_EQ(cache.insertChildren(child, makeChildren(child)), NodeCache::Insert::Inserted);
    cache.beginFrame();
    const NodeId parent = child.child(1);
    EXPECT_EQ(cache.insertChildren(parent, makeChildren(parent)), NodeCache::Insert::NoRoom);
    EXPECT_TRUE(cache.isResident(parent));
    EXPECT_EQ(cache.evictions(), 0u);
    // With a group of another branch to evict, the insertion evicts that one.
    NodeCache roomy(13);
    roomy.setRoot(makeNode(NodeId::root()));
    const NodeId other = NodeId::root().child(3);
    ASSERT_EQ(roomy.insertChildren(NodeId::root(), makeChildren(NodeId::root())), NodeCache::Insert::Inserted);
    ASSERT_EQ(roomy.insertChildren(child, makeChildren(child)), NodeCache::Insert::Inserted);
    ASSERT_EQ(roomy.insertChildren(other, makeChildren(other)), NodeCache::Insert::Inserted);
    roomy.beginFrame();
    EXPECT_EQ(roomy.insertChildren(parent, makeChildren(parent)), NodeCache::Insert::Inserted);
    EXPECT_TRUE(roomy.isResident(parent));
    EXPECT_FALSE(roomy.isResident(other.child(0)));
    expectReachable(roomy, {NodeId::root(), child, other, parent});
}

TEST(NodeCacheTest, AByteBudgetHoldsWhateverTheNodesSizes)
{
    // Nodes of 1 to 64 KB of texture under a 600 KB budget and 201 slots (far more than the bytes allow): the
    // cache's bytes are always the resident nodes' residentBytes summed, never above the budget; groups go for
    // bytes while slots are free; a group larger than the budget is refused without evicting anything; and
    // groupsInsertable() never promises room that a group no larger than one offered before would not find.
    std::mt19937 random(11);
    constexpr std::size_t kBudget = 600 * 1024;
    NodeCache cache(201, kBudget);
    cache.setRoot(makeNode(NodeId::root()));
    auto sized = [&](const NodeId& parent) {
        ChildNodes children = makeChildren(parent);
        for (NodePtr& child : children) {
            auto node = std::make_shared<NodeData>(*child);
            node->texture.resize(1024 * (1 + random() % 64));
            child = node;
        }
        return children;
    };
    std::vector<NodeId> inserted;
    bool evictedWithSlotsFree = false;
    std::size_t largest = 0;  // the largest group offered so far
    for (int frame = 0; frame < 2000; ++frame) {
        cache.beginFrame();
        const NodeId id = walkToMissingGroup(cache, random, 7);
        if (id.level < 7 && cache.isResident(id)) {
            const std::uint64_t evictions = cache.evictions();
            const std::size_t insertable = cache.groupsInsertable();
            const ChildNodes children = sized(id);
            std::size_t bytes = 0;
            for (const NodePtr& child : children) {
                bytes += residentBytes(*child);
            }
            const NodeCache::Insert result = cache.insertChildren(id, children);
            evictedWithSlotsFree = evictedWithSlotsFree || (cache.evictions() > evictions && cache.size() + 4 < 201);
            if (result == NodeCache::Insert::Inserted) {
                inserted.push_back(id);
            } else {
                ASSERT_EQ(result, NodeCache::Insert::NoRoom);
                ASSERT_EQ(cache.evictions(), evictions) << "nothing evicted for a refused group";
                EXPECT_TRUE(insertable == 0 || bytes > largest)
                    << "room was promised, and a group no larger than one offered before did not find it";
            }
            largest = std::max(largest, bytes);
        }
        std::size_t held = residentBytes(*cache.root());
        std::set<std::uint64_t> counted;  // a group evicted and inserted again is in `inserted` twice
        for (const NodeId& parent : inserted) {
            const ChildNodes* group = cache.children(parent);
            if (group && counted.insert(parent.key()).second) {
                for (const NodePtr& node : *group) {
                    held += residentBytes(*node);
                }
            }
        }
        ASSERT_EQ(cache.bytes(), held);
        ASSERT_LE(cache.bytes(), kBudget);
        ASSERT_LE(cache.size(), cache.capacity());
    }
    expectReachable(cache, inserted);
    EXPECT_TRUE(evictedWithSlotsFree) << "the budget, not the slots, bounds these nodes";

    // A group larger than the budget: refused, and the groups that could have gone stay.
    NodeCache small(201, kBudget);
    small.setRoot(makeNode(NodeId::root()));
    ASSERT_EQ(small.insertChildren(NodeId::root(), makeChildren(NodeId::root())), NodeCache::Insert::Inserted);
    const NodeId parent = NodeId::root().child(0);
    ASSERT_EQ(small.insertChildren(parent, makeChildren(parent)), NodeCache::Insert::Inserted);
    small.beginFrame();  // nothing used in this frame: every group without resident children may go
    ChildNodes huge = makeChildren(parent.child(3));
    for (NodePtr& child : huge) {
        auto node = std::make_shared<NodeData>(*child);
        node->texture.resize(kBudget / 2);
        child = node;
    }
    EXPECT_EQ(small.insertChildren(parent.child(3), huge), NodeCache::Insert::NoRoom);
    EXPECT_EQ(small.evictions(), 0u);
    EXPECT_EQ(small.size(), 9u);
}

}  // namespace
}  // namespace terrain
