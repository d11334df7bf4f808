// The working set of resident nodes (paper 3.2.14): LRU with a fixed capacity (`quad_cache_size`), and
// optionally a budget of the CPU bytes its nodes hold (residentBytes, lod/NodeMemory.h, or a charge standing for
// them; memory_budget).
//
// Nodes enter and leave in sibling groups of four (the children of one parent), as they are loaded
// (3.2.14: siblings are always loaded together). The root is always resident. Eviction takes the least
// recently used group that was not used this frame and none of whose nodes has resident children, so it
// never removes a node drawn this frame and never leaves a resident node unreachable from the root. A group
// goes when the slots are full or when the new group's bytes would overrun the budget. When no group can go, an
// insertion is refused instead of overfilling the cache (the paper's 4.5 defect): the budget always holds.
// Every resident node has a slot in [0, capacity): the root 0, a group's four nodes four consecutive slots that
// the group keeps while resident and gives back when evicted. The renderer's node pools have a layer per slot,
// so what the cache holds is what the pools can hold, and a slot whose node changed is all the renderer needs
// to know. Render thread only; not thread-safe.
#pragma once

#include "lod/NodeData.h"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <unordered_map>
#include <vector>

namespace terrain {

/// What a resident node is charged against a cache's byte budget; empty: its residentBytes.
using NodeCharge = std::function<std::size_t(const NodeData&)>;

class NodeCache {
public:
    /// `capacity` in nodes (root included), at least 5; `byteBudget` the most bytes its nodes are charged
    /// together (`charge`, residentBytes when empty), the root's included (SIZE_MAX: no limit but the capacity).
    explicit NodeCache(std::size_t capacity, std::size_t byteBudget = SIZE_MAX, NodeCharge charge = {});

    void setRoot(NodePtr root);
    const NodePtr& root() const { return mRoot; }

    /// Starts a frame: groups touched from now on are protected from eviction until the next beginFrame.
    void beginFrame() { ++mFrame; }

    /// The four children of `parent` if they are resident, else null. Does not count as a use.
    const ChildNodes* children(const NodeId& parent) const;
    /// Marks the children of `parent` used this frame (the traversal descends into them). Returns them, or
    /// null (and counts a miss) when they are not resident.
    const ChildNodes* touchChildren(const NodeId& parent);
    /// True for the root and for every node of a resident group.
    bool isResident(const NodeId& id) const;

    enum class Insert { Inserted, AlreadyResident, ParentNotResident, NoRoom };
    /// Makes the children of `parent` resident, evicting least recently used groups as needed.
    Insert insertChildren(const NodeId& parent, ChildNodes children);

    /// Groups that insertChildren() could make room for now: free space plus groups it may evict, in slots and,
    /// with a byte budget, in bytes (groups as large as the largest offered so far).
    std::size_t groupsInsertable() const;

    std::size_t size() const { return 1 + 4 * mGroups.size(); }
    std::size_t capacity() const { return mCapacity; }
    std::size_t byteBudget() const { return mByteBudget; }
    /// The bytes the resident nodes are charged, the root's included.
    std::size_t bytes() const { return mBytes; }
    /// What `node` is charged.
    std::size_t chargeOf(const NodeData& node) const { return mCharge(node); }
    std::uint64_t hits() const { return mHits; }
    std::uint64_t misses() const { return mMisses; }
    std::uint64_t evictions() const { return mEvictions; }

    /// The slot of resident node `id`, in [0, capacity()); -1 when it is not resident. The root's is 0; the
    /// nodes of a group hold 4g + 1 .. 4g + 4 (in quadrant order) while the group is resident; a slot given back
    /// by an evicted group goes to a later one.
    int slotOf(const NodeId& id) const;

private:
    struct Group {
        ChildNodes nodes;
        std::uint64_t lastUsed = 0;
        std::list<std::uint64_t>::iterator lru;  ///< position in mLru (front = most recent)
        int slot = 0;                            ///< g: its nodes' slots are 4g + 1 .. 4g + 4
        std::size_t bytes = 0;                   ///< its nodes' charges
    };
    /// A parent key no group has (the root's children's group is keyed by the root).
    static constexpr std::uint64_t kNoGroup = ~std::uint64_t{0};
    /// Evicts the least recently used evictable group but the one keyed `keep`; false when there is none.
    bool evictOne(std::uint64_t keep);
    bool isEvictable(const Group& group) const;

    std::size_t mCapacity;
    std::size_t mByteBudget;
    NodeCharge mCharge;
    std::size_t mBytes = 0;       ///< resident nodes' bytes, the root's included
    std::size_t mGroupBytes = 0;  ///< the groups' part of mBytes
    /// The largest charge of a group inserted or offered so far: what groupsInsertable() counts room for in
    /// bytes, so that it never promises room a group no larger than those before would not find.
    std::size_t mLargestGroupBytes = 0;
    NodePtr mRoot;
    std::unordered_map<std::uint64_t, Group> mGroups;  ///< by parent key
    std::list<std::uint64_t> mLru;                     ///< parent keys, most recently used first
    std::uint64_t mFrame = 1;
    std::uint64_t mHits = 0;
    std::uint64_t mMisses = 0;
    std::uint64_t mEvictions = 0;
    std::vector<int> mFreeGroupSlots;  ///< a stack, the lowest on top
};

}  // namespace terrain
