// Per-block simplification errors of a node, for the tessellation render mode (Yusov & Shevtsov,
// seed 000, section 5: the errors lambda^(d) of each tessellation block). A node of N x N samples is cut
// into blocks of B x B quads; drawing a block from every 2^d-th sample (d = 1 .. log2 B) moves its surface
// by at most lambda(d) metres vertically. Pure: no GL.
//
// The tessellator splits each quad it makes along a diagonal the implementation chooses, so lambda covers
// both: the largest distance between the node's own surface (the template triangulation, quads split from
// south-west to north-east) and the coarse block under either split. Both surfaces are linear on the
// pieces of the fine triangles that the coarse diagonals cut out, and those pieces' corners are samples or
// quad centres (a north-west to south-east coarse diagonal crosses the fine diagonals at their midpoints),
// so the maximum over the block's samples and quad centres is exact.
//
// The render mode never asks the tessellator for transitions (their triangulation is left to the
// implementation by the GL specification): a block is tessellated uniformly, and where a neighbour is
// coarser the block's vertices on that side are snapped onto the neighbour's lattice
// (lod/TessellationLevels.h). TessellationErrors adds the exact error of those snapped bands.
#pragma once

#include <glm/vec2.hpp>

#include <span>
#include <vector>

namespace terrain {

struct BlockErrors {
    int blockQuads = 0;         ///< B: quads per block side, a power of two >= 2 dividing N - 1
    int blocksPerSide = 0;      ///< (N - 1) / B
    int levels = 0;             ///< log2(B): the simplifications d = 1 .. levels
    std::vector<float> lambda;  ///< metres, [(by * blocksPerSide + bx) * levels + d - 1]

    /// lambda(d) of block (bx, by), bx east and by north of the node's south-west block; d in [1, levels].
    float at(int bx, int by, int d) const;
};

/// The block errors of a node whose drawn surface is `surface`: N x N heights in metres (N = `chunkSize`),
/// rows south to north, what is drawn (base plus displacement). lambda is made non-decreasing in d: a coarser
/// level is never reported closer than a finer one (at equal cost the finer one is then never worse), which
/// lets the render mode pick the coarsest level within its bound by a monotone search.
BlockErrors computeBlockErrors(std::span<const float> surface, int chunkSize, int blockQuads);

/// Sides of a block, in this order everywhere (levels, snap errors, the shaders' codes).
enum BlockSide { kSouth = 0, kEast = 1, kNorth = 2, kWest = 3 };

/// Where the tessellation mode puts a vertex that lies on a block side snapped to lattice `level`: sample
/// coordinate `c` (along the side, node samples, >= 0) to the nearest multiple of 2^level, halves up. The
/// tessellation evaluation shader computes the same.
inline int snapToLattice(int c, int level)
{
    const int g = 1 << level;
    return (c + g / 2) / g * g;
}

/// Corner (a, b), in cells of 2^t samples (0 .. B / 2^t), of block (bx, by) drawn at level t with its sides
/// vertices snapped to the lattices `snap` (indexed by BlockSide, each >= t): node sample coordinates. Block
/// corners are on every lattice and never move.
inline glm::ivec2 tessellatedVertex(int blockQuads, int bx, int by, int t, int a, int b, const int snap[4])
{
    const int s = 1 << t;
    const int f = blockQuads >> t;
    glm::ivec2 v{bx * blockQuads + a * s, by * blockQuads + b * s};
    const bool alongX = a > 0 && a<f, alongY = b> 0 && b < f;
    if (alongX && b == 0) {
        v.x = snapToLattice(v.x, snap[kSouth]);
    } else if (alongX && b == f) {
        v.x = snapToLattice(v.x, snap[kNorth]);
    } else if (alongY && a == 0) {
        v.y = snapToLattice(v.y, snap[kWest]);
    } else if (alongY && a == f) {
        v.y = snapToLattice(v.y, snap[kEast]);
    }
    return v;
}

/// The largest vertical distance between the surface `surface` (N x N, template triangulation) and the
/// triangle with corners p, q, r (sample coordinates) interpolating the surface's heights there: exact
/// (both are linear on the pieces the triangle's edges cut from the template's triangles, whose corners are
/// samples inside the triangle and the edges' crossings with the template's lines). 0 for a triangle of no
/// area.
double triangleError(std::span<const float> surface, int chunkSize, glm::ivec2 p, glm::ivec2 q, glm::ivec2 r);

/// What the tessellation mode's error bound needs of a node (computed when it becomes resident).
struct TessellationErrors {
    /// lambda of the node's own surface and of its surface at morph 0 (odd samples the mean of their even
    /// neighbours along the template triangulation, as the shaders morph), the larger of the two: the drawn
    /// surface is their blend.
    BlockErrors blocks;
    /// Per block, side and pair of levels t < e: metres between the node's surface (either of the two) and
    /// the block drawn at level t with the side's vertices snapped to lattice e, over the band of cells
    /// along that side, under either diagonal of every cell; the band's corner cells under every snap of the
    /// adjacent sides. [((by * blocksPerSide + bx) * 4 + side) * pairs + e (e - 1) / 2 + t].
    std::vector<float> snap;
    int pairs = 0;  ///< levels (levels + 1) / 2
    /// Per block: metres between the surface and the block at level 0 (every quad) split along the other
    /// diagonal (north-west to south-east), the larger for the two surfaces: the tessellator chooses the
    /// diagonals of its quads, so level 0 is exact only where it happens to choose the template's.
    std::vector<float> flip;
    /// Per block: the highest of its samples (its sides included) on the drawn surface, metres (of `surface`;
    /// TerrainNodeSource adds the map's height offset, so nodes carry them absolute, like their boxes).
    /// Every level of the block, snapped or morphed, lies at or below it (the morph blends towards means of
    /// these samples).
    std::vector<float> top;

    /// Precondition: 0 <= t < e <= blocks.levels.
    float snapError(int bx, int by, int side, int t, int e) const;
};

/// The tessellation errors of a node whose drawn surface (morph 1) is `surface` (N x N heights, metres).
TessellationErrors computeTessellationErrors(std::span<const float> surface, int chunkSize, int blockQuads);

}  // namespace terrain
