// Fractal (PIFS) coding of static node heights, seed 003 (Erra, Scarano & Guida, section 7; Jacquin's block
// coder): each node's square is cut into 4 x 4 range blocks, each approximated by a domain block of 8 x 8
// samples of the same node shrunk by 2 x 2 averaging, under one of 8 isometries, scaled and offset:
// r = m + s (d - mean d) (the offset as the range's mean, Oien's orthogonal form). The decoder starts from
// the range means and iterates the transforms kPifsIterations times (the seed's "8 iterations converge").
//
// What this engine adds so that a lossy per-node code keeps the quadtree's invariants (docs/map-format.md,
// "Fractal height coding"): the samples a node shares with others are not fractal-coded.
//   - A non-root node's even-even samples are its parent's (as in the residual coding): parent and child
//     agree where both have samples, so the geomorph ends on the parent's surface.
//   - The samples on a node's edges and in its 2-sample border are stored exactly (residuals from the
//     Kobbelt prediction of the parent): they are the values of the level's stored grid there (the edge's
//     input samples, the neighbour's decoded heights in the border), so neighbours agree on every shared
//     sample and normals and dynamic children match across node edges.
// Only the interior of the square is fractal; its error against the input is measured by the builder and
// stored (MapHeader::maxErrorBound, the nodes' delta_c).
#pragma once

#include "core/Expected.h"
#include "quadtree/HeightCodec.h"
#include "quadtree/MapFormat.h"
#include "quadtree/QuantizedGrid.h"

#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

namespace terrain {

/// Range block side in samples (the seed's 4 x 4).
inline constexpr int kPifsRange = 4;
/// Domain block positions step by this many samples in each direction (domains are 2 kPifsRange wide).
/// Step 4 gives 15 x 15 = 225 domains x 8 isometries per 65-sample node; step 2 (841 domains) measured
/// 3% less error for 4x the encoding time on the bundled terrain.
inline constexpr int kPifsDomainStep = 4;
/// Scale s = q / kPifsScaleSteps with |q| <= kPifsMaxScale: |s| <= 15/16 < 1 keeps every transform
/// contractive, so the iteration converges whatever the start.
inline constexpr int kPifsScaleSteps = 16;
inline constexpr int kPifsMaxScale = 15;
/// Parent domains: 4 x 4 blocks of the parent's samples whose origin lies within this many samples of the
/// range's collocated block, (2 reach + 1)^2 of them (self-similarity across the scale step).
inline constexpr int kPifsParentReach = 3;
/// Decoder iterations the encoder writes (the seed found 8 enough; each stream states its own count).
inline constexpr int kPifsIterations = 8;
/// Most iterations a stream may ask for (the reader refuses more: a bad count is corruption, not work).
inline constexpr int kPifsMaxIterations = 64;

/// One range block's transform.
struct PifsTransform {
    std::uint16_t domain = 0;   ///< domain index, row-major over the domain positions
    std::uint8_t isometry = 0;  ///< 0..7: bit 0 mirror u, bit 1 mirror v, bit 2 swap u and v
    std::int8_t scale = 0;      ///< q: s = q / kPifsScaleSteps, |q| <= kPifsMaxScale
    std::uint16_t mean = 0;     ///< m: the range's mean over the samples the transform codes, in codes
    bool operator==(const PifsTransform&) const = default;
};

/// Whether window sample (x, y) of node `id` is fractal-coded: strictly inside the node's square and, below
/// the root, not an even-even sample (those are the parent's).
bool pifsCodes(const NodeId& id, int chunkSize, int x, int y);

/// Fits the transforms of a node's range blocks (row-major, ((N - 1) / 4)^2 of them) to `window`: the
/// node's W x W window with the fixed samples as the decoder will have them (parent's even-even samples,
/// edges) and the target heights at the coded ones. Precondition: chunkSize >= 5.
std::vector<PifsTransform> fitPifs(const NodeId& id, int chunkSize, std::span<const std::uint16_t> window,
                                   std::span<const std::uint16_t> parent);

/// The decoder's iterations: sets the coded samples of `window` (W x W, fixed samples already in place) to
/// the range means, then applies `transforms` `iterations` times (each pass reads the previous one's image).
/// Integer arithmetic only: every reader gets the same codes.
void iteratePifs(const NodeId& id, int chunkSize, std::span<const PifsTransform> transforms, int iterations,
                 std::span<const std::uint16_t> parent, std::span<std::uint16_t> window);

/// A node's height stream: u32 raw size, then zlib of: u8 iterations, per range block varint(domain * 8 +
/// isometry), u8 (scale + kPifsMaxScale), zigzag varint of the mean minus the previous block's; then, for
/// every sample inside the terrain that is neither coded nor the parent's, in raster order, the zigzag varint
/// of its code minus the Kobbelt prediction from the parent (root: minus the previous such sample).
/// `stored` is the node's window as it must decode (the pyramid's), `parent` the parent's (empty for the root).
std::vector<std::uint8_t> encodePifsHeights(const NodeWindow& geometry, const NodeId& id,
                                            std::span<const std::uint16_t> stored,
                                            std::span<const std::uint16_t> parent,
                                            std::span<const PifsTransform> transforms, int iterations,
                                            int zlibLevel = 4);

/// Decodes a stream of encodePifsHeights into `window` (outside samples filled by reflection). Errors say
/// what was wrong; callers prefix the file and node.
Status decodePifsHeights(const NodeWindow& geometry, const NodeId& id, std::span<const std::uint8_t> stream,
                         std::span<const std::uint16_t> parent, std::span<std::uint16_t> window);

/// The stored heights of every static node of a map coded with PIFS, built top-down in memory by prep: per
/// level k the grid G_k of what the nodes store (even-even samples G_{k-1}'s, the other samples on node edges
/// the input's, node interiors their fractal decoding), each node's stream and its error against the input.
class PifsPyramid {
public:
    /// Codes the nodes `nodesAt(level)` lists, level by level, from the quantized input `grid`, on `threads`
    /// threads (the result does not depend on their number).
    template <class NodesAt>
    static PifsPyramid build(const MapHeader& header, const QuantizedGrid& grid, NodesAt&& nodesAt, int threads,
                             int zlibLevel)
    {
        PifsPyramid pyramid(header);
        for (int level = 0; level < static_cast<int>(header.levels); ++level) {
            pyramid.buildLevel(level, grid, nodesAt(level), threads, zlibLevel);
        }
        return pyramid;
    }

