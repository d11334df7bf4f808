// One frame of the runtime core, without GL (paper 3.2.15): take the nodes the server finished into the
// cache, select with the camera, hand the selection's child requests to the server. The viewer draws
// `selection().nodes` with the data from node(); tools and benchmarks replay camera paths through it.
#pragma once

#include "lod/LodSelector.h"
#include "lod/NodeCache.h"
#include "lod/NodeServer.h"

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace terrain {

struct StreamerOptions {
    std::size_t cacheSize = 512;  ///< quad_cache_size, nodes
    /// The most CPU bytes the cached nodes hold together (NodeCache's byte budget; memory_budget's share of the
    /// nodes' CPU data); SIZE_MAX: the count alone.
    std::size_t cacheBytes = SIZE_MAX;
    NodeCharge cacheCharge;      ///< what a node is charged against cacheBytes; empty: its residentBytes
    std::size_t queueLimit = 8;  ///< most load requests waiting at once
    int workers = 1;             ///< loader threads; 0 = inline (loads happen in drain())
    /// detail_velocity_limit (3.4.4): no new dynamic nodes while the camera moves faster than this many of
    /// their sample spacings per second; 0 = no limit. Static nodes are always loaded.
    double velocityLimit = 0.0;
    /// visibility_reveal_seconds: with visibility, a node drawn for the first time below a node
    /// that was hidden less than kRevealWindowSeconds ago morphs in from its parent's surface over this long,
    /// and is not refined before it has (the next level then morphs in the same way): cresting a ridge
    /// refines the terrain behind it a level each this many seconds, morphed, instead of popping the levels
    /// in at once. > 0.
    double revealSeconds = 0.1;
};

/// How long after a node was last hidden the nodes first drawn below it morph in (StreamerOptions::revealSeconds).
inline constexpr double kRevealWindowSeconds = 2.0;

/// What the viewer saw of the nodes it drew (visibility_lod) and when, for one update.
struct FrameVisibility {
    NodeHidden hidden;  ///< nodes not to refine (NodeVisibility::hidden); empty: none
    double time = 0.0;  ///< seconds on the viewer's clock (video mode: the frame's time); never decreasing
};

/// Per-frame figures.
struct FrameStats {
    std::size_t selected = 0;   ///< nodes drawn
    std::size_t requested = 0;  ///< child groups the traversal wanted but were not resident
    /// Of those, not asked for: the cache has no room this frame (frames.csv's cache_short); the ones asked for
    /// are those of the largest screen-space error.
    std::size_t deferred = 0;
    std::size_t tooFast = 0;                ///< of those, not asked for: dynamic, and the camera is too fast (3.4.4)
    std::size_t inserted = 0;               ///< groups that became resident this frame
    std::size_t refused = 0;                ///< finished groups the cache had no room (or no parent) for
    std::size_t synthesized = 0;            ///< finished groups of dynamic nodes (made by synthesis, 3.4)
    double selectionSeconds = 0.0;          ///< time in selectNodes
    std::size_t hidden = 0;                 ///< nodes selected as they are because hidden (LodSelection::hiddenNodes)
    std::size_t requestsSkippedHidden = 0;  ///< of those, the ones whose children were not resident
    std::size_t revealing = 0;              ///< nodes selected this frame still morphing in after a reveal
};

/// How much of what a frame wants is loaded before it is drawn.
enum class Settle {
    Arrived,   ///< real time: what has arrived by now; the rest comes in later frames
    Complete,  ///< video frames and tools: load and select again until the frame wants nothing more it can have
};

/// The most select-and-load rounds of one Settle::Complete frame. A round loads the children of the nodes the
/// last selection wanted, so the rounds are at most the levels the frame refines by (each level is one round);
/// failed groups are never asked for again. The cap only bounds a cache that evicts what it just loaded.
inline constexpr int kMaxSettleRounds = 256;

class TerrainStreamer {
public:
    /// `source` must outlive the streamer; `extent` places its root. Loads the root synchronously. The
    /// selection runs on the resident nodes' own information (NodeData: errors, boxes, whether children can
    /// be made), which covers static and dynamic nodes alike.
    static Expected<std::unique_ptr<TerrainStreamer>> create(NodeSource& source, const QuadtreeExtent& extent,
                                                             const StreamerOptions& options);

    /// One frame: collect finished loads, select for `camera` at tau pixels, request what is missing.
    /// `cameraSpeed` (metres per second, >= 0) feeds the velocity limit.
    FrameStats update(const Camera& camera, double tauPixels, double cameraSpeed = 0.0);
    /// The same with visibility: `visibility.hidden` nodes are not refined and request nothing;
    /// nodes first drawn below a node hidden in the last kRevealWindowSeconds morph in over
    /// StreamerOptions::revealSeconds from their parent's surface (their SelectedNode::morph is at most the
    /// time since then over revealSeconds) and are not refined before that (NodeHeld).
    FrameStats update(const Camera& camera, double tauPixels, double cameraSpeed, const FrameVisibility& visibility);

    /// Clipmap mode (lod/ClipmapTerrain.h): no selection (it stays empty). Keeps the `wanted` nodes and
    /// their ancestors resident and, for each one missing, asks for the children of its deepest resident
    /// ancestor that can have them, coarse levels first (within the cache's room). FrameStats::requested counts
    /// the groups asked for (or wanted and deferred), inserted / refused / synthesized what arrived.
    FrameStats updateFor(std::span<const NodeId> wanted);

    /// Waits for every queued load, then takes the results into the cache (no selection); returns what it took
    /// (FrameStats::inserted, refused and synthesized; the rest 0).
    FrameStats drain();

    /// One frame settled as `settle` says: runs `select` (an update or updateFor of this streamer); with
    /// Settle::Complete, while the frame asked for groups it could load (FrameStats::requested beyond deferred and
    /// tooFast) or `unsettled` (when given) says the frame is not final yet, waits for the loads (drain) and runs
    /// `select` again, at most kMaxSettleRounds times. Identical runs give identical frames whatever the threads'
    /// timing. Returns the last round's figures with FrameStats::synthesized summed over the rounds.
    FrameStats settle(Settle settle, const std::function<FrameStats()>& select,
                      const std::function<bool()>& unsettled = {});
    /// settle() of update(camera, tauPixels, cameraSpeed, visibility).
    FrameStats settle(Settle settle, const Camera& camera, double tauPixels, double cameraSpeed = 0.0,
                      const FrameVisibility& visibility = {});

    const LodSelection& selection() const { return mSelection; }
    /// The resident data of a node selected this frame (or any resident node); null if not resident.
    NodePtr node(const NodeId& id) const;
    const NodeCache& cache() const { return mCache; }
    NodeServerStats serverStats() const { return mServer.stats(); }
    /// The node pools' slot of resident node `id` (NodeCache::slotOf), -1 if not resident.
    int slotOf(const NodeId& id) const { return mCache.slotOf(id); }
    /// Called once per group that failed to load, with the error (file and node named).
    void onLoadError(std::function<void(const std::string&)> report) { mReport = std::move(report); }

    /// The tree the selection sees: resident nodes' NodeData.
    const LodTree& tree() const { return mTree; }
    /// Whether the children of `id` are resident, without touching them in the cache.
    bool childrenResident(const NodeId& id) const { return mCache.children(id) != nullptr; }

private:
    /// LodTree over the resident nodes (a node's info is asked for only once it is resident).
    class ResidentTree final : public LodTree {
    public:
        ResidentTree(const TerrainStreamer& streamer, const QuadtreeExtent& extent)
            : mStreamer(streamer), mExtent(extent)
        {
        }
        QuadtreeExtent extent() const override { return mExtent; }
        NodeInfo info(const NodeId& id) const override;

    private:
        const TerrainStreamer& mStreamer;
        QuadtreeExtent mExtent;
    };

    TerrainStreamer(NodeSource& source, const QuadtreeExtent& extent, const StreamerOptions& options);
    /// Takes the finished loads into the cache, counting them into stats (inserted, refused, synthesized).
    void collect(FrameStats& stats);

    StreamerOptions mOptions;
    ResidentTree mTree;
    NodeCache mCache;
    NodeServer mServer;
    LodSelection mSelection;
    std::vector<LoadRequest> mRequests;
    std::function<void(const std::string&)> mReport;
    // Visibility (update with FrameVisibility): by node key, the time a node was last selected hidden; the
    // time nodes still morphing in after a reveal were first drawn; the nodes of the previous selection.
    std::unordered_map<std::uint64_t, double> mHiddenAt;
    std::unordered_map<std::uint64_t, double> mRevealStart;
    std::unordered_set<std::uint64_t> mPrevious;
};

}  // namespace terrain
