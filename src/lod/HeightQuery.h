// Height queries against the static quadtree: the surface exactly as the finest static level renders it.
#pragma once

#include "core/Expected.h"
#include "lod/TerrainNodeSource.h"
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

/// Height of the rendered surface (static + synthesized: base + displacement) at world (x, y) metres, at
/// quadtree level `depth` (or the deepest level above it that `source` can make), interpolated along the
/// template triangulation: exactly what the viewer draws when that level is selected with morph factor 1.
/// Nodes come from `source` (its detail policy decides what is synthesized), so the query and the viewer
/// share one code path. Fails outside the input's valid region and when a node cannot be read.
Expected<HeightSample> surfaceHeightAt(const MapFile& map, TerrainNodeSource& source, double x, double y, int depth);

}  // namespace terrain
