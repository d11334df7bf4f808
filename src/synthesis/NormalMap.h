// Per-node normal maps (paper 4.2.4: "a texture with lighting information is created for the node";
// Appendix A, dynamic_texture_size): the unit normals of the surface that the levels below a node
// draw, sampled on a texel grid finer than the node's samples, so the lighting shows detail finer than the
// node's triangles. Made on the worker threads with the node.
//
// The surface below. The texels sample the surface `depth` levels below the node (1 for twice the node's
// resolution, 2 for four times; at most kMaxNormalMapDepth), made by the synthesizer exactly as those levels'
// nodes are made (DetailSynthesizer::synthesizeChild, recursively): below the static leaves the normal map
// is the normals of the very surface that refining will draw, so the shading does not change when the
// children replace the node, only the geometry catches up with it. Above the static leaves the levels below
// are real data the node does not have; there the same step (the data subdivided, plus the materials) is the
// estimate, and the children's own maps take over as they are drawn (morphed like the colours).
//
// Texels. T = dynamic_texture_size; a texture of 2^k + 1 texels has T - 1 cells, one of 2^k has T cells and
// gets one texel more, so that corner texels sit on the node's corners and neighbours share their edge
// texels (as the colour textures do: 3.2.7). A texel on a sample of the surface below takes that sample's
// normal; with fewer texels than samples, the central difference spans the texel (at most kBorder samples
// each way); between samples (more texels than 4x the node's samples), the gradients are interpolated.
#pragma once

#include "synthesis/DetailSynthesizer.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

/// Most levels below a node that its normal map samples (16 syntheses of a child: the cost grows 4x a level).
inline constexpr int kMaxNormalMapDepth = 2;

/// Cells per side of a node's normal map for dynamic_texture_size `textureSize` (2^k or 2^k + 1, >= 2).
int normalMapCells(int textureSize);
/// Texels per side of a node's normal map: normalMapCells + 1.
inline int normalMapTexels(int textureSize)
{
    return normalMapCells(textureSize) + 1;
}
/// Levels below the node that a map of `cells` cells samples: the fewest d <= kMaxNormalMapDepth with
/// 2^d (N - 1) >= cells (N = chunkSize).
int normalMapDepth(int cells, int chunkSize);

/// The surface `depth` levels below a node, over its square and a kBorder-sample border: a window of
/// W = 2^depth (N - 1) + 1 + 2 kBorder samples a side at spacing where.spacing / 2^depth, metres above the
/// map's offset, rows south to north; window sample (kBorder, kBorder) is the node's south-west corner.
/// Every sample is the one the node's descendants at that depth have (their windows' inner samples), made
/// by `synthesizer` from `node` (the node's window, W = N + 4) placed at `where`. Depth 0 is the node's own
/// surface.
std::vector<float> surfaceBelow(const DetailSynthesizer& synthesizer, const DualHeightMap& node,
                                const WindowPlacement& where, int depth);

/// surfaceBelow at `depth` >= 1 from the node's four children (DetailSynthesizer::synthesizeChildren of the
/// node at `where`): the same samples, without synthesizing the children again.
std::vector<float> surfaceBelow(const DetailSynthesizer& synthesizer, const std::array<DualHeightMap, 4>& children,
                                const WindowPlacement& where, int depth);

/// A node's normal map: texels x texels unit normals (x, y) as signed 8-bit normalised integers
/// (GL_RG8_SNORM: round(127 x); z = sqrt(1 - x^2 - y^2)), rows south to north, texel (0, 0) on the node's
/// south-west corner. From the node's window `node` placed at `where` and the synthesizer that makes its
/// levels below (surfaceBelow at normalMapDepth).
std::vector<std::int8_t> makeNormalMap(const DetailSynthesizer& synthesizer, const DualHeightMap& node,
                                       const WindowPlacement& where, int textureSize);

/// makeNormalMap with the node's four children already made (synthesizeChildren; used where the map samples
/// the surface below the node).
std::vector<std::int8_t> makeNormalMap(const DetailSynthesizer& synthesizer, const DualHeightMap& node,
                                       const std::array<DualHeightMap, 4>& children, const WindowPlacement& where,
                                       int textureSize);

/// The normal map of a surface window (W = cells + 1 + 2 kBorder samples a side at `spacing` metres, as
/// surfaceBelow returns) on `texels` x texels texels: the part of makeNormalMap that does not synthesize.
std::vector<std::int8_t> normalMapOf(std::span<const float> window, int cells, double spacing, int texels);

}  // namespace terrain
