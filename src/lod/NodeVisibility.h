// Per-node visibility from the pixels the renderer counted for the nodes it drew (Özak & Demir, seed 001,
// method 2: a counter per drawn node, incremented by the fragments that pass the depth test), read back
// one or more frames late. It answers the selection's question (NodeHidden): which nodes have shown no
// pixel for the last k measured frames. A node's record sums the nodes drawn at or below it, so a refined
// subtree that is hidden as a whole collapses to its root, whose own count then decides. Pure: no GL.
#pragma once

#include "core/Camera.h"
#include "lod/DepthOcclusion.h"
#include "lod/LodSelector.h"
#include "quadtree/NodeId.h"

#include <cstdint>
#include <functional>
#include <span>
#include <unordered_map>
#include <utility>
#include <vector>

namespace terrain {

class NodeVisibility {
public:
    /// `hiddenFrames` (k >= 1): measured frames without a visible pixel before a node counts as hidden.
    explicit NodeVisibility(int hiddenFrames);

    /// The visible-pixel counts of the nodes drawn in frame `frame` (pixels[i] for drawn[i]); frames come in
    /// increasing order, each once. A node that shows pixels again after being hidden must stay dark twice
    /// as long before it counts as hidden again (up to 8 k frames): coarse geometry that peeks over a
    /// ridge while the refined one does not would otherwise refine and collapse by turns.
    void record(std::uint64_t frame, std::span<const NodeId> drawn, std::span<const std::uint32_t> pixels);

    /// Whether `id` is hidden: it (or a node below it) was drawn in the latest measured frame, and showed
    /// no pixel in each of the last measured frames it needs (k, more after a reveal). A node never drawn,
    /// or not drawn in the latest measured frame (out of view, just made), is not hidden: conservative.
    bool hidden(const NodeId& id) const;

    /// What the counts tell of `id`: hidden (hidden()), visible (drawn in the latest measured frame and showed
    /// pixels within the dark frames it needs to count as hidden), or nothing yet (not drawn in the latest
    /// measured frame, or dark in every frame measured since its record began: new in view, or just split).
    enum class Seen { kHidden, kVisible, kUnknown };
    Seen seen(const NodeId& id) const;

    /// Nodes with a record (statistics; records not drawn for 256 frames are dropped).
    std::size_t records() const { return mRecords.size(); }
    /// The latest frame recorded; 0 before any.
    std::uint64_t latestFrame() const { return mLatest; }

private:
    struct Record {
        std::uint64_t lastFrame = 0;  ///< the latest measured frame it or a node below it was drawn in
        int hiddenStreak = 0;         ///< measured frames in a row without a visible pixel
        int required = 0;             ///< hiddenStreak needed to count as hidden
        bool everVisible = false;     ///< showed a pixel in some measured frame
    };
    int mHiddenFrames;
    std::uint64_t mLatest = 0;
    bool mAny = false;
    std::unordered_map<std::uint64_t, Record> mRecords;
    std::vector<std::pair<std::uint64_t, bool>> mTouched;  ///< per record(): node key, visible (reused)
};

/// The visible pixels of the nodes drawn in one frame (counted by the renderer, visibility_lod), and its depth.
struct PixelCounts {
    std::uint64_t frame = 0;            ///< the renderer's frame number: 1 for the first frame drawn
    std::vector<NodeId> nodes;          ///< the nodes drawn, in drawing order
    std::vector<std::uint32_t> pixels;  ///< per node, its fragments that passed the depth test
    /// The frame's depth buffer after the terrain (DepthOcclusion's input), row 0 at the bottom, and the
    /// camera it was drawn with; empty when nothing was drawn.
    std::vector<float> depth;
    Camera camera;
};

/// Where the frames' visibility comes from: what drew them (TerrainRenderer), frames late so that reading
/// does not wait for the GPU. The viewer session takes what is ready before it selects a frame.
class PixelCountSource {
public:
    virtual ~PixelCountSource() = default;
    /// The counts of the oldest frame not yet taken that is ready, into `out`; false when there is none.
    virtual bool takePixelCounts(PixelCounts& out) = 0;
};

/// Whether the children of a node are resident (without touching them in the cache).
using ChildrenKnown = std::function<bool(const NodeId&)>;

/// Levels of resident children below a node whose boxes the depth test may use in its place.
constexpr int kOcclusionLevels = 2;

/// The selection's question from both measures. Without `occlusion` (the depth of the latest
/// measured frame; null when there is none): a node's own pixel counts (NodeVisibility::hidden). With it, a
/// node is hidden when its counts do not show it visible and its surface, refined as far as it can be, lay
/// behind that depth: its nested box in `tree` (resident nodes' heights) is occluded, or, where
/// `childrenResident` says its children are resident, each child is, down to kOcclusionLevels levels. Counts
/// alone would keep a coarse node hidden whose finer surface shows (a peak cut off below the ridge in front).
/// Boxes grow by `growMetres` (>= 0: how far the viewer moved since that depth; DepthOcclusion::occluded).
/// `visibility`, `occlusion` and `tree` must outlive the result.
NodeHidden hiddenFrom(const NodeVisibility& visibility, const DepthOcclusion* occlusion, const LodTree& tree,
                      ChildrenKnown childrenResident = {}, double growMetres = 0.0);

}  // namespace terrain
