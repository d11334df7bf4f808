// Per-frame level-of-detail selection (paper 3.2.4-3.2.15 and 3.4.2, listing 3.7 with the culling of
// listing 3.4 and the morph factor of eq. 3.5). Pure: no GL, no I/O, no allocation once the output
// buffers have grown to the frame's size.
#pragma once

#include "core/Aabb.h"
#include "core/Camera.h"
#include "quadtree/NodeId.h"

#include <cstddef>
#include <functional>
#include <vector>

namespace terrain {

class MapFile;
struct MapHeader;

/// What the selection needs to know about a node without its heights.
struct NodeInfo {
    bool hasChildren = false;  ///< static: four children exist in the map; dynamic: children can be made
    float deltaC = 0.0f;       ///< metres, nested error (eq. 3.1): >= every descendant's deltaC
    double zMin = 0.0;         ///< metres, nested bounding box (3.2.12): contains every descendant's box
    double zMax = 0.0;
};

/// Where the quadtree's square lies in the world.
struct QuadtreeExtent {
    double originX = 0.0;  ///< metres: south-west corner of the root
    double originY = 0.0;
    double rootSize = 1.0;  ///< metres: side of the root node, > 0

    /// Side of a node at `level` (metres).
    double nodeSize(int level) const;
    /// The node's bounding box: its square in x, y and [zMin, zMax] in z.
    Aabb box(const NodeId& id, double zMin, double zMax) const;
};

/// The extent of a map's quadtree: its root's square.
QuadtreeExtent extentOf(const MapHeader& header);

/// The tree being selected from: a map's static nodes (MapLodTree), or the resident static and dynamic
/// nodes the streamer holds (TerrainStreamer::tree).
class LodTree {
public:
    virtual ~LodTree() = default;
    virtual QuadtreeExtent extent() const = 0;
    /// Information on node `id`. Precondition: `id` is the root, or a child of a node whose info has
    /// hasChildren set. Called several times per frame per visited node: keep it cheap.
    virtual NodeInfo info(const NodeId& id) const = 0;
};

/// The static nodes of a map (its directory). Keeps a reference: `map` must outlive this.
class MapLodTree final : public LodTree {
public:
    explicit MapLodTree(const MapFile& map);
    QuadtreeExtent extent() const override;
    NodeInfo info(const NodeId& id) const override;

private:
    const MapFile& mMap;
};

/// Whether all four children of `parent` are resident (ready to draw). Empty function: all resident.
using ChildrenResident = std::function<bool(const NodeId& parent)>;

/// Whether node `id` has shown no pixel for long enough that its hidden terrain need not be refined
/// (visibility_lod; NodeVisibility::hidden). Empty function: nothing is hidden.
using NodeHidden = std::function<bool(const NodeId& id)>;

/// Whether node `id` is held at its own detail this frame although the error test would refine it: it is
/// still morphing in after a reveal (TerrainStreamer, visibility_lod), and refining it now would pop. Unlike a
/// hidden node it still asks for its children, so they are ready when the hold ends. Empty: nothing held.
using NodeHeld = std::function<bool(const NodeId& id)>;

/// One node to draw this frame.
struct SelectedNode {
    NodeId id;
    float morph = 1.0f;        ///< eq. 3.5 morph factor in [0, 1]: 0 looks like the parent, 1 the node's own detail
    double distance = 0.0;     ///< metres from the camera to the node's bounding box
    double lodDistance = 0.0;  ///< the distance the error test and the morph use (lodDistance())
    glm::dvec3 cameraRelativeOrigin{
        0.0};           ///< metres: the node's south-west corner at height 0, minus the camera position
    double size = 0.0;  ///< metres: side of the node's square
    /// Selected as it is because hidden (NodeHidden): nothing of it showed, so the renderer may draw it as
    /// coarsely as it likes (the tessellation mode's coarsest blocks); it still counts its pixels.
    bool hidden = false;
};

/// A node that wants to be refined but whose children are not all resident: load (or synthesize) them.
struct ChildRequest {
    NodeId parent;
    double distance = 0.0;  ///< metres, the parent's distance: the priority, smaller first
};

/// The output of one frame; owned by the caller and reused so a steady state allocates nothing.
struct LodSelection {
    std::vector<SelectedNode> nodes;        ///< in traversal order, see selectNodes()
    std::vector<ChildRequest> requests;     ///< in traversal order (not sorted by distance)
    std::size_t visitedNodes = 0;           ///< nodes that passed culling (statistics)
    std::size_t culledNodes = 0;            ///< nodes rejected by the frustum test (statistics)
    std::size_t hiddenNodes = 0;            ///< nodes the error test would refine, selected as they are: hidden
    std::size_t requestsSkippedHidden = 0;  ///< of those, the ones whose children were not resident
    std::size_t heldNodes = 0;              ///< nodes the error test would refine, selected as they are: held
};

/// `selection` as the renderer draws it with geomorph = false: every node at its own detail (morph 1).
LodSelection unmorphed(LodSelection selection);

/// C of eq. 3.3: S / (2 tau |tan(fov / 2)|) with S = viewport height in pixels. A node is refined when
/// d < deltaC * C. `tauPixels` > 0.
double lodDistanceFactor(const Camera& camera, double tauPixels);

/// K: the most a vertical segment at eye depth z can cover on screen, in units of its length / z times
/// S / (2 tan(fov / 2)) pixels, anywhere in the image. A vertical step moves a point at normalized image
/// position (x', y') by (-x' sin p, cos p - y' sin p) / z (p the camera's pitch), whose length is largest at
/// an image corner: K = max over x' = +-tan(hfov / 2), y' = +-tan(vfov / 2). 1 for a level camera; it
/// grows with the pitch, and looking down it shrinks towards the bottom of the image (unused here).
double verticalErrorFactor(const Camera& camera);

/// The distance eq. 3.3 and eq. 3.5 use (a pixel bound everywhere in the image): the smallest eye
/// depth of `box` (its corners against the view direction, at least the near plane) divided by K =
/// verticalErrorFactor(camera). A vertical error of delta metres anywhere in the box then covers at most
/// delta * S / (2 tan(fov / 2)) / lodDistance pixels, so lodDistance >= delta * C keeps it within tau. The
/// distance to the box instead (the paper's) lets errors at the image's edges reach 1 / cos(angle off
/// axis) times tau: measured up to 1.45 tau with tengine-tool error.
double lodDistance(const Camera& camera, double k, const Aabb& box);

/// Listing 3.7 with culling (listing 3.4): from the root, skip nodes whose bounding box is outside the
/// camera's frustum (Frustum::intersects, conservative); refine a node when d < deltaC * C and it has
/// children (d = lodDistance()); if its children are not all resident, select it and request them.
/// Otherwise select it.
///
/// Guarantees, for a tree with nested boxes and errors:
/// - the selected nodes are disjoint, and they are exactly the nodes of the unculled selection (same
///   rules without culling: a partition of the terrain square) whose boxes pass the frustum test;
/// - order: a depth-first traversal that visits the unculled children of a refined node by
///   non-decreasing distance to their boxes (ties: quadrant order). So nodes under a nearer sibling come before nodes
///   under a farther one; the whole list is NOT sorted by distance;
/// - morph (eq. 3.5): f = clamp(1 - (d - d_m) / (d_mp - d_m), 0, 1) with d_m = deltaC * C and
///   d_mp = deltaC(parent) * C. The root has no coarser level to morph to: f = 1. Where d_mp <= d_m the
///   parent adds no error (deltaM = 0, nothing to morph): f = 1. A node waiting for its children has
///   d < d_m, so f = 1. f is continuous in the camera position for a node that stays selected.
///
/// `out` is cleared first; its vectors keep their capacity.
void selectNodes(const LodTree& tree, const Camera& camera, double tauPixels, const ChildrenResident& resident,
                 LodSelection& out);
/// The same, except that a node the error test would refine but `hidden` says is hidden is selected as it
/// is and requests nothing (counted in hiddenNodes, and requestsSkippedHidden when its children were not
/// resident). The nodes it selects still partition the unculled terrain.
void selectNodes(const LodTree& tree, const Camera& camera, double tauPixels, const ChildrenResident& resident,
                 const NodeHidden& hidden, LodSelection& out);
/// The same, and a node that is not hidden but `held` says is held is selected as it is too (counted in
/// heldNodes), still requesting its children when they are not resident.
void selectNodes(const LodTree& tree, const Camera& camera, double tauPixels, const ChildrenResident& resident,
                 const NodeHidden& hidden, const NodeHeld& held, LodSelection& out);

}  // namespace terrain
