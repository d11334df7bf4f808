#include "lod/TerrainStreamer.h"

#include "core/Check.h"

#include <algorithm>
#include <chrono>

namespace terrain {

TerrainStreamer::TerrainStreamer(NodeSource& source, const QuadtreeExtent& extent, const StreamerOptions& options)
    : mOptions(options),
      mTree(*this, extent),
      mCache(options.cacheSize, options.cacheBytes, options.cacheCharge),
      mServer(source, {options.workers, options.queueLimit})
{
}

NodeInfo TerrainStreamer::ResidentTree::info(const NodeId& id) const
{
    NodePtr node = mStreamer.node(id);
    TERRAIN_EXPECTS(node != nullptr, "the selection asked about a node that is not resident");
    return {node->hasChildren, node->deltaC, node->zMin, node->zMax};
}

Expected<std::unique_ptr<TerrainStreamer>> TerrainStreamer::create(NodeSource& source, const QuadtreeExtent& extent,
                                                                   const StreamerOptions& options)
{
    if (!(options.velocityLimit >= 0.0)) {
        return makeError("detail_velocity_limit ", options.velocityLimit, " must be >= 0");
    }
    if (options.cacheSize < 5) {
        return makeError("quad_cache_size ", options.cacheSize, " must be at least 5 (the root and four children)");
    }
    if (!(options.revealSeconds > 0.0)) {
        return makeError("visibility_reveal_seconds ", options.revealSeconds, " must be > 0");
    }
    if (options.queueLimit < 1) {
        return makeError("the request queue limit must be at least 1");
    }
    auto root = source.loadRoot();
    TERRAIN_TRY(root);
    std::unique_ptr<TerrainStreamer> streamer(new TerrainStreamer(source, extent, options));
    streamer->mCache.setRoot(std::move(root.value()));
    return streamer;
}

NodePtr TerrainStreamer::node(const NodeId& id) const
{
    if (id.isRoot()) {
        return mCache.root();
    }
    const ChildNodes* group = mCache.children(id.parent());
    return group ? (*group)[static_cast<std::size_t>(id.quadrant())] : nullptr;
}

void TerrainStreamer::collect(FrameStats& stats)
{
    for (auto& done : mServer.takeCompleted()) {
        if (!done.children.ok()) {
            if (mReport) {
                mReport(done.children.error().message);
            }
            continue;  // never requested again: the parent keeps being drawn
        }
        const ChildNodes& children = done.children.value();
        stats.synthesized += children[0] && !children[0]->isStatic ? 1 : 0;
        if (mCache.insertChildren(done.parent, std::move(done.children.value())) == NodeCache::Insert::Inserted) {
            ++stats.inserted;
        } else {
            ++stats.refused;
        }
    }
}

FrameStats TerrainStreamer::update(const Camera& camera, double tauPixels, double cameraSpeed)
{
    return update(camera, tauPixels, cameraSpeed, FrameVisibility{});
}

FrameStats TerrainStreamer::update(const Camera& camera, double tauPixels, double cameraSpeed,
                                   const FrameVisibility& visibility)
{
    TERRAIN_EXPECTS(cameraSpeed >= 0.0, "the camera speed must be >= 0");
    FrameStats stats;
    mCache.beginFrame();
    collect(stats);

    const auto start = std::chrono::steady_clock::now();
    const ChildrenResident resident = [this](const NodeId& parent) { return mCache.touchChildren(parent) != nullptr; };
    if (!visibility.hidden && mHiddenAt.empty() && mRevealStart.empty()) {
        selectNodes(mTree, camera, tauPixels, resident, mSelection);
    } else {
        const double now = visibility.time;
        const double ramp = mOptions.revealSeconds;
        NodeHidden hidden;
        if (visibility.hidden) {
            hidden = [&](const NodeId& id) {
                const bool h = visibility.hidden(id);
                if (h) {
                    mHiddenAt[id.key()] = now;
                }
                return h;
            };
        }
        // Whether `id` would be new surface in a revealed area: a node above it was drawn in the previous
        // selection (it refines what was drawn, not what was collapsed into a coarser node), and a node above it
        // was hidden a moment ago.
        auto revealedBelow = [&](NodeId id) {
            if (mHiddenAt.empty()) {
                return false;
            }
            bool refines = false, belowHidden = false;
            while (!id.isRoot() && !(refines && belowHidden)) {
                id = id.parent();
                refines = refines || mPrevious.contains(id.key());
                if (!belowHidden) {
                    const auto it = mHiddenAt.find(id.key());
                    belowHidden = it != mHiddenAt.end() && now - it->second <= kRevealWindowSeconds;
                }
            }
            return refines && belowHidden;
        };
        // Held: still morphing in, or about to be drawn for the first time in a revealed area (it morphs in
        // from this frame on, so its children must wait).
        const NodeHeld held = [&](const NodeId& id) {
            const auto it = mRevealStart.find(id.key());
            if (it != mRevealStart.end()) {
                return now - it->second < ramp;
            }
            return revealedBelow(id);
        };
        selectNodes(mTree, camera, tauPixels, resident, hidden, held, mSelection);
        // Nodes drawn for the first time below a node hidden a moment ago start morphing in now.
        std::unordered_set<std::uint64_t> drawn;
        drawn.reserve(mSelection.nodes.size());
        for (SelectedNode& node : mSelection.nodes) {
            const std::uint64_t key = node.id.key();
            drawn.insert(key);
            auto it = mRevealStart.find(key);
            if (it == mRevealStart.end() && revealedBelow(node.id)) {
                it = mRevealStart.emplace(key, now).first;
            }
            if (it != mRevealStart.end()) {
                const double f = (now - it->second) / ramp;
                if (f < 1.0) {
                    node.morph = std::min(node.morph, static_cast<float>(f));
                    ++stats.revealing;
                }
            }
        }
        std::erase_if(mRevealStart,
                      [&](const auto& entry) { return !drawn.contains(entry.first) || now - entry.second >= ramp; });
        std::erase_if(mHiddenAt, [&](const auto& entry) { return now - entry.second > kRevealWindowSeconds; });
        mPrevious = std::move(drawn);
    }
    if (mRevealStart.empty() && mHiddenAt.empty()) {
        mPrevious.clear();
    }
    stats.selectionSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    stats.selected = mSelection.nodes.size();
    stats.requested = mSelection.requests.size();
    stats.hidden = mSelection.hiddenNodes;
    stats.requestsSkippedHidden = mSelection.requestsSkippedHidden;

    // Ask only for what the cache can take now: a group loaded without room would be refused and asked for
    // again every frame, wasting the loader on a working set larger than the cache. When the room is short,
    // the parents whose screen-space error is largest (delta_c over distance, eq. 3.3) are refined first.
    mRequests.clear();
    for (const auto& request : mSelection.requests) {
        NodePtr parent = node(request.parent);
        TERRAIN_ASSERT(parent);  // a node waiting for its children is selected, hence resident
        // 3.4.4: dynamic detail finer than the camera can see while moving this fast is not made at all.
        if (!parent->hasStaticChildren && mOptions.velocityLimit > 0.0 &&
            cameraSpeed > mOptions.velocityLimit * parent->spacing * 0.5) {
            ++stats.tooFast;
            continue;
        }
        mRequests.push_back({std::move(parent), request.distance});
    }
    const std::size_t room = mCache.groupsInsertable();
    if (mRequests.size() > room) {
        auto error = [](const LoadRequest& r) {
            return static_cast<double>(r.parent->deltaC) / std::max(r.distance, 1e-3);
        };
        std::partial_sort(mRequests.begin(), mRequests.begin() + static_cast<std::ptrdiff_t>(room), mRequests.end(),
                          [&](const LoadRequest& a, const LoadRequest& b) {
                              const double ea = error(a), eb = error(b);
                              return ea > eb || (ea == eb && a.parent->id.key() < b.parent->id.key());
                          });
        stats.deferred = mRequests.size() - room;
        mRequests.resize(room);
    }
    mServer.submit(mRequests);
    return stats;
}

FrameStats TerrainStreamer::updateFor(std::span<const NodeId> wanted)
{
    FrameStats stats;
    mCache.beginFrame();
    collect(stats);
    mSelection = {};
    mRequests.clear();
    std::unordered_set<std::uint64_t> asked;
    for (const NodeId& id : wanted) {
        // Down from the root: touch each resident group on the way, ask for the first one missing.
        NodePtr at = mCache.root();
        for (int level = 1; level <= id.level && at; ++level) {
            const NodeId step{level, id.x >> (id.level - level), id.y >> (id.level - level)};
            const ChildNodes* group = mCache.touchChildren(step.parent());
            if (group) {
                at = (*group)[static_cast<std::size_t>(step.quadrant())];
                continue;
            }
            if (at->hasChildren && asked.insert(step.parent().key()).second) {
                mRequests.push_back({at, static_cast<double>(level)});
            }
            at = nullptr;
        }
    }
    stats.requested = mRequests.size();
    const std::size_t room = mCache.groupsInsertable();
    if (mRequests.size() > room) {
        // Coarse levels first: finer groups need them as parents.
        std::stable_sort(mRequests.begin(), mRequests.end(),
                         [](const LoadRequest& a, const LoadRequest& b) { return a.distance < b.distance; });
        stats.deferred = mRequests.size() - room;
        mRequests.resize(room);
    }
    mServer.submit(mRequests);
    return stats;
}

FrameStats TerrainStreamer::settle(Settle settle, const std::function<FrameStats()>& select,
                                   const std::function<bool()>& unsettled)
{
    FrameStats stats = select();
    if (settle == Settle::Arrived) {
        return stats;
    }
    for (int round = 1; round < kMaxSettleRounds; ++round) {
        const bool wantsMore = stats.requested > stats.deferred + stats.tooFast;
        if (!wantsMore && !(unsettled && unsettled())) {
            break;
        }
        const std::size_t synthesized = stats.synthesized + drain().synthesized;
        stats = select();
        stats.synthesized += synthesized;  // the frame's, all rounds together
    }
    return stats;
}

FrameStats TerrainStreamer::settle(Settle settle, const Camera& camera, double tauPixels, double cameraSpeed,
                                   const FrameVisibility& visibility)
{
    return this->settle(settle, [&] { return update(camera, tauPixels, cameraSpeed, visibility); });
}

FrameStats TerrainStreamer::drain()
{
    mServer.drain();
    FrameStats stats;
    collect(stats);
    return stats;
}

}  // namespace terrain
