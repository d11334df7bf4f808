// The screen-space error the viewer really draws (closed-loop LOD): the vertical distance between
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
#include "lod/DrawList.h"
#include "lod/LodSelector.h"
#include "lod/NodeData.h"
#include "lod/TessellationLevels.h"
#include "quadtree/MapFormat.h"

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
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
    std::size_t nodes = 0;                   ///< selected nodes (drawn), all of them
    std::uint64_t tessellatedTriangles = 0;  ///< tessellation mode: the triangles of the measured blocks' levels
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

/// The fewest chunked nodes that draw a frame within tau, picked with the measured errors instead of bounds:
/// from the root down, a node in view whose own surface (morph 1) is within tau of the reference at every one
/// of its points in view is drawn, any other is replaced by its children in view. No selection of whole
/// nodes that are each within tau has fewer nodes in view (each of its nodes holds one of these or lies
/// inside one), so this is the floor that any bound-driven chunked selection of the frame stands on.
struct OracleSelection {
    std::vector<NodePtr> nodes;    ///< drawn
    std::vector<NodePtr> refined;  ///< their ancestors in view, every one over tau
    double maxPixels = 0.0;        ///< the worst drawn node's own error
    std::size_t overTau = 0;       ///< drawn nodes over tau because the source has nothing finer there
    /// Refined nodes whose own error in pixels at their points' distances was within tau: refinements that
    /// bought nothing (none when the criterion is that error itself, blocks = 0).
    std::size_t refinedWithinTau = 0;
};

/// What a frame drawn with visibility_lod showed, for measuring it (ErrorMeter::measure).
struct MeasuredVisibility {
    /// Points (world metres, on the drawn surface) it says did not show are not measured; empty: all are.
    std::function<bool(const glm::dvec3&)> shows;
};

class ErrorMeter {
public:
    /// `source` makes the reference nodes (the same source the viewer draws from, so a reference node is the
    /// node the viewer would make); it must outlive the meter. `header` is the map's.
    ErrorMeter(const MapHeader& header, NodeSource& source, const ErrorMeterOptions& options);

    /// Measures the frame that `frame` draws (made for its camera; lod/DrawList.h): each node as drawn, morphed
    /// towards its parent by its morph factor, or in tessellation mode (DrawList::tessellated) its blocks at the
    /// levels the list gives, of the node's samples blended by its morph as the shaders blend them; where the
    /// tessellator may split a cell either way, the worse diagonal counts. `resident` gives the nodes above the
    /// drawn ones (the refinements' judged). `tauPixels` > 0 decides the refinements that bought nothing.
    /// Errors: a reference node that cannot be loaded (file and node named). With `visibility`, what is
    /// measured is what the frame showed (see MeasuredVisibility).
    Expected<FrameError> measure(const DrawList& frame, const ResidentNodeLookup& resident, double tauPixels,
                                 const MeasuredVisibility& visibility = {});

    /// The oracle's selection for `camera` at `tauPixels` > 0 (see OracleSelection), from the same reference
    /// as measure(). With `blocks` = 0 a node's error is its largest error in pixels at its points' own
    /// distances. With `blocks` = B >= 1 the node is cut into B x B blocks and its error is the largest over
    /// its blocks of the block's measured vertical error in metres projected as the selection projects a
    /// bound (at lodDistance() of the block's square with the node's height range): what bounds as tight as
    /// the measurement would buy, per node (B = 1) or per block. Errors: a node that cannot be loaded (file
    /// and node named).
    Expected<OracleSelection> oracle(const Camera& camera, double tauPixels, int blocks = 0);

    /// The height (metres above the map's offset) another method draws at world (x, y), or nothing where it
    /// draws nothing: lod_mode = clipmap's surface (ClipmapTerrain::drawnHeight).
    using DrawnSurface = std::function<std::optional<double>(double x, double y)>;
    /// Measures a frame drawn by another method than the quadtree selection (geometry clipmaps)
    /// against the same reference: the reference refined from the root as for measure() (static leaves, then
    /// dynamic nodes until they converge), at every vertex of its leaves in view. Exact where the drawn
    /// triangles nest with the leaves' (clipmap rings use the quadtree's grids), the points in between not
    /// measured otherwise. FrameError's node figures stay 0. Errors: a reference node that cannot be loaded.
    Expected<FrameError> measureSurface(const DrawnSurface& drawn, const Camera& camera,
                                        const MeasuredVisibility& visibility = {});

    /// Reference groups made so far (statistics).
    std::uint64_t groupsMade() const { return mGroupsMade; }

private:
    struct CachedGroup {
        ChildNodes nodes;
        std::uint64_t used = 0;
    };
    struct View;  // the frame's projector and frustum with the map's grid (ErrorMeter.cpp)
    Expected<const ChildNodes*> children(const NodeData& parent);
    void trimCache();
    /// Appends the reference leaves in view below `from` (itself when it has no children in view) to `leaves`.
    Status referenceLeaves(const View& view, const NodePtr& from, int maxDepthBelow, std::vector<NodePtr>& leaves);

    MapHeader mHeader;
    QuadtreeExtent mExtent;
    NodeSource& mSource;
    ErrorMeterOptions mOptions;
    std::unordered_map<std::uint64_t, CachedGroup> mCache;
    std::uint64_t mStamp = 0;
    std::uint64_t mGroupsMade = 0;
    NodePtr mRoot;  ///< for oracle(), loaded once
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
