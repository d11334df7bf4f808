#include "lod/NodeVisibility.h"

#include "core/Check.h"

#include <algorithm>

namespace terrain {

namespace {
constexpr std::uint64_t kForgetFrames = 256;
}

NodeVisibility::NodeVisibility(int hiddenFrames) : mHiddenFrames(hiddenFrames)
{
    TERRAIN_EXPECTS(hiddenFrames >= 1, "a node must be dark for at least one frame to count as hidden");
}

void NodeVisibility::record(std::uint64_t frame, std::span<const NodeId> drawn, std::span<const std::uint32_t> pixels)
{
    TERRAIN_EXPECTS(drawn.size() == pixels.size(), "one pixel count per drawn node");
    TERRAIN_EXPECTS(!mAny || frame > mLatest, "frames are recorded in increasing order");
    // Every drawn node and its ancestors, visible when any node drawn at or below them is.
    mTouched.clear();
    for (std::size_t i = 0; i < drawn.size(); ++i) {
        for (NodeId id = drawn[i];; id = id.parent()) {
            mTouched.emplace_back(id.key(), pixels[i] > 0);
            if (id.isRoot()) {
                break;
            }
        }
    }
    std::sort(mTouched.begin(), mTouched.end());
    for (std::size_t i = 0; i < mTouched.size();) {
        const std::uint64_t key = mTouched[i].first;
        bool visible = false;
        for (; i < mTouched.size() && mTouched[i].first == key; ++i) {
            visible = visible || mTouched[i].second;
        }
        Record& r = mRecords[key];
        if (r.required == 0) {
            r.required = mHiddenFrames;
        }
        if (visible) {
            if (r.hiddenStreak >= r.required) {
                r.required = std::min(2 * r.required, 8 * mHiddenFrames);  // revealed: slower to hide again
            }
            r.hiddenStreak = 0;
            r.everVisible = true;
        } else {
            ++r.hiddenStreak;
        }
        r.lastFrame = frame;
    }
    mLatest = frame;
    mAny = true;
    if (frame % 64 == 0) {
        std::erase_if(mRecords, [&](const auto& entry) { return entry.second.lastFrame + kForgetFrames < frame; });
    }
}

bool NodeVisibility::hidden(const NodeId& id) const
{
    const auto it = mRecords.find(id.key());
    return it != mRecords.end() && it->second.lastFrame == mLatest && it->second.hiddenStreak >= it->second.required;
}

NodeVisibility::Seen NodeVisibility::seen(const NodeId& id) const
{
    const auto it = mRecords.find(id.key());
    if (it == mRecords.end() || it->second.lastFrame != mLatest) {
        return Seen::kUnknown;
    }
    const Record& r = it->second;
    if (r.hiddenStreak >= r.required) {
        return Seen::kHidden;
    }
    return r.everVisible ? Seen::kVisible : Seen::kUnknown;
}

namespace {

/// Whether every drawable surface below `id` lay behind the depth: its nested box is occluded, or, down to
/// `depth` more levels of resident nodes, every child's box is (tighter: the quarters' own height ranges).
bool occludedBelow(const NodeId& id, const NodeInfo& info, const DepthOcclusion& occlusion, const LodTree& tree,
                   const ChildrenKnown& childrenResident, int depth, double grow)
{
    if (occlusion.occluded(tree.extent().box(id, info.zMin, info.zMax), grow)) {
        return true;
    }
    if (depth == 0 || !info.hasChildren || !childrenResident || !childrenResident(id)) {
        return false;
    }
    for (int q = 0; q < 4; ++q) {
        const NodeId child = id.child(q);
        if (!occludedBelow(child, tree.info(child), occlusion, tree, childrenResident, depth - 1, grow)) {
            return false;
        }
    }
    return true;
}

}  // namespace

NodeHidden hiddenFrom(const NodeVisibility& visibility, const DepthOcclusion* occlusion, const LodTree& tree,
                      ChildrenKnown childrenResident, double growMetres)
{
    TERRAIN_EXPECTS(growMetres >= 0.0, "boxes grow by >= 0 metres");
    return
        [&visibility, occlusion, &tree, childrenResident = std::move(childrenResident), growMetres](const NodeId& id) {
            switch (visibility.seen(id)) {
                case NodeVisibility::Seen::kHidden:
                    // Dark as drawn, but its refined surface may not be: a peak that the coarse node cuts off
                    // below the ridge in front would stay hidden for good. Nested boxes bound every descendant,
                    // so the node stays hidden only where its boxes are behind the depth as well.
                    if (occlusion == nullptr) {
                        return true;
                    }
                    break;
                case NodeVisibility::Seen::kVisible:
                    return false;
                case NodeVisibility::Seen::kUnknown:
                    if (occlusion == nullptr) {
                        return false;
                    }
                    break;
            }
            return occludedBelow(id, tree.info(id), *occlusion, tree, childrenResident, kOcclusionLevels, growMetres);
        };
}

}  // namespace terrain
