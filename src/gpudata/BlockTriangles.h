// The tessellation blocks of a drawn node (lod/TessellationLevels.h) as triangles of the template mesh
// (gpudata/TemplateMesh.h): what render_mode = blocks draws with the chunk vertex program instead of tessellation
// shaders. Every vertex the tessellation evaluation shader makes is a template vertex (a sample of the node, snapped
// onto a lattice of samples, or a skirt vertex below an edge sample), so the same blocks are index lists over the
// shared template. A block at level t is its (B / 2^t)^2 cells of 2^t samples, each split from south-west to
// north-east like the template (BlockErrors covers both diagonals), with the vertices of its sides moved as
// tessellatedVertex moves them; a triangle that the snapping collapses is left out (the tessellator makes it and the
// rasterizer drops it). A drawn block on the node's border hangs one skirt quad per cell along that border, between
// the side's vertices and the skirt ring's vertices below them (3.2.6).
//
// Pure CPU code: no GL. The renderer appends a node's lists each frame and draws them in one call per group.
#pragma once

#include "lod/TessellationLevels.h"

#include <cstdint>
#include <vector>

namespace terrain {

class BlockTriangles {
public:
    /// For nodes of `chunkSize` samples a side cut into blocks of `blockQuads` quads (a power of two >= 2 dividing
    /// chunkSize - 1): every block's triangles for every level and lattice of its sides, made once.
    BlockTriangles(int chunkSize, int blockQuads);

    /// Appends the triangles of the drawn (not culled) blocks of `levels`, three template vertex indices each,
    /// counter-clockwise seen from outside (above for the surface, from outside the node for skirts), block by
    /// block in rows from the south-west, each block's skirts after its surface. Returns the triangles appended.
    /// Precondition: `levels` is for this chunk size and block size.
    std::uint64_t append(const BlockLevels& levels, std::vector<std::uint32_t>& out) const;

    /// The triangles append() gives a block of level t with side lattices `snap` (south, east, north, west), its
    /// skirts not counted. Precondition: t <= snap[side] <= log2(blockQuads).
    std::uint64_t surfaceTriangles(int t, const int snap[4]) const;

private:
    std::size_t patternIndex(int t, const int snap[4]) const;

    int mChunkSize = 0;
    int mBlockQuads = 0;
    int mLevels = 0;  ///< log2(blockQuads)
    /// Per level and side lattices (patternIndex): the block's surface triangles as offsets from the index of the
    /// block's south-west sample, (dj * N + di); mPatternStart[k] .. mPatternStart[k + 1] in mPatterns.
    std::vector<std::uint32_t> mPatterns;
    std::vector<std::size_t> mPatternStart;
};

}  // namespace terrain
