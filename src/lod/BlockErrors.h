// Per-block simplification errors of a node, for the tessellation render mode (issue 13; Yusov & Shevtsov,
// seed 000, section 5: the errors lambda^(d) of each tessellation block). A node of N x N samples is cut
// into blocks of B x B quads; drawing a block from every 2^d-th sample (d = 1 .. log2 B) moves its surface
// by at most lambda(d) metres vertically. Pure: no GL.
//
// The tessellator splits each quad it makes along a diagonal the implementation chooses, so lambda covers
// both: the largest distance between the node's own surface (the template triangulation, quads split from
// south-west to north-east) and the coarse block under either split. Both surfaces are linear on the
// pieces of the fine triangles that the coarse diagonals cut out, and those pieces' corners are samples or
// quad centres (a north-west to south-east coarse diagonal crosses the fine diagonals at their midpoints),
// so the maximum over the block's samples and quad centres is exact. Where an edge of a block is
// tessellated finer than its interior, the tessellator's transition triangles are not among these: the
// render mode has to bound those by itself (see docs/design.md, "Tessellation").
#pragma once

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

}  // namespace terrain
