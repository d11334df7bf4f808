// The simplification level of every tessellation block edge of a node (issue 13, part 2; Yusov & Shevtsov,
// seed 000, section 5, with their edge-centre projection replaced by the selector's bound projection).
// An edge shared by two blocks gets the coarsest level d (its segments span 2^d samples) at which both
// blocks' errors lambda(d) stay within the pixel budget, each projected at the nearer of the two blocks'
// distances (lodDistance() of the block's square with the node's height range), so both sides compute the
// same level and the tessellated node has no cracks. An edge on the node's border has one block. A block's
// interior takes the finest of its four edges, which is at least as fine as its own error needs. Pure: the
// tessellation control shader computes the same from the same data.
#pragma once

#include "core/Aabb.h"
#include "core/Camera.h"
#include "lod/BlockErrors.h"

#include <cstdint>
#include <vector>

namespace terrain {

struct BlockLevels {
    int blocksPerSide = 0;
    /// Edges between blocks (bx - 1, by) and (bx, by), running north: [by * (B + 1) + bx], bx in [0, B].
    std::vector<std::uint8_t> northEdges;
    /// Edges between blocks (bx, by - 1) and (bx, by), running east: [by * B + bx], by in [0, B].
    std::vector<std::uint8_t> eastEdges;
    /// Per block [by * B + bx]: the finest (smallest) level of its four edges.
    std::vector<std::uint8_t> interior;
};

/// The levels of the blocks of a node whose box is `node` (its square and height range), for `camera` at
/// `pixels` of error (the part of tau the blocks may spend). `errors` are the node's (computeBlockErrors).
BlockLevels chooseBlockLevels(const BlockErrors& errors, const Aabb& node, const Camera& camera, double pixels);

}  // namespace terrain
