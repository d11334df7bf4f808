// Height queries against the static quadtree: the surface exactly as the finest static level renders it.
#pragma once

#include "core/Expected.h"
#include "quadtree/MapFile.h"

namespace terrain {

/// A height and where it came from.
struct HeightSample {
    double height = 0.0;  ///< metres
    NodeId node;          ///< the finest static node containing the point
};

/// Height of the finest static level at world position (x, y) metres, interpolated along the template
/// triangulation (TemplateTriangulation.h) as it is rendered. Fails outside the input's valid region
/// (padding excluded) and when a node on the way cannot be read.
Expected<HeightSample> staticHeightAt(const MapFile& map, double x, double y);

}  // namespace terrain
