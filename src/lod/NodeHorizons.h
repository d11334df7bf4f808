// Terrain shadows and sky visibility for the quadtree's nodes (light/Horizon.h): the horizons of a node's
// surface at a lattice of its samples, searched over one height grid of the whole map (the static levels'
// heights, as fine as a bounded size allows). Made on the loading threads with the node; the renderer derives
// the sun's and sky's visibility from them for the current sun.
//
// Seamless by construction: a lattice point's horizons depend only on its world position and surface height
// and on the one grid, so neighbours of a level, which share their edge samples, share their edge points'
// horizons; a node also keeps its parent's lattice over its square (latticeQuadrant), which the renderer morphs
// from as it morphs the heights.
//
// What the grid does not hold (relief finer than its spacing) casts no shadow: there the normal maps shade the
// surface. A point below the grid's surface (the synthesized relief in a hollow) looks from the grid's height,
// so a hollow does not shade itself with the coarser surface above it.
#pragma once

#include "core/Expected.h"
#include "light/Horizon.h"
#include "quadtree/MapFile.h"
#include "synthesis/DetailSynthesizer.h"

#include <span>
#include <string>
#include <vector>

namespace terrain {

/// The static map's heights (metres above the map's height offset, without material displacement) on the grid
/// of its finest level with at most `maxSide` samples a side (the root's level at least): world sample (i, j)
/// at (originX + i spacing, originY + j spacing). Nodes without children at that level are sampled bilinearly. A
/// node that cannot be read (damaged) has its parent's samples over its square instead, and its error (naming the
/// map and node) in `unreadable`; an unreadable root is the error.
Expected<HeightGrid> staticHeightGrid(const MapFile& map, int maxSide, std::vector<std::string>* unreadable = nullptr);
/// The level of the map's whose samples staticHeightGrid(map, maxSide) holds.
int staticHeightGridLevel(const MapHeader& header, int maxSide);

/// Lattice points a side for a node of `chunkSize` samples (2^k + 1) `spacing` metres apart over a grid of
/// `gridSpacing`: a point at every sample while the node is no finer than the grid (its shadows as sharp as its
/// geometry), then a point every 2^m samples, the most that keeps the points no further apart than the grid's
/// samples (finer points would only repeat what the grid holds), and never fewer than kMinHorizonLattice (or the
/// chunk's samples).
int horizonLatticeSize(int chunkSize, double spacing, double gridSpacing);
inline constexpr int kMinHorizonLattice = 9;

/// The horizons of the node whose surface window (`window`: (N + 4)^2 heights above the map's offset, rows south
/// to north, NodeData::heights' surface) lies at `where`, at a lattice of `latticeSize` points a side (2^k + 1,
/// dividing the N - 1 cells), over `grid`.
HorizonLattice nodeHorizons(const HeightGrid& grid, const WindowPlacement& where, std::span<const float> window,
                            int chunkSize, int latticeSize, const HorizonOptions& options);

}  // namespace terrain
