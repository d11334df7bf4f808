// LRU node cache (paper 3.2.14) with the reachability rule of this engine.
#include "lod/NodeCache.h"

#include "core/Check.h"
#include "lod/NodeMemory.h"

#include <algorithm>
#include <utility>

namespace terrain {

NodeCache::NodeCache(std::size_t capacity, std::size_t byteBudget, NodeCharge charge)
    : mCapacity(capacity),
      mByteBudget(byteBudget),
      mCharge(charge ? std::move(charge) : NodeCharge([](const NodeData& node) { return residentBytes(node); }))
{
    TERRAIN_EXPECTS(capacity >= 5, "the cache must hold at least the root and one group of four");
    mGroups.reserve(capacity / 4 + 1);
    const auto groups = static_cast<int>((capacity - 1) / 4);
    for (int g = groups; g-- > 0;) {
        mFreeGroupSlots.push_back(g);
    }
}

int NodeCache::slotOf(const NodeId& id) const
{
    if (id.isRoot()) {
        return mRoot ? 0 : -1;
    }
    auto it = mGroups.find(id.parent().key());
    return it == mGroups.end() ? -1 : 4 * it->second.slot + 1 + id.quadrant();
}

void NodeCache::setRoot(NodePtr root)
{
    TERRAIN_EXPECTS(root && root->id.isRoot(), "the root must be node 0/0/0");
    mRoot = std::move(root);
    mBytes = mGroupBytes + mCharge(*mRoot);
}

const ChildNodes* NodeCache::children(const NodeId& parent) const
{
    auto it = mGroups.find(parent.key());
    return it == mGroups.end() ? nullptr : &it->second.nodes;
}

const ChildNodes* NodeCache::touchChildren(const NodeId& parent)
{
    auto it = mGroups.find(parent.key());
    if (it == mGroups.end()) {
        ++mMisses;
        return nullptr;
    }
    ++mHits;
    Group& group = it->second;
    group.lastUsed = mFrame;
    mLru.splice(mLru.begin(), mLru, group.lru);
    return &group.nodes;
}

bool NodeCache::isResident(const NodeId& id) const
{
    return id.isRoot() ? static_cast<bool>(mRoot) : mGroups.count(id.parent().key()) != 0;
}

bool NodeCache::isEvictable(const Group& group) const
{
    if (group.lastUsed == mFrame) {
        return false;  // drawn or traversed this frame
    }
    for (const auto& node : group.nodes) {
        if (mGroups.count(node->id.key()) != 0) {
            return false;  // evicting it would orphan its descendants
        }
    }
    return true;
}

std::size_t NodeCache::groupsInsertable() const
{
    std::size_t free = (mCapacity - size()) / 4;
    std::size_t freeBytes = mByteBudget - std::min(mBytes, mByteBudget);
    for (const auto& [key, group] : mGroups) {
        if (isEvictable(group)) {
            ++free;
            freeBytes += group.bytes;
        }
    }
    if (mByteBudget == SIZE_MAX || mLargestGroupBytes == 0) {
        return free;
    }
    return std::min(free, freeBytes / mLargestGroupBytes);
}

bool NodeCache::evictOne(std::uint64_t keep)
{
    for (auto it = mLru.rbegin(); it != mLru.rend(); ++it) {
        auto found = mGroups.find(*it);
        TERRAIN_ASSERT(found != mGroups.end());
        if (*it == keep || !isEvictable(found->second)) {
            continue;
        }
        mLru.erase(found->second.lru);
        mFreeGroupSlots.push_back(found->second.slot);
        mBytes -= found->second.bytes;
        mGroupBytes -= found->second.bytes;
        mGroups.erase(found);
        ++mEvictions;
        return true;
    }
    return false;
}

NodeCache::Insert NodeCache::insertChildren(const NodeId& parent, ChildNodes children)
{
    for (int q = 0; q < 4; ++q) {
        TERRAIN_EXPECTS(
            children[static_cast<std::size_t>(q)] && children[static_cast<std::size_t>(q)]->id == parent.child(q),
            "children must be the four children of parent, in quadrant order");
    }
    if (mGroups.count(parent.key()) != 0) {
        return Insert::AlreadyResident;
    }
    if (!isResident(parent)) {
        return Insert::ParentNotResident;  // evicted while its children were loading
    }
    std::size_t bytes = 0;
    for (const NodePtr& child : children) {
        bytes += mCharge(*child);
    }
    mLargestGroupBytes = std::max(mLargestGroupBytes, bytes);
    // The group holding `parent` stays: evicting it would leave the new group unreachable.
    const std::uint64_t keep = parent.isRoot() ? kNoGroup : parent.parent().key();
    if (mByteBudget != SIZE_MAX && mBytes + bytes > mByteBudget) {
        // Nothing is evicted for a group that would not fit with every evictable group gone.
        std::size_t evictable = 0;
        for (const auto& [key, group] : mGroups) {
            evictable += key != keep && isEvictable(group) ? group.bytes : 0;
        }
        if (mBytes - evictable + bytes > mByteBudget) {
            return Insert::NoRoom;
        }
    }
    while (size() + 4 > mCapacity || (mByteBudget != SIZE_MAX && mBytes + bytes > mByteBudget)) {
        if (!evictOne(keep)) {
            return Insert::NoRoom;
        }
    }
    TERRAIN_ASSERT(!mFreeGroupSlots.empty());
    const int slot = mFreeGroupSlots.back();
    mFreeGroupSlots.pop_back();
    mLru.push_front(parent.key());
    // A group arrives because the traversal wants it: it counts as used this frame, so a later insertion in
    // the same frame cannot evict it again.
    mGroups.emplace(parent.key(), Group{std::move(children), mFrame, mLru.begin(), slot, bytes});
    mBytes += bytes;
    mGroupBytes += bytes;
    return Insert::Inserted;
}

}  // namespace terrain
