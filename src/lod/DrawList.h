// What a frame of the quadtree draws, decided once: the selected nodes in the selection's (front to back)
// order, each with its data and its parent's (the morph's other end), their node-pool slots, and in the
// tessellation render mode the levels of its blocks (lod/TessellationLevels.h). The renderer draws this
// object as it is; the error meter and tengine-tool's pop count measure the same object, so what is measured
// is what is drawn by construction. Pure: no GL.
#pragma once

#include "core/Camera.h"
#include "lod/LodSelector.h"
#include "lod/NodeData.h"
#include "lod/TessellationLevels.h"

#include <cstdint>
#include <functional>
#include <vector>

namespace terrain {

class TerrainStreamer;

/// One node of a frame's draw list.
struct DrawnNode {
    SelectedNode selected;  ///< the selection's node: its id, morph, camera-relative origin, size, distance
    NodePtr node;           ///< its data, held for the frame
    NodePtr parent;         ///< its parent's (textural and geometric morph, eq. 3.4-3.6); the node itself for the root
    int slot = -1;          ///< the node's slot in the node pools (NodeCache::slotOf)
    int parentSlot = -1;    ///< the parent's slot; the node's own for the root
    BlockLevels levels;     ///< tessellation mode: its blocks' levels as drawn (drawnBlockLevels); else empty
};

/// A frame's draw list (see the file comment).
struct DrawList {
    Camera camera;                     ///< the camera the selection was made for
    double blockPixels = 0.0;          ///< > 0: tessellation mode, the blocks' part of tau
    std::vector<DrawnNode> nodes;      ///< the selection's order: front to back
    std::uint64_t blockTriangles = 0;  ///< tessellation mode: what the tessellator makes of the blocks
    std::size_t blocks = 0;            ///< tessellation mode: blocks drawn (inside the view frustum)
    std::size_t culledBlocks = 0;      ///< tessellation mode: blocks outside the view frustum
    std::size_t occludedBlocks = 0;    ///< tessellation mode: drawn at their coarsest because hidden
    /// The visibility test the blocks' levels were chosen with (the previous frame's depth; visibility_lod);
    /// empty without. Valid until the next frame's list is made.
    BoxOccluded occluded;

    bool tessellated() const { return blockPixels > 0.0; }
};

/// A resident node's slot in the node pools (NodeCache::slotOf), -1 for none.
using NodeSlotLookup = std::function<int(const NodeId&)>;

/// The draw list of `selection` (made for `camera`) from the nodes `resident` gives (every selected node and
/// its parent must be resident) in the quadtree `extent`, their slots from `slotOf` (empty: -1, a list only
/// measured, not drawn). With `blockPixels` > 0 (tessellation mode) every node's blocks get the levels
/// drawnBlockLevels picks for that budget, `occluded` and the node's hidden flag; the nodes must carry
/// tessellation errors.
DrawList makeDrawList(const LodSelection& selection, const ResidentNodeLookup& resident, const QuadtreeExtent& extent,
                      const Camera& camera, double blockPixels = 0.0, BoxOccluded occluded = {},
                      const NodeSlotLookup& slotOf = {});
/// makeDrawList() of the nodes resident in `streamer` and their cache slots.
DrawList makeDrawList(const LodSelection& selection, const TerrainStreamer& streamer, const Camera& camera,
                      double blockPixels = 0.0, BoxOccluded occluded = {});

}  // namespace terrain