    /// The window node `id` stores (outside samples filled by reflection).
    void extractWindow(const NodeId& id, std::span<std::uint16_t> window) const;
    /// The stored code at level-`level` grid sample (x, y).
    std::uint16_t at(int level, std::uint64_t x, std::uint64_t y) const
    {
        return mLevels[static_cast<std::size_t>(level)][y * mLevelSize[static_cast<std::size_t>(level)] + x];
    }
    /// Node `id`'s height stream (a node the build coded).
    const std::vector<std::uint8_t>& stream(const NodeId& id) const { return mNodes.at(id.key()).stream; }
    /// The largest |stored - input| over node `id`'s window inside the terrain, in codes.
    std::uint32_t errorCodes(const NodeId& id) const { return mNodes.at(id.key()).errorCodes; }
    /// The largest errorCodes over all nodes.
    std::uint32_t maxErrorCodes() const { return mMaxError; }

private:
    struct Node {
        std::vector<std::uint8_t> stream;
        std::uint32_t errorCodes = 0;
    };
    explicit PifsPyramid(const MapHeader& header);
    void buildLevel(int level, const QuantizedGrid& grid, const std::vector<NodeId>& nodes, int threads, int zlibLevel);

    MapHeader mHeader;  ///< by value: NodeWindow keeps a pointer to it, so windows are made per call
    std::vector<std::vector<std::uint16_t>> mLevels;  ///< G_k, row-major, rows south to north
    std::vector<std::uint64_t> mLevelSize;
    std::unordered_map<std::uint64_t, Node> mNodes;
    std::uint32_t mMaxError = 0;
};

}  // namespace terrain
