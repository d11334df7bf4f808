// The screen-space error the viewer really draws (issue 12, closed-loop LOD): the vertical distance between
// the drawn surface (every selected node with its morph, eq. 3.4) and a reference surface, projected to
// pixels at each point's own distance and direction, the way Yusov & Shevtsov project their error segments
// (seed 000, section 5). Pure: no GL; nodes come from the streamer (drawn) and a NodeSource (reference).
//
// The reference is the same quadtree refined further below each selected node: static nodes down to the
// static leaves (on a map without detail synthesis, the input data itself), and below them dynamic nodes
// for as long as a further level changes the surface by `convergencePixels` (tau / 8) or more at some sample
// in view. A child whose surface differs from its parent's by less than that everywhere in view is a
// reference leaf. The reference leaves' grids nest in the selected node's (children split every quad into
// four), so both surfaces are piecewise linear on the leaves' triangles, and the largest distance between
// them lies at a leaf's vertex: measuring every vertex of every reference leaf is the exact maximum over the
// drawn node, points between the drawn vertices included (skirts are not measured).
#pragma once

#include "core/Camera.h"
#include "core/Expected.h"
#include "lod/LodSelector.h"
#include "lod/NodeData.h"
#include "quadtree/MapFormat.h"

#include <array>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <vector>

namespace terrain {

struct ErrorMeterOptions {
    /// A dynamic reference node whose surface differs from its parent's by less than this many pixels at
    /// every one of its samples in view ends the refinement there. The caller passes tau / 8. > 0.
    double convergencePixels = 0.25;
    /// Reference child groups kept between frames (least recently used go first): about 4 x 60 KB each.
    std::size_t cachedGroups = 1024;
    /// Deepest reference level below a selected node (a guard; the source's own limits usually stop first).
    int maxDepthBelow = 16;
};

/// One frame's figures. Points are the vertices of the reference leaves inside the view frustum.
struct FrameError {
    double maxPixels = 0.0;
    double p99Pixels = 0.0;
    double meanPixels = 0.0;
    double maxMetres = 0.0;  ///< vertical distance at the worst point
    std::size_t points = 0;
    std::size_t nodes = 0;  ///< selected nodes (drawn), all of them
    /// Refined nodes (ancestors of selected nodes, resident, with a point in view) and those of them whose own
    /// surface, drawn instead of their descendants, would already have been within tau at every point:
    /// refinements that bought nothing.
    std::size_t refined = 0;
    std::size_t refinedWithinTau = 0;
    std::size_t referenceNodes = 0;  ///< reference leaves measured against
    int deepestReference = 0;        ///< level of the deepest reference leaf
    NodeId worstNode;                ///< the selected node holding the worst point
    double worstX = 0.0, worstY = 0.0;
    /// Every point's error in pixels (for the caller's statistics over many frames).
    std::vector<float> pixels;
    /// Per selected node with a point in view: its bound (deltaC) against the largest vertical distance of
    /// its own surface (morph 1) from the reference, in metres. The bound holds where measured <= deltaC.
    struct BoundCheck {
        NodeId id;
        bool isStatic = true;
        float deltaC = 0.0f;
        double measured = 0.0;
    };
    std::vector<BoundCheck> bounds;
};

/// The drawn nodes' data: the streamer's resident nodes (TerrainStreamer::node). Null when not resident.
using ResidentNodeLookup = std::function<NodePtr(const NodeId&)>;

class ErrorMeter {
public:
    /// `source` makes the reference nodes (the same source the viewer draws from, so a reference node is the
    /// node the viewer would make); it must outlive the meter. `header` is the map's.
    ErrorMeter(const MapHeader& header, NodeSource& source, const ErrorMeterOptions& options);

    /// Measures the frame that `selection` (made for `camera`) draws from the nodes `drawn` returns. Every
    /// selected node must be resident, with its parent (for the morph). `tauPixels` > 0 decides the
    /// refinements that bought nothing. Errors: a reference node that cannot be loaded (file and node named).
    Expected<FrameError> measure(const LodSelection& selection, const ResidentNodeLookup& drawn, const Camera& camera,
                                 double tauPixels);

    /// Reference groups made so far (statistics).
    std::uint64_t groupsMade() const { return mGroupsMade; }

private:
    struct CachedGroup {
        ChildNodes nodes;
        std::uint64_t used = 0;
    };
    Expected<const ChildNodes*> children(const NodeData& parent);
    void trimCache();

    MapHeader mHeader;
    QuadtreeExtent mExtent;
    NodeSource& mSource;
    ErrorMeterOptions mOptions;
    std::unordered_map<std::uint64_t, CachedGroup> mCache;
    std::uint64_t mStamp = 0;
    std::uint64_t mGroupsMade = 0;
};

/// Screen length in pixels of vertical segments seen by a camera: the projection of (x, y, z) and
/// (x, y, z + dz), clipped to the near plane. For the error meter and its tests.
class VerticalSegmentProjector {
public:
    explicit VerticalSegmentProjector(const Camera& camera);
    /// Pixels between the projections of (x, y, z) and (x, y, z + dz) (world metres), or -1 when (x, y, z) is
    /// outside the view frustum.
    double pixels(double x, double y, double z, double dz) const;

private:
    glm::dmat4 mMatrix;  ///< projection * viewRotation: camera-relative world -> clip
    glm::dvec3 mEye;
    double mHalfWidth, mHalfHeight, mNear;
};

}  // namespace terrain
