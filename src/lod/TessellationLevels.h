// The tessellation render mode's levels for the blocks of a drawn node (Yusov & Shevtsov,
// seed 000, section 5, with their edge-centre projection replaced by the selector's bound projection).
//
// Each block is tessellated uniformly at its level t (cells of 2^t samples). Where two blocks meet, the
// side takes the coarser of their levels, e = max(t_a, t_b), and the finer block's vertices on that side are
// snapped onto lattice e (snapToLattice), so both blocks put exactly the same vertices on it: no crack, and
// no transition triangles, whose triangulation the GL leaves to the implementation. A snapped vertex falls
// onto its neighbour and the cell between them becomes a degenerate triangle, which the rasterizer drops.
//
// A block's level is the coarsest d whose error lambda(d), projected as eq. 3.3 projects bounds (at
// lodDistance() of the block's square with the node's height range), stays within the budget; a side whose
// snapped band would exceed the block's budget makes the coarser neighbour finer, until none does. So every
// block's drawn surface is within `pixels` of the node's full surface. Blocks outside the view frustum are
// marked culled (the control shader drops them). Pure: the renderer uploads these levels as they are, and
// the error meter evaluates the same surface (tessellatedHeights).
#pragma once

#include "core/Aabb.h"
#include "core/Camera.h"
#include "lod/BlockErrors.h"
#include "lod/NodeData.h"

#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

namespace terrain {

/// Quads per side of a tessellation block (render_mode = tessellation): 8 x 8 blocks of a 65 x 65 node.
inline constexpr int kTessellationBlockQuads = 8;

/// The fields of a block's code (BlockLevels::code), as the control shader reads them: the level t in the bits of
/// kBlockLevelMask, then the four sides' lattices (south, east, north, west) kBlockSnapBits each from bit
/// kBlockSnapShift, then kBlockCulledBit.
inline constexpr int kBlockLevelMask = 3;
inline constexpr int kBlockSnapShift = 2;
inline constexpr int kBlockSnapBits = 2;
inline constexpr int kBlockCulledBit = 1 << (kBlockSnapShift + 4 * kBlockSnapBits);
static_assert(kTessellationBlockQuads <= 1 << kBlockLevelMask, "a block's levels fit the code's level field");

struct BlockLevels {
    int blocksPerSide = 0;
    int blockQuads = 0;
    std::vector<std::uint8_t> level;   ///< per block [by * B + bx]: t
    std::vector<std::uint8_t> snap;    ///< per block and side [(by * B + bx) * 4 + side]: the side's lattice, >= t
    std::vector<std::uint8_t> culled;  ///< per block: 1 outside the view frustum (not drawn)
    int occludedBlocks = 0;            ///< drawn blocks made coarsest because hidden (`occluded`)

    /// The block as the shaders read it: t | south << 2 | east << 4 | north << 6 | west << 8 | culled << 10 (the
    /// fields above).
    std::uint16_t code(int block) const;
    /// Triangles the tessellator makes for the node's surface patches (2 (B / 2^t)^2 a drawn block,
    /// degenerate ones included).
    std::uint64_t surfaceTriangles() const;
    /// Triangles of the skirt patches of the drawn blocks on the node's border (skirtPatchTriangles each).
    std::uint64_t skirtTriangles() const;
    std::uint64_t triangles() const { return surfaceTriangles() + skirtTriangles(); }
};

/// Triangles the tessellator makes for a skirt patch of f columns (outer levels 1, f, 1, f; inner f, 1): the
/// inner level 1 counts as 2 beside an outer level above 1 (GL 4.5, 11.2.2.2), so a ring of 2f + 2 outer and
/// 2f - 4 inner vertices, stitched; f = 1 is a single pair. TessellationGLTest counts what the GL makes.
inline std::uint64_t skirtPatchTriangles(int f)
{
    return f == 1 ? 2 : 4 * static_cast<std::uint64_t>(f) - 2;
}

/// Whether a box lay wholly behind what the previous frame drew (DepthOcclusion::occluded).
using BoxOccluded = std::function<bool(const Aabb&)>;

/// The levels of the blocks of a node whose box is `node` (its square and height range), for `camera` at
/// `pixels` of error (the part of tau the blocks may spend). `errors` are the node's. With `occluded`
/// (visibility_lod), a block whose box up to its own top (TessellationErrors::top) it says was hidden, and
/// none of whose drawn neighbours in the node is visible, takes the coarsest level: none of its levels would
/// have shown. Hidden blocks beside visible ones keep their levels, so the visible blocks, sides and all, are
/// exactly those chosen without `occluded`.
BlockLevels chooseBlockLevels(const TessellationErrors& errors, const Aabb& node, const Camera& camera, double pixels,
                              const BoxOccluded& occluded = {});

/// The levels a selected node is drawn with (its DrawnNode::levels in the frame's draw list, lod/DrawList.h): a
/// `hidden` node's (SelectedNode::hidden) every block at its coarsest, the others' chooseBlockLevels.
BlockLevels drawnBlockLevels(const TessellationErrors& errors, const Aabb& node, const Camera& camera, double pixels,
                             bool hidden, const BoxOccluded& occluded);

/// The heights the tessellation mode draws at node sample coordinates (lx, ly) in [0, N - 1]^2, for the
/// node's blended sample heights `surface` (N x N) and `levels`: under the one and the other diagonal of the
/// tessellator's cells (the implementation picks). Both equal where the cell is a triangle.
std::pair<double, double> tessellatedHeights(std::span<const float> surface, int chunkSize, const BlockLevels& levels,
                                             double lx, double ly);

/// The node's N x N sample heights as the shaders blend them at morph factor `morph` (terrain.vert,
/// terrain.tese): odd samples move towards the mean of their even neighbours along the template
/// triangulation, which is where the parent's surface lies.
std::vector<float> morphedSamples(const NodeData& node, int chunkSize, float morph);

/// A point where a block's switch of levels moves the drawn surface: node sample coordinates and metres.
struct LevelSwitch {
    double lx = 0.0, ly = 0.0;
    double metres = 0.0;
};

/// Where the blocks whose codes differ between `before` and `after` (levels for the same node) move the
/// surface `surface` (N x N blended heights, the current frame's) when drawn with the one and then the
/// other: at the block's samples and quad centres, the larger change of the two diagonals (each compared
/// with itself). Appends to `out`. The pops of the tessellation mode, which does not morph block levels.
void levelSwitches(std::span<const float> surface, int chunkSize, const BlockLevels& before, const BlockLevels& after,
                   std::vector<LevelSwitch>& out);

}  // namespace terrain
