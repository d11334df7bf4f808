// A frame's draw list: the selection with its nodes' data, pool slots and tessellation block levels.
#include "lod/DrawList.h"

#include "core/Check.h"
#include "lod/TerrainStreamer.h"

#include <utility>

namespace terrain {

DrawList makeDrawList(const LodSelection& selection, const ResidentNodeLookup& resident, const QuadtreeExtent& extent,
                      const Camera& camera, double blockPixels, BoxOccluded occluded, const NodeSlotLookup& slotOf)
{
    DrawList list;
    list.camera = camera;
    list.blockPixels = blockPixels;
    list.occluded = std::move(occluded);
    list.nodes.reserve(selection.nodes.size());
    auto slot = [&slotOf](const NodeId& id) { return slotOf ? slotOf(id) : -1; };
    for (const SelectedNode& selected : selection.nodes) {
        DrawnNode drawn;
        drawn.selected = selected;
        drawn.node = resident(selected.id);
        TERRAIN_EXPECTS(drawn.node != nullptr, "every selected node must be resident");
        drawn.slot = slot(selected.id);
        if (selected.id.isRoot()) {
            drawn.parent = drawn.node;
            drawn.parentSlot = drawn.slot;
        } else {
            drawn.parent = resident(selected.id.parent());
            TERRAIN_EXPECTS(drawn.parent != nullptr, "a selected node's parent must be resident");
            drawn.parentSlot = slot(selected.id.parent());
        }
        if (list.tessellated()) {
            const NodeData& node = *drawn.node;
            TERRAIN_EXPECTS(node.tessellation != nullptr,
                            "tessellation mode needs nodes made with their tessellation errors "
                            "(DetailPolicy::tessellationBlockQuads)");
            // Hidden nodes' blocks all at their coarsest; in the others, hidden blocks away from visible ones.
            drawn.levels = drawnBlockLevels(*node.tessellation, extent.box(selected.id, node.zMin, node.zMax), camera,
                                            blockPixels, selected.hidden, list.occluded);
            list.occludedBlocks += static_cast<std::size_t>(drawn.levels.occludedBlocks);
            for (std::uint8_t culled : drawn.levels.culled) {
                (culled == 0 ? list.blocks : list.culledBlocks) += 1;
            }
            list.blockTriangles += drawn.levels.triangles();
        }
        list.nodes.push_back(std::move(drawn));
    }
    return list;
}

DrawList makeDrawList(const LodSelection& selection, const TerrainStreamer& streamer, const Camera& camera,
                      double blockPixels, BoxOccluded occluded)
{
    return makeDrawList(
        selection, [&streamer](const NodeId& id) { return streamer.node(id); }, streamer.tree().extent(), camera,
        blockPixels, std::move(occluded), [&streamer](const NodeId& id) { return streamer.slotOf(id); });
}

}  // namespace terrain
